//! A shard's partial result, `partial.json`: what it hands to `pinsight
//! merge`. Every partial starts with the same [`Header`] (which job, which
//! pinsight, which shard of which input list, with which settings); the
//! body is the job's own (its mergeable aggregate and an index of the
//! per-item lines in the shard's own files, see `plant::yields`, or the
//! per-log results, `plant::monitor` …).
//!
//! The files of the shard's folder a merge reads are named in the body
//! with their size and CRC-32 ([`FileCheck`]): a file changed, truncated or
//! left from another run is refused, naming it, before anything is
//! written.

use super::shard::{Part, Shard};
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};

/// The partial's file name in a shard's output folder.
pub const PARTIAL_FILE: &str = "partial.json";

/// The format tag (a pinsight that changes the partial changes the tag;
/// a merge refuses a tag it does not know).
pub const FORMAT: &str = "pinsight-partial/2";

/// The largest partial read.
pub const PARTIAL_MAX_BYTES: u64 = 1 << 30;

/// This pinsight's version, as partials carry it.
pub fn pinsight_version() -> String {
    env!("CARGO_PKG_VERSION").to_string()
}

/// The job a partial belongs to.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Job {
    Yield,
    Monitor,
    Trend,
    Sweep,
}

impl Job {
    pub fn name(self) -> &'static str {
        match self {
            Job::Yield => "yield",
            Job::Monitor => "monitor",
            Job::Trend => "trend",
            Job::Sweep => "sweep",
        }
    }
}

/// What identifies a shard's part of a job.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Header {
    pub format: String,
    pub job: Job,
    /// The pinsight version that wrote it.
    pub pinsight: String,
    pub shard: Shard,
    /// Distinct units (input files, rig logs, grid cases) of the whole job.
    pub units: u64,
    /// SHA-256 of the whole job's sorted unit names, one per line.
    pub digest: String,
    /// SHA-256 of the settings every shard must share (the recipes'
    /// content, the options that change the results).
    pub settings: String,
    /// Those settings in words, for a refusal's message.
    pub settings_text: String,
}

impl Header {
    pub fn new(job: Job, shard: Shard, units: u64, digest: String, settings: &str) -> Header {
        Header {
            format: FORMAT.into(),
            job,
            pinsight: pinsight_version(),
            shard,
            units,
            digest,
            settings: sha256_hex(settings.as_bytes()),
            settings_text: shorten(settings),
        }
    }
}

impl<T> Part<T> {
    /// The header of this shard's partial for `job`: the whole list's
    /// identity (its units and digest) with the job's `settings`.
    pub fn header(&self, job: Job, shard: Shard, settings: &str) -> Header {
        Header::new(job, shard, self.units, self.digest.clone(), settings)
    }
}

/// The first 300 characters of a settings text (the digest covers all).
fn shorten(s: &str) -> String {
    match s.char_indices().nth(300) {
        Some((i, _)) => format!("{}…", &s[..i]),
        None => s.to_string(),
    }
}

/// A partial: the header and the job's body.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct Partial<B> {
    pub header: Header,
    pub body: B,
}

/// SHA-256 in hex.
pub fn sha256_hex(bytes: &[u8]) -> String {
    use sha2::Digest;
    sha2::Sha256::digest(bytes)
        .iter()
        .map(|b| format!("{b:02x}"))
        .collect()
}

/// An output folder's files as (name, bytes) — names may be paths below
/// the folder — and the entries an earlier run left there that this run
/// does not write (to be removed when the folder is committed).
pub type FolderFiles = (Vec<(String, Vec<u8>)>, Vec<String>);

/// A file of the shard's folder that the merge reads: its name (relative
/// to the folder), size and CRC-32.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct FileCheck {
    pub name: String,
    pub bytes: u64,
    pub crc32: u32,
}

impl FileCheck {
    pub fn of(name: &str, bytes: &[u8]) -> FileCheck {
        FileCheck {
            name: name.to_string(),
            bytes: bytes.len() as u64,
            crc32: crc32fast::hash(bytes),
        }
    }

    /// Reads the file from the shard's folder and checks it.
    pub fn read(&self, dir: &Path) -> Result<Vec<u8>, String> {
        let path = dir.join(&self.name);
        let shown = path.display();
        let meta = std::fs::metadata(&path).map_err(|e| format!("{shown}: {e}"))?;
        if !meta.is_file() {
            return Err(format!("{shown}: not a regular file"));
        }
        if meta.len() != self.bytes {
            return Err(format!(
                "{shown}: {} bytes, its shard's partial.json says {}: the file was changed after the shard wrote it (re-run the shard)",
                meta.len(),
                self.bytes
            ));
        }
        let bytes = std::fs::read(&path).map_err(|e| format!("{shown}: {e}"))?;
        if crc32fast::hash(&bytes) != self.crc32 {
            return Err(format!(
                "{shown}: its CRC-32 differs from what its shard's partial.json says: the file was changed after the shard wrote it (re-run the shard)"
            ));
        }
        Ok(bytes)
    }

    /// Checks the file without keeping its bytes.
    pub fn verify(&self, dir: &Path) -> Result<(), String> {
        self.read(dir).map(|_| ())
    }
}

/// Where a partial was found: the file and the shard's folder.
#[derive(Debug, Clone)]
pub struct Found {
    pub file: PathBuf,
    pub dir: PathBuf,
    /// The file as given on the command line, for messages.
    pub shown: String,
}

/// The partial of a path given to merge: a `partial.json` file, or a
/// shard's output folder holding one.
pub fn locate(path: &Path) -> Result<Found, String> {
    let file = if path.is_dir() {
        path.join(PARTIAL_FILE)
    } else {
        path.to_path_buf()
    };
    let dir = file
        .parent()
        .map(Path::to_path_buf)
        .filter(|d| !d.as_os_str().is_empty())
        .unwrap_or_else(|| PathBuf::from("."));
    Ok(Found {
        shown: file.display().to_string(),
        file,
        dir,
    })
}

/// The partial's bytes (a regular file, bounded in size).
pub fn read_bytes(found: &Found) -> Result<Vec<u8>, String> {
    let shown = &found.shown;
    // A device (`/dev/zero`) never ends: only a regular file is a partial.
    match std::fs::metadata(&found.file) {
        Ok(m) if !m.is_file() => return Err(format!("{shown}: not a regular file")),
        Err(e) => return Err(format!("{shown}: {e}")),
        Ok(_) => {}
    }
    crate::input::read_bounded(&found.file, PARTIAL_MAX_BYTES).map_err(|e| format!("{shown}: {e}"))
}

/// The header alone (the body is skipped).
pub fn read_header(found: &Found, bytes: &[u8]) -> Result<Header, String> {
    #[derive(Deserialize)]
    struct Head {
        header: Header,
    }
    #[derive(Deserialize)]
    struct Tag {
        format: Option<String>,
        header: Option<serde::de::IgnoredAny>,
    }
    let shown = &found.shown;
    // An older partial (format 1 had its tag at the top) is named as such.
    if let Ok(t) = serde_json::from_slice::<Tag>(bytes)
        && t.header.is_none()
        && let Some(f) = t.format
    {
        return Err(format!(
            "{shown}: partial format `{f}`, this pinsight merges `{FORMAT}` (re-run the shard with this pinsight)"
        ));
    }
    let h: Head = serde_json::from_slice(bytes)
        .map_err(|e| format!("{shown}: not a pinsight partial result: {e}"))?;
    if h.header.format != FORMAT {
        return Err(format!(
            "{shown}: partial format `{}`, this pinsight merges `{FORMAT}`",
            h.header.format
        ));
    }
    Ok(h.header)
}

/// The whole partial of a job whose header was checked.
pub fn read_body<B: serde::de::DeserializeOwned>(
    found: &Found,
    bytes: &[u8],
) -> Result<Partial<B>, String> {
    serde_json::from_slice(bytes).map_err(|e| format!("{}: a corrupt partial: {e}", found.shown))
}

/// Checks that the partials (their headers, each with where it was found)
/// are one job's complete set: one job, one pinsight, one format, one
/// input list, one shard count, the same settings, every shard exactly
/// once. Returns them ordered by shard index.
pub fn check_set(heads: &[(Found, Header)]) -> Result<Vec<&(Found, Header)>, String> {
    let Some((f0, h0)) = heads.first() else {
        return Err("nothing to merge".into());
    };
    let n = h0.shard.n;
    let mut seen: Vec<Option<&(Found, Header)>> = vec![None; n as usize];
    for entry in heads {
        let (f, h) = entry;
        let src = &f.shown;
        let first = &f0.shown;
        let differs = |what: &str, a: &str, b: &str| {
            format!("{src}: {what} {a} differs from {first}'s {b}: not shards of one job")
        };
        if h.job != h0.job {
            return Err(differs("job", h.job.name(), h0.job.name()));
        }
        if h.pinsight != h0.pinsight {
            return Err(differs(
                "pinsight version",
                &h.pinsight,
                &format!("{} (shards of one job run one pinsight)", h0.pinsight),
            ));
        }
        if h.shard.n != n {
            return Err(differs(
                "shard count",
                &h.shard.n.to_string(),
                &n.to_string(),
            ));
        }
        if h.digest != h0.digest || h.units != h0.units {
            return Err(differs(
                "input list",
                &format!("({} units)", h.units),
                &format!("({} units)", h0.units),
            ));
        }
        if h.settings != h0.settings {
            return Err(differs(
                "settings",
                &format!("[{}]", h.settings_text),
                &format!("[{}]", h0.settings_text),
            ));
        }
        let slot = seen
            .get_mut(h.shard.k as usize)
            .ok_or_else(|| format!("{src}: shard {} out of range", h.shard))?;
        if let Some((other, _)) = slot {
            return Err(format!(
                "shard {} given twice: {} and {src}",
                h.shard, other.shown
            ));
        }
        *slot = Some(entry);
    }
    let missing: Vec<String> = seen
        .iter()
        .enumerate()
        .filter(|(_, s)| s.is_none())
        .map(|(k, _)| format!("{k}/{n}"))
        .collect();
    if !missing.is_empty() {
        return Err(format!(
            "shard(s) {} missing: a merge needs every shard of the job",
            missing.join(", ")
        ));
    }
    Ok(seen.into_iter().flatten().collect())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn head(k: u32, n: u32) -> (Found, Header) {
        let h = Header::new(
            Job::Yield,
            Shard::new(k, n).unwrap(),
            10,
            "d".into(),
            "recipes A",
        );
        let f = locate(Path::new(&format!("s{k}/partial.json"))).unwrap();
        (f, h)
    }

    #[test]
    fn a_complete_set_in_shard_order() {
        let set = vec![head(2, 3), head(0, 3), head(1, 3)];
        let ok = check_set(&set).unwrap();
        let ks: Vec<u32> = ok.iter().map(|(_, h)| h.shard.k).collect();
        assert_eq!(ks, vec![0, 1, 2]);
    }

    #[test]
    fn refusals_name_the_files() {
        let e = check_set(&[head(0, 3), head(1, 3)]).unwrap_err();
        assert!(e.contains("2/3 missing"), "{e}");
        let e = check_set(&[head(0, 2), head(0, 2), head(1, 2)]).unwrap_err();
        assert!(
            e.contains("given twice") && e.contains("s0/partial.json"),
            "{e}"
        );
        let mut other = head(1, 2);
        other.1.pinsight = "9.9.9".into();
        let e = check_set(&[head(0, 2), other]).unwrap_err();
        assert!(e.contains("s1/partial.json") && e.contains("9.9.9"), "{e}");
        let mut other = head(1, 2);
        other.1 = Header::new(Job::Yield, other.1.shard, 10, "d".into(), "recipes B");
        let e = check_set(&[head(0, 2), other]).unwrap_err();
        assert!(e.contains("settings") && e.contains("recipes B"), "{e}");
        let mut other = head(1, 2);
        other.1.job = Job::Monitor;
        let e = check_set(&[head(0, 2), other]).unwrap_err();
        assert!(e.contains("job monitor"), "{e}");
        let mut other = head(1, 2);
        other.1.digest = "e".into();
        assert!(
            check_set(&[head(0, 2), other])
                .unwrap_err()
                .contains("input list")
        );
        let e = check_set(&[head(0, 2), head(1, 3)]).unwrap_err();
        assert!(e.contains("shard count"), "{e}");
    }

    #[test]
    fn file_checks_catch_changes() {
        let d = tempfile::tempdir().unwrap();
        std::fs::write(d.path().join("a.csv"), b"hello\n").unwrap();
        let c = FileCheck::of("a.csv", b"hello\n");
        assert_eq!(c.read(d.path()).unwrap(), b"hello\n");
        std::fs::write(d.path().join("a.csv"), b"hellO\n").unwrap();
        let e = c.read(d.path()).unwrap_err();
        assert!(e.contains("a.csv") && e.contains("CRC"), "{e}");
        std::fs::write(d.path().join("a.csv"), b"hello").unwrap();
        assert!(c.read(d.path()).unwrap_err().contains("bytes"));
        std::fs::remove_file(d.path().join("a.csv")).unwrap();
        assert!(c.read(d.path()).unwrap_err().contains("a.csv"));
    }
}
