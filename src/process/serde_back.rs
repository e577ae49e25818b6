//! Reading a monitor run back from its JSON (a shard's partial, merged by
//! `pinsight merge`): the names the run holds as `&'static str` (object
//! kinds, quantities, units, chart kinds) are interned once each, and a
//! number written as `null` because it was not a number (NaN: a spread of
//! one value, an amount that could not be measured) reads back as NaN, so
//! the run written again is the same text.

use serde::{Deserialize, Deserializer};
use std::collections::{BTreeMap, BTreeSet};
use std::sync::Mutex;

/// A name held as `&'static str` (the alias keeps serde's derive from
/// taking the field for a borrow of the input, which would tie every
/// containing type to `'static` input).
pub type Name = &'static str;

/// The names read so far (each leaked once: a run has a few dozen).
static NAMES: Mutex<BTreeSet<&'static str>> = Mutex::new(BTreeSet::new());

/// A `&'static str` field.
pub fn name<'de, D: Deserializer<'de>>(d: D) -> Result<&'static str, D::Error> {
    let s = String::deserialize(d)?;
    let mut names = NAMES.lock().unwrap_or_else(|p| p.into_inner());
    if let Some(n) = names.get(s.as_str()) {
        return Ok(n);
    }
    let n: &'static str = Box::leak(s.into_boxed_str());
    names.insert(n);
    Ok(n)
}

/// An `f64` field that may have been NaN (written as `null`).
pub fn f64_nan<'de, D: Deserializer<'de>>(d: D) -> Result<f64, D::Error> {
    Ok(Option::<f64>::deserialize(d)?.unwrap_or(f64::NAN))
}

/// A `Vec<f64>` whose entries may have been NaN.
pub fn vec_nan<'de, D: Deserializer<'de>>(d: D) -> Result<Vec<f64>, D::Error> {
    Ok(Vec::<Option<f64>>::deserialize(d)?
        .into_iter()
        .map(|v| v.unwrap_or(f64::NAN))
        .collect())
}

/// A map of `f64` whose values may have been NaN.
pub fn map_nan<'de, D: Deserializer<'de>>(d: D) -> Result<BTreeMap<String, f64>, D::Error> {
    Ok(BTreeMap::<String, Option<f64>>::deserialize(d)?
        .into_iter()
        .map(|(k, v)| (k, v.unwrap_or(f64::NAN)))
        .collect())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[derive(Deserialize)]
    struct T {
        #[serde(deserialize_with = "name")]
        kind: &'static str,
        #[serde(deserialize_with = "f64_nan")]
        x: f64,
        #[serde(deserialize_with = "vec_nan")]
        v: Vec<f64>,
    }

    #[test]
    fn names_interned_and_nan_back() {
        let a: T = serde_json::from_str(r#"{"kind":"window","x":null,"v":[1.5,null]}"#).unwrap();
        let b: T = serde_json::from_str(r#"{"kind":"window","x":2.0,"v":[]}"#).unwrap();
        assert!(std::ptr::eq(a.kind, b.kind), "one copy of each name");
        assert!(a.x.is_nan() && b.x == 2.0);
        assert_eq!(a.v[0], 1.5);
        assert!(a.v[1].is_nan());
    }
}
