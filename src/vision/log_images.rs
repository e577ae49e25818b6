//! Connector images from rig logs: the `/camera/connector` topic
//! (`foxglove.CompressedImage`, JSON encoding, base64 `data`,
//! `frame_id` = `cycle-<k>`) and the `rig` metadata record (lot, part,
//! rig, motor speed, clearance), spec/rig-log.md.
//!
//! A minimal, self-contained reader kept apart from the rest of the vision
//! code so it can be folded into the rig module (whose loader has its own
//! image extractor) without touching anything else. It follows
//! pitfalls.md: the sans-io linear reader with a record-length limit (no
//! 10^18-byte allocation on corrupt lengths), no end magic required (a
//! truncated file yields every image before the cut and a note), and a
//! panic guard around the reader so a malformed file is an error, never a
//! crash.

use base64::Engine;
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;
use std::path::Path;

/// Topic the camera publishes on.
pub const CAMERA_TOPIC: &str = "/camera/connector";
/// No single record of a rig log is larger than this.
const RECORD_LIMIT: usize = 256 * 1024 * 1024;

/// `rig` metadata keys the vision reports group by.
#[derive(Debug, Clone, Default, PartialEq, Serialize)]
pub struct LogMeta {
    pub rig_id: Option<String>,
    pub lot: Option<String>,
    pub part_number: Option<String>,
    pub motor_rpm: Option<f64>,
    pub clearance_mm: Option<f64>,
}

/// One image of a log.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct LogImage {
    pub cycle: Option<u64>,
    pub log_time_ns: u64,
    pub frame_id: String,
    pub format: String,
    /// The image file's bytes (base64-decoded).
    #[serde(skip)]
    pub data: Vec<u8>,
}

/// Everything read from a log.
#[derive(Debug, Clone, Default, PartialEq, Serialize)]
pub struct LogImages {
    pub meta: LogMeta,
    pub images: Vec<LogImage>,
    /// What went wrong (unreadable messages, truncation); the images
    /// before a problem are kept.
    pub problems: Vec<String>,
}

#[derive(Deserialize)]
struct CompressedImage {
    #[serde(default)]
    frame_id: String,
    #[serde(default)]
    format: String,
    data: String,
}

fn meta_from(map: &BTreeMap<String, String>) -> LogMeta {
    let num = |k: &str| map.get(k).and_then(|v| v.trim().parse::<f64>().ok());
    let s = |k: &str| {
        map.get(k)
            .map(|v| v.trim().to_string())
            .filter(|v| !v.is_empty())
    };
    LogMeta {
        rig_id: s("rig_id"),
        lot: s("lot"),
        part_number: s("part_number"),
        motor_rpm: num("motor_rpm"),
        clearance_mm: num("clearance_mm"),
    }
}

/// Reads the camera images and the `rig` metadata of an MCAP file.
/// Fails only when the file cannot be read at all or is not MCAP.
pub fn read_log_images(path: &Path) -> Result<LogImages, String> {
    let bytes = std::fs::read(path).map_err(|e| format!("cannot read {}: {e}", path.display()))?;
    read_log_images_bytes(&bytes)
}

/// [`read_log_images`] on bytes in memory.
pub fn read_log_images_bytes(bytes: &[u8]) -> Result<LogImages, String> {
    if bytes.len() < 8 || &bytes[..8] != mcap::MAGIC {
        return Err("not an MCAP file (no MCAP magic at the start)".into());
    }
    match std::panic::catch_unwind(|| read_inner(bytes)) {
        Ok(r) => Ok(r),
        Err(_) => Err("malformed MCAP data (the reader gave up)".into()),
    }
}

fn read_inner(bytes: &[u8]) -> LogImages {
    use mcap::sans_io::linear_reader::{LinearReadEvent, LinearReader, LinearReaderOptions};
    let opts = LinearReaderOptions::default()
        .with_skip_end_magic(true)
        .with_record_length_limit(RECORD_LIMIT);
    let mut reader = LinearReader::new_with_options(opts);
    let mut out = LogImages::default();
    let mut camera_channels: Vec<u16> = Vec::new();
    let mut pos = 0usize;
    let mut undecodable = 0usize;
    let mut first_bad: Option<String> = None;
    loop {
        let ev = match reader.next_event() {
            None => break,
            Some(Err(e)) => {
                out.problems.push(format!("log read stopped: {e}"));
                break;
            }
            Some(Ok(ev)) => ev,
        };
        match ev {
            LinearReadEvent::ReadRequest(n) => {
                let take = n.min(bytes.len() - pos);
                let buf = reader.insert(take);
                buf[..take].copy_from_slice(&bytes[pos..pos + take]);
                reader.notify_read(take);
                pos += take;
            }
            LinearReadEvent::Record { data, opcode } => {
                let rec = match mcap::parse_record(opcode, data) {
                    Ok(r) => r,
                    Err(e) => {
                        out.problems
                            .push(format!("unreadable record (opcode {opcode:#x}): {e}"));
                        continue;
                    }
                };
                match rec {
                    mcap::records::Record::Channel(c)
                        if c.topic == CAMERA_TOPIC && !camera_channels.contains(&c.id) =>
                    {
                        camera_channels.push(c.id);
                    }
                    mcap::records::Record::Metadata(m) if m.name == "rig" => {
                        out.meta = meta_from(&m.metadata);
                    }
                    mcap::records::Record::Message { header, data } => {
                        if !camera_channels.contains(&header.channel_id) {
                            continue;
                        }
                        let parsed: Result<CompressedImage, String> =
                            serde_json::from_slice(&data).map_err(|e| e.to_string());
                        let decoded = parsed.and_then(|m| {
                            base64::engine::general_purpose::STANDARD
                                .decode(m.data.as_bytes())
                                .map(|d| (m.frame_id, m.format, d))
                                .map_err(|e| format!("bad base64: {e}"))
                        });
                        match decoded {
                            Ok((frame_id, format, d)) => out.images.push(LogImage {
                                cycle: frame_id
                                    .strip_prefix("cycle-")
                                    .and_then(|s| s.trim().parse().ok()),
                                log_time_ns: header.log_time,
                                frame_id,
                                format,
                                data: d,
                            }),
                            Err(e) => {
                                undecodable += 1;
                                first_bad
                                    .get_or_insert(format!("log_time {}: {e}", header.log_time));
                            }
                        }
                    }
                    _ => {}
                }
            }
        }
    }
    if undecodable > 0 {
        out.problems.push(format!(
            "{undecodable} camera message(s) could not be decoded (first: {})",
            first_bad.unwrap_or_default()
        ));
    }
    out.images.sort_by_key(|i| i.log_time_ns);
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn fixture() -> std::path::PathBuf {
        Path::new(env!("CARGO_MANIFEST_DIR")).join("fixtures/interop/logs/run-2000-images.mcap")
    }

    #[test]
    fn reads_images_and_metadata_of_the_interop_log() {
        let p = fixture();
        let r = read_log_images(&p).unwrap();
        let truth: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(p.with_extension("truth.json")).unwrap())
                .unwrap();
        let want = truth["images"].as_array().unwrap();
        assert_eq!(r.images.len(), want.len());
        assert!(r.problems.is_empty(), "{:?}", r.problems);
        assert_eq!(r.meta.part_number.as_deref(), Some("HDR-2x10-2.54"));
        assert_eq!(r.meta.motor_rpm, Some(2000.0));
        assert_eq!(r.meta.clearance_mm, Some(0.1));
        assert_eq!(r.meta.lot.as_deref(), Some("L2026-1120-07"));
        for (img, t) in r.images.iter().zip(want) {
            assert_eq!(img.frame_id, t["frame_id"].as_str().unwrap());
            assert_eq!(img.cycle, t["cycle_index"].as_u64());
            assert_eq!(img.log_time_ns, t["log_time_ns"].as_u64().unwrap());
            assert_eq!(img.data.len() as u64, t["bytes"].as_u64().unwrap());
            assert!(!img.data.is_empty());
        }
    }

    #[test]
    fn truncated_and_garbage_logs_do_not_crash() {
        let bytes = std::fs::read(fixture()).unwrap();
        let full = read_log_images_bytes(&bytes).unwrap().images.len();
        let cut = read_log_images_bytes(&bytes[..bytes.len() * 6 / 10]).unwrap();
        assert!(cut.images.len() < full);
        assert!(!cut.problems.is_empty());
        let mut flipped = bytes.clone();
        for i in (1000..flipped.len()).step_by(997) {
            flipped[i] ^= 0x5a;
        }
        let _ = read_log_images_bytes(&flipped);
        assert!(read_log_images_bytes(b"hello").is_err());
    }
}
