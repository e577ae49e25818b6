//! A parameter's value as a user writes it (`--set key=value`, a TOML
//! file) and as pinsight shows it back: the text parser of `--set`, the
//! typed value in user units, and its display (never a 300-digit number).

use crate::fmt::plain;
use serde::{Deserialize, Serialize};
use std::fmt;

/// Parses the text of a `--set` value: TOML value syntax, or a bare word as a string.
pub fn parse_value_text(text: &str) -> toml::Value {
    // TOML reads 0x10 as 16, 0o10 as 8 and 0b10 as 2: a parameter typed on
    // the command line means a decimal number, so those stay text (and are
    // refused with the key's range).
    let digits = text.trim().trim_start_matches(['+', '-']);
    if ["0x", "0o", "0b", "0X", "0O", "0B"]
        .iter()
        .any(|p| digits.starts_with(p))
    {
        return toml::Value::String(text.to_string());
    }
    let doc = format!("v = {text}");
    match doc.parse::<toml::Table>() {
        Ok(mut t) => t
            .remove("v")
            .unwrap_or_else(|| toml::Value::String(text.to_string())),
        Err(_) => toml::Value::String(text.to_string()),
    }
}

pub(crate) fn pairs(value: &toml::Value) -> Option<Vec<(f64, f64)>> {
    let num = |v: &toml::Value| match v {
        toml::Value::Float(f) => Some(*f),
        toml::Value::Integer(i) => Some(*i as f64),
        _ => None,
    };
    match value {
        toml::Value::Array(rows) => rows
            .iter()
            .map(|row| match row {
                toml::Value::Array(p) if p.len() == 2 => Some((num(&p[0])?, num(&p[1])?)),
                _ => None,
            })
            .collect(),
        _ => None,
    }
}

/// A parameter value in user units.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(untagged)]
pub enum ParamValue {
    Number(f64),
    Text(String),
    Pairs(Vec<(f64, f64)>),
    Vector(Vec<f64>),
}

impl ParamValue {
    pub fn to_toml(&self) -> toml::Value {
        match self {
            ParamValue::Number(x) => toml::Value::Float(*x),
            ParamValue::Text(s) => toml::Value::String(s.clone()),
            ParamValue::Pairs(p) => toml::Value::Array(
                p.iter()
                    .map(|(a, b)| {
                        toml::Value::Array(vec![toml::Value::Float(*a), toml::Value::Float(*b)])
                    })
                    .collect(),
            ),
            ParamValue::Vector(v) => {
                toml::Value::Array(v.iter().map(|x| toml::Value::Float(*x)).collect())
            }
        }
    }
}

impl fmt::Display for ParamValue {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            ParamValue::Number(x) => write!(f, "{}", plain(*x)),
            ParamValue::Text(s) => write!(f, "{s}"),
            ParamValue::Pairs(p) => {
                let items: Vec<String> = p
                    .iter()
                    .map(|(a, b)| format!("[{}, {}]", plain(*a), plain(*b)))
                    .collect();
                write!(f, "[{}]", items.join(", "))
            }
            ParamValue::Vector(v) => {
                let items: Vec<String> = v.iter().map(|a| plain(*a)).collect();
                write!(f, "[{}]", items.join(", "))
            }
        }
    }
}
