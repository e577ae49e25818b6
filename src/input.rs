//! Every file pinsight reads whole goes through here, with a bound on its
//! size. `std::fs::read_to_string("/dev/zero")` never ends and takes all
//! the memory there is (`--params /dev/zero` grew to 24 GB before the
//! kernel killed it); a recipe, a parameter file, a channel map, a grid or
//! a batch script is a few KiB, an image a few MB. A file over its bound
//! is refused with its size and the bound, before it is read when the
//! filesystem knows its size, after reading one byte past the bound when it
//! does not (a pipe, a device): reading never takes more than the bound.

use std::io::Read;
use std::path::Path;

/// Largest text (TOML) file read: 16 MiB, thousands of times any real one.
pub const TEXT_MAX_BYTES: u64 = 16 << 20;
/// Largest image file read: 256 MiB (a 5 MP 16-bit colour TIFF is 30 MB).
pub const IMAGE_MAX_BYTES: u64 = 256 << 20;

fn mib(n: u64) -> String {
    format!("{} MiB", n >> 20)
}

/// Reads a whole file of at most `max` bytes.
pub fn read_bounded(path: &Path, max: u64) -> std::io::Result<Vec<u8>> {
    let f = std::fs::File::open(path)?;
    let meta = f.metadata()?;
    if meta.is_dir() {
        return Err(std::io::Error::new(
            std::io::ErrorKind::IsADirectory,
            "it is a folder, not a file",
        ));
    }
    if meta.is_file() && meta.len() > max {
        return Err(std::io::Error::new(
            std::io::ErrorKind::InvalidData,
            format!(
                "{} bytes, more than the {} such a file may hold",
                meta.len(),
                mib(max)
            ),
        ));
    }
    let mut bytes = Vec::with_capacity(if meta.is_file() {
        meta.len() as usize
    } else {
        0
    });
    f.take(max + 1).read_to_end(&mut bytes)?;
    if bytes.len() as u64 > max {
        return Err(std::io::Error::new(
            std::io::ErrorKind::InvalidData,
            format!("more than the {} such a file may hold", mib(max)),
        ));
    }
    Ok(bytes)
}

/// Reads a whole UTF-8 text file of at most [`TEXT_MAX_BYTES`].
pub fn read_text(path: &Path) -> std::io::Result<String> {
    let bytes = read_bounded(path, TEXT_MAX_BYTES)?;
    String::from_utf8(bytes).map_err(|e| {
        std::io::Error::new(
            std::io::ErrorKind::InvalidData,
            format!("not UTF-8 text (byte {})", e.utf8_error().valid_up_to()),
        )
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn an_endless_file_is_refused_after_the_bound() {
        let e = read_bounded(Path::new("/dev/zero"), 1 << 20).unwrap_err();
        assert!(e.to_string().contains("more than the 1 MiB"), "{e}");
    }

    #[test]
    fn a_large_file_is_refused_before_reading() {
        let d = tempfile::tempdir().unwrap();
        let p = d.path().join("big.toml");
        let f = std::fs::File::create(&p).unwrap();
        f.set_len(TEXT_MAX_BYTES + 1).unwrap();
        let e = read_text(&p).unwrap_err().to_string();
        assert!(e.contains("16777217 bytes") && e.contains("16 MiB"), "{e}");
    }

    #[test]
    fn text_folders_and_binary() {
        let d = tempfile::tempdir().unwrap();
        let p = d.path().join("a.toml");
        std::fs::write(&p, "x = 1\n").unwrap();
        assert_eq!(read_text(&p).unwrap(), "x = 1\n");
        assert!(
            read_text(d.path())
                .unwrap_err()
                .to_string()
                .contains("folder")
        );
        std::fs::write(&p, [b'a', 0xff, 0xfe]).unwrap();
        let e = read_text(&p).unwrap_err().to_string();
        assert!(e.contains("not UTF-8 text (byte 1)"), "{e}");
    }
}
