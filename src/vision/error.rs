//! Why an image could not be inspected. Every variant reads as a sentence
//! a technician can act on; the batch report prefixes it with the image's
//! name.

use serde::Serialize;

/// An image that cannot be read or analysed (counted as `error` in yield).
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum VisionError {
    #[error("cannot read file: {0}")]
    Io(String),
    #[error("empty file (0 bytes)")]
    Empty,
    #[error("not a recognised image format (PNG, JPEG, BMP, TIFF, ...); first bytes: {0}")]
    NotImage(String),
    #[error(
        "image header claims {width} × {height} px, beyond the limit of {limit_mpx} Mpx: refusing to allocate it"
    )]
    TooLarge {
        width: u32,
        height: u32,
        limit_mpx: u32,
    },
    #[error("image exceeds the decoder's memory limit, refusing to decode it: {0}")]
    LimitExceeded(String),
    #[error(
        "image is {width} × {height} px: too small to hold a connector (minimum {min} × {min})"
    )]
    TooSmall { width: u32, height: u32, min: u32 },
    #[error("corrupt or truncated {format} data: {msg}")]
    Decode { format: String, msg: String },
    #[error("image has no contrast (all samples between {lo} and {hi}): a blank or black frame")]
    NoContrast { lo: f32, hi: f32 },
    #[error("image does not match recipe {part}: {msg}")]
    WrongPart { part: String, msg: String },
    #[error("no pins found for recipe {part}: {msg}")]
    NoPins { part: String, msg: String },
    #[error("housing not found: {0}")]
    NoHousing(String),
    #[error("{0}")]
    Recipe(String),
    #[error("cancelled before this image was inspected")]
    Cancelled,
}

/// Short machine-readable class of an error (CSV / JSON `error_kind`).
#[derive(
    Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, serde::Deserialize, PartialOrd, Ord,
)]
#[serde(rename_all = "snake_case")]
pub enum ErrorKind {
    Io,
    Empty,
    NotImage,
    TooLarge,
    TooSmall,
    Decode,
    NoContrast,
    WrongPart,
    NoPins,
    NoHousing,
    Recipe,
    Cancelled,
}

impl ErrorKind {
    /// The snake_case name, as in JSON (CSV and Markdown use the same).
    pub fn as_str(self) -> &'static str {
        match self {
            ErrorKind::Io => "io",
            ErrorKind::Empty => "empty",
            ErrorKind::NotImage => "not_image",
            ErrorKind::TooLarge => "too_large",
            ErrorKind::TooSmall => "too_small",
            ErrorKind::Decode => "decode",
            ErrorKind::NoContrast => "no_contrast",
            ErrorKind::WrongPart => "wrong_part",
            ErrorKind::NoPins => "no_pins",
            ErrorKind::NoHousing => "no_housing",
            ErrorKind::Recipe => "recipe",
            ErrorKind::Cancelled => "cancelled",
        }
    }
}

impl VisionError {
    pub fn kind(&self) -> ErrorKind {
        match self {
            VisionError::Io(_) => ErrorKind::Io,
            VisionError::Empty => ErrorKind::Empty,
            VisionError::NotImage(_) => ErrorKind::NotImage,
            VisionError::TooLarge { .. } | VisionError::LimitExceeded(_) => ErrorKind::TooLarge,
            VisionError::TooSmall { .. } => ErrorKind::TooSmall,
            VisionError::Decode { .. } => ErrorKind::Decode,
            VisionError::NoContrast { .. } => ErrorKind::NoContrast,
            VisionError::WrongPart { .. } => ErrorKind::WrongPart,
            VisionError::NoPins { .. } => ErrorKind::NoPins,
            VisionError::NoHousing(_) => ErrorKind::NoHousing,
            VisionError::Recipe(_) => ErrorKind::Recipe,
            VisionError::Cancelled => ErrorKind::Cancelled,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn kind_names_agree_with_json() {
        for k in [
            ErrorKind::Io,
            ErrorKind::Empty,
            ErrorKind::NotImage,
            ErrorKind::TooLarge,
            ErrorKind::TooSmall,
            ErrorKind::Decode,
            ErrorKind::NoContrast,
            ErrorKind::WrongPart,
            ErrorKind::NoPins,
            ErrorKind::NoHousing,
            ErrorKind::Recipe,
            ErrorKind::Cancelled,
        ] {
            assert_eq!(
                serde_json::to_string(&k).unwrap(),
                format!("\"{}\"", k.as_str())
            );
        }
    }
}
