//! JSON for report files that must be reproducible: a value written as
//! `serde_json` writes it (pretty with two-space indents, or compact), but
//! without the object members named in a list — the wall-clock times
//! (`wall_ms`) a result keeps in memory for the terminal and the TUI, which
//! no two runs share. A re-run of a shard (or of a whole job) then writes
//! the same bytes; the time is printed on the terminal instead.
//!
//! Done as a `serde_json` [`Formatter`] (not through `serde_json::Value`,
//! which would sort the members by name): every member's key is collected
//! first, and a member whose key is on the list is dropped with its whole
//! value, however nested. Everything else is byte for byte what
//! `serde_json::to_vec_pretty` / `to_vec` gives (tested below).

use serde::Serialize;
use serde_json::ser::{CharEscape, CompactFormatter, Formatter};
use std::io::{self, Write};

/// The members no reproducible report file holds: wall-clock times.
pub const NOT_REPRODUCIBLE: &[&str] = &["wall_ms"];

/// `value` as pretty JSON (as `serde_json::to_vec_pretty`) without the
/// members named in `skip`.
pub fn to_vec_pretty_without<T: Serialize + ?Sized>(
    value: &T,
    skip: &[&str],
) -> serde_json::Result<Vec<u8>> {
    write(value, skip, true)
}

/// `value` as compact JSON (as `serde_json::to_vec`) without the members
/// named in `skip`.
pub fn to_vec_without<T: Serialize + ?Sized>(
    value: &T,
    skip: &[&str],
) -> serde_json::Result<Vec<u8>> {
    write(value, skip, false)
}

fn write<T: Serialize + ?Sized>(
    value: &T,
    skip: &[&str],
    pretty: bool,
) -> serde_json::Result<Vec<u8>> {
    let mut out = Vec::with_capacity(256);
    let f = Skipping {
        skip: skip
            .iter()
            .map(|k| format!("\"{k}\"").into_bytes())
            .collect(),
        pretty,
        wrote: Vec::new(),
        key: None,
        skipping: None,
    };
    let mut ser = serde_json::Serializer::with_formatter(&mut out, f);
    value.serialize(&mut ser)?;
    Ok(out)
}

/// The formatter: two-space pretty printing or compact, dropping members.
struct Skipping {
    /// The keys to drop, as written (quoted).
    skip: Vec<Vec<u8>>,
    pretty: bool,
    /// Per open object or array: whether an element was written.
    wrote: Vec<bool>,
    /// The key being written (between `begin_object_key` and
    /// `end_object_key`), collected before it is known whether it stays.
    key: Option<Vec<u8>>,
    /// Inside a dropped member's value: how deep in it.
    skipping: Option<usize>,
}

impl Skipping {
    fn newline<W: ?Sized + Write>(&self, w: &mut W) -> io::Result<()> {
        if self.pretty {
            w.write_all(b"\n")?;
            for _ in 0..self.wrote.len() {
                w.write_all(b"  ")?;
            }
        }
        Ok(())
    }

    fn open<W: ?Sized + Write>(&mut self, w: &mut W, bracket: &[u8]) -> io::Result<()> {
        if let Some(d) = &mut self.skipping {
            *d += 1;
            return Ok(());
        }
        self.wrote.push(false);
        w.write_all(bracket)
    }

    fn close<W: ?Sized + Write>(&mut self, w: &mut W, bracket: &[u8]) -> io::Result<()> {
        if let Some(d) = &mut self.skipping {
            *d -= 1;
            return Ok(());
        }
        if self.wrote.pop().unwrap_or(false) {
            self.newline(w)?;
        }
        w.write_all(bracket)
    }

    /// Where a scalar goes: nowhere (dropped), the key being collected, or
    /// the output.
    fn put<W: ?Sized + Write>(
        &mut self,
        w: &mut W,
        f: impl FnOnce(&mut dyn Write) -> io::Result<()>,
    ) -> io::Result<()> {
        if self.skipping.is_some() {
            Ok(())
        } else if let Some(k) = &mut self.key {
            f(k)
        } else {
            f(&mut Fwd(w))
        }
    }
}

/// A writer of unknown size as a `dyn Write`.
struct Fwd<'a, W: ?Sized>(&'a mut W);

impl<W: ?Sized + Write> Write for Fwd<'_, W> {
    fn write(&mut self, buf: &[u8]) -> io::Result<usize> {
        self.0.write(buf)
    }
    fn write_all(&mut self, buf: &[u8]) -> io::Result<()> {
        self.0.write_all(buf)
    }
    fn flush(&mut self) -> io::Result<()> {
        self.0.flush()
    }
}

macro_rules! scalar {
    ($($name:ident: $t:ty),* $(,)?) => {$(
        fn $name<W: ?Sized + Write>(&mut self, w: &mut W, v: $t) -> io::Result<()> {
            self.put(w, |w| CompactFormatter.$name(w, v))
        }
    )*};
}

impl Formatter for Skipping {
    scalar!(
        write_bool: bool, write_i8: i8, write_i16: i16, write_i32: i32, write_i64: i64,
        write_i128: i128, write_u8: u8, write_u16: u16, write_u32: u32, write_u64: u64,
        write_u128: u128, write_f32: f32, write_f64: f64, write_number_str: &str,
        write_string_fragment: &str, write_char_escape: CharEscape,
        write_byte_array: &[u8], write_raw_fragment: &str,
    );

    fn write_null<W: ?Sized + Write>(&mut self, w: &mut W) -> io::Result<()> {
        self.put(w, |w| CompactFormatter.write_null(w))
    }

    fn begin_string<W: ?Sized + Write>(&mut self, w: &mut W) -> io::Result<()> {
        self.put(w, |w| CompactFormatter.begin_string(w))
    }

    fn end_string<W: ?Sized + Write>(&mut self, w: &mut W) -> io::Result<()> {
        self.put(w, |w| CompactFormatter.end_string(w))
    }

    fn begin_array<W: ?Sized + Write>(&mut self, w: &mut W) -> io::Result<()> {
        self.open(w, b"[")
    }

    fn end_array<W: ?Sized + Write>(&mut self, w: &mut W) -> io::Result<()> {
        self.close(w, b"]")
    }

    fn begin_array_value<W: ?Sized + Write>(&mut self, w: &mut W, _first: bool) -> io::Result<()> {
        if self.skipping.is_some() {
            return Ok(());
        }
        if let Some(last) = self.wrote.last_mut()
            && std::mem::replace(last, true)
        {
            w.write_all(b",")?;
        }
        self.newline(w)
    }

    fn end_array_value<W: ?Sized + Write>(&mut self, _w: &mut W) -> io::Result<()> {
        Ok(())
    }

    fn begin_object<W: ?Sized + Write>(&mut self, w: &mut W) -> io::Result<()> {
        self.open(w, b"{")
    }

    fn end_object<W: ?Sized + Write>(&mut self, w: &mut W) -> io::Result<()> {
        self.close(w, b"}")
    }

    fn begin_object_key<W: ?Sized + Write>(&mut self, _w: &mut W, _first: bool) -> io::Result<()> {
        if self.skipping.is_none() {
            self.key = Some(Vec::new());
        }
        Ok(())
    }

    fn end_object_key<W: ?Sized + Write>(&mut self, w: &mut W) -> io::Result<()> {
        let Some(key) = self.key.take() else {
            return Ok(());
        };
        if self.skip.contains(&key) {
            self.skipping = Some(0);
            return Ok(());
        }
        if let Some(last) = self.wrote.last_mut()
            && std::mem::replace(last, true)
        {
            w.write_all(b",")?;
        }
        self.newline(w)?;
        w.write_all(&key)
    }

    fn begin_object_value<W: ?Sized + Write>(&mut self, w: &mut W) -> io::Result<()> {
        match (self.skipping, self.pretty) {
            (Some(_), _) => Ok(()),
            (None, true) => w.write_all(b": "),
            (None, false) => w.write_all(b":"),
        }
    }

    fn end_object_value<W: ?Sized + Write>(&mut self, _w: &mut W) -> io::Result<()> {
        if self.skipping == Some(0) {
            self.skipping = None;
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use serde_json::json;
    use std::collections::BTreeMap;

    #[derive(Serialize)]
    struct Case {
        name: &'static str,
        wall_ms: f64,
        nested: Vec<Inner>,
        map: BTreeMap<u32, Option<f64>>,
        empty: Vec<u8>,
        only: Only,
        last: Inner,
    }
    #[derive(Serialize)]
    struct Inner {
        x: f64,
        text: String,
        wall_ms: Option<Vec<f64>>,
    }
    #[derive(Serialize)]
    struct Only {
        wall_ms: f64,
    }

    fn case() -> Case {
        let inner = |x: f64, w: Option<Vec<f64>>| Inner {
            x,
            text: "a \"wall_ms\": 1,\n\u{1}é".into(),
            wall_ms: w,
        };
        Case {
            name: "n",
            wall_ms: 12.5,
            nested: vec![inner(0.1, None), inner(1e-300, Some(vec![1.0, 2.0]))],
            map: [(3, Some(f64::NAN)), (7, Some(0.30000000000000004))].into(),
            empty: vec![],
            only: Only { wall_ms: 1.0 },
            last: inner(-0.0, Some(vec![])),
        }
    }

    /// The reference: serde_json's own output with the members removed by
    /// hand from the same value (`Value` sorts keys, so compare parsed).
    fn reference() -> serde_json::Value {
        let mut v = serde_json::to_value(case()).unwrap();
        v.as_object_mut().unwrap().remove("wall_ms");
        for i in v["nested"].as_array_mut().unwrap() {
            i.as_object_mut().unwrap().remove("wall_ms");
        }
        v["last"].as_object_mut().unwrap().remove("wall_ms");
        v["only"] = json!({});
        v
    }

    #[test]
    fn the_members_are_dropped_and_the_rest_is_serde_jsons() {
        for pretty in [true, false] {
            let bytes = write(&case(), NOT_REPRODUCIBLE, pretty).unwrap();
            let back: serde_json::Value = serde_json::from_slice(&bytes).unwrap();
            assert_eq!(back, reference(), "pretty {pretty}");
            let text = String::from_utf8(bytes).unwrap();
            // The string that looks like the key stays.
            assert!(text.contains(r#"a \"wall_ms\": 1,\n\u0001é"#), "{text}");
            assert_eq!(text.matches("wall_ms").count(), 3, "{text}");
        }
    }

    #[test]
    fn without_members_to_drop_it_is_serde_jsons_output_byte_for_byte() {
        let c = case();
        assert_eq!(
            write(&c, &[], true).unwrap(),
            serde_json::to_vec_pretty(&c).unwrap()
        );
        assert_eq!(
            write(&c, &[], false).unwrap(),
            serde_json::to_vec(&c).unwrap()
        );
        // And dropping: the layout of what stays is serde_json's.
        let v = reference();
        let pretty = to_vec_pretty_without(&case(), NOT_REPRODUCIBLE).unwrap();
        let parsed: serde_json::Value = serde_json::from_slice(&pretty).unwrap();
        assert_eq!(parsed, v);
        let text = String::from_utf8(pretty).unwrap();
        assert!(
            text.starts_with("{\n  \"name\": \"n\",\n  \"nested\": [\n    {\n      \"x\": 0.1,"),
            "{text}"
        );
        assert!(
            text.contains("\"empty\": [],\n  \"only\": {},\n  \"last\": {"),
            "{text}"
        );
    }
}
