//! Field paths into a binary (protobuf or ROS 2) message: how a channel map
//! names the value it wants.
//!
//! `force_n`, `wrench.force.z` (nested messages, separated by dots),
//! `data[3]` (element 3 of a repeated field) and `position[name=crank]`
//! (the element of `position` at the index where the sibling array `name`
//! holds `crank`, the way `sensor_msgs/JointState` pairs its arrays). A path
//! that ends on a repeated number field without an element is a block of
//! samples (see [`super::Extracted::Block`]). Indexes and lookups are only
//! allowed on the last field.

/// Which element of the last field a path takes.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Select {
    /// The field itself (a scalar, or a whole repeated field = a block).
    Whole,
    /// Element `i` of a repeated field.
    Index(usize),
    /// The element at the position where the sibling field `keys` equals `key`.
    Lookup { keys: String, key: String },
}

/// A parsed field path.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct FieldPath {
    /// Field names from the message root to the field.
    pub fields: Vec<String>,
    pub select: Select,
}

impl FieldPath {
    /// Parses `a.b.c`, `a.b[3]`, `a[name=crank]`.
    pub fn parse(text: &str) -> Result<Self, String> {
        let text = text.trim();
        let (head, select) = match text.find('[') {
            None => (text, Select::Whole),
            Some(open) => {
                let inner = text[open + 1..].strip_suffix(']').ok_or_else(|| {
                    format!("field path '{text}': an index `[...]` must close the path")
                })?;
                let select = if let Some((k, v)) = inner.split_once('=') {
                    let (k, v) = (k.trim(), v.trim().trim_matches('"'));
                    if !is_name(k) || v.is_empty() {
                        return Err(format!(
                            "field path '{text}': a lookup is `[field=value]`, e.g. `position[name=crank]`"
                        ));
                    }
                    Select::Lookup {
                        keys: k.to_string(),
                        key: v.to_string(),
                    }
                } else {
                    Select::Index(inner.trim().parse().map_err(|_| {
                        format!("field path '{text}': `[{inner}]` is not an element number or `[field=value]`")
                    })?)
                };
                (&text[..open], select)
            }
        };
        let fields: Vec<String> = head.split('.').map(|s| s.trim().to_string()).collect();
        if fields.iter().any(|f| !is_name(f)) {
            return Err(format!(
                "field path '{text}': expected field names separated by dots (e.g. `wrench.force.z`)"
            ));
        }
        Ok(FieldPath { fields, select })
    }
}

fn is_name(s: &str) -> bool {
    !s.is_empty() && s.chars().all(|c| c.is_ascii_alphanumeric() || c == '_')
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parses_the_forms_and_refuses_the_rest() {
        let p = FieldPath::parse("wrench.force.z").unwrap();
        assert_eq!(p.fields, ["wrench", "force", "z"]);
        assert_eq!(p.select, Select::Whole);
        assert_eq!(
            FieldPath::parse("data[3]").unwrap().select,
            Select::Index(3)
        );
        assert_eq!(
            FieldPath::parse("position[name=crank]").unwrap().select,
            Select::Lookup {
                keys: "name".into(),
                key: "crank".into()
            }
        );
        for bad in ["", "a..b", "a[", "a[x]", "a[1]b", "a[=x]", "a b"] {
            assert!(FieldPath::parse(bad).is_err(), "{bad}");
        }
    }
}
