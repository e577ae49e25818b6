//! What is wrong with a parameter, said so a user can fix it: the key, the
//! value as they wrote it (readably), the allowed range, the nearest known
//! key for a misspelt one.

use super::param_table::PARAM_SPECS;
use std::path::Path;

/// Errors in parameters: each names the key and the allowed range.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ParamError {
    #[error("unknown parameter `{key}`{}", suggestion.as_ref().map(|s| format!(" (did you mean `{s}`?)")).unwrap_or_default())]
    UnknownKey {
        key: String,
        suggestion: Option<String>,
    },
    #[error("invalid value for `{key}`: {value} (allowed: {allowed})")]
    Invalid {
        key: String,
        value: String,
        allowed: String,
    },
    #[error("inconsistent parameters ({keys}): {msg}")]
    Relation { keys: String, msg: String },
    #[error("`{text}` is not of the form key=value")]
    Syntax { text: String },
    #[error("parameter file {file}: {msg}")]
    File { file: String, msg: String },
    #[error("parameter file {file}: {inner}")]
    InFile {
        file: String,
        inner: Box<ParamError>,
    },
}

impl ParamError {
    pub(crate) fn unknown(key: &str) -> Self {
        let suggestion = PARAM_SPECS
            .iter()
            .map(|s| (edit_distance(key, s.key), s.key))
            .filter(|(d, _)| *d <= 3)
            .min()
            .map(|(_, k)| k.to_string())
            .or_else(|| {
                // A key without its unit suffix (`clearance` for `clearance_mm`).
                PARAM_SPECS
                    .iter()
                    .find(|s| s.key.starts_with(key) && key.len() >= 2)
                    .map(|s| s.key.to_string())
            });
        ParamError::UnknownKey {
            key: key.to_string(),
            suggestion,
        }
    }

    pub(crate) fn in_file(self, path: &Path) -> Self {
        match self {
            ParamError::File { msg, .. } => ParamError::File {
                file: path.display().to_string(),
                msg,
            },
            other => ParamError::InFile {
                file: path.display().to_string(),
                inner: Box::new(other),
            },
        }
    }
}

fn edit_distance(a: &str, b: &str) -> usize {
    let a: Vec<char> = a.chars().collect();
    let b: Vec<char> = b.chars().collect();
    let mut prev: Vec<usize> = (0..=b.len()).collect();
    for i in 1..=a.len() {
        let mut cur = vec![i; b.len() + 1];
        for j in 1..=b.len() {
            let sub = prev[j - 1] + usize::from(a[i - 1] != b[j - 1]);
            cur[j] = sub.min(prev[j] + 1).min(cur[j - 1] + 1);
        }
        prev = cur;
    }
    prev[b.len()]
}
