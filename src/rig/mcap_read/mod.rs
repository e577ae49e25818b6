//! Crash-proof reading of the MCAP container over a memory map.
//!
//! Why not the `mcap` crate's readers directly: with default options they
//! allocate whatever a corrupt length field says and abort the process
//! (pitfalls.md), they stop at the first bad chunk, and they decompress a
//! chunk record by record. Here the file is memory-mapped and read in two
//! passes, with `mcap`'s record parsers ([`mcap::parse_record`] and its
//! record types) for everything but the framing:
//!
//! 1. [`scan`]: a sequential walk over the top-level records (cheap: it only
//!    touches record headers, chunks are not decompressed), plus the summary
//!    section located from the footer when the file has one. Every length is
//!    checked against the bytes actually present before anything is sliced;
//!    a length that runs past the end of the file is either a truncation (no
//!    footer) or a corrupt record, and the walk re-synchronises on the next
//!    chunk (from the summary's chunk index, else by searching for a
//!    plausible chunk header). The result is a list of [`WorkItem`]s (chunks
//!    and runs of top-level messages) plus schemas, channels, metadata,
//!    attachments and findings.
//! 2. [`decode_batch`]: the work items are decoded in parallel (rayon) in
//!    bounded batches: each chunk is decompressed whole into a per-thread
//!    buffer (its declared size checked against the record-length limit
//!    first), its CRC validated, and its records walked with the same bounds
//!    checks. A chunk that fails (bad CRC, undecodable, unknown compression)
//!    is dropped and reported; the others still load. A chunk cut by a
//!    truncation is decompressed as far as it goes and its complete
//!    messages are kept (reported as not CRC-verifiable).
//!
//! Memory stays bounded: only one batch of decompressed chunks exists at a
//! time, and the pages of the map that a batch has been read from are
//! released (`MADV_DONTNEED`) after it, so a log larger than RAM streams.

mod items;
mod scan;

pub use items::*;
pub use scan::*;

use super::error::LogError;
use super::report::Finding;
use mcap::records::{self, op};
use memmap2::Mmap;
use serde::Serialize;
use std::collections::BTreeMap;
use std::path::Path;

/// The MCAP magic, at the start and the end of a file.
pub const MAGIC: &[u8; 8] = b"\x89MCAP0\r\n";

/// Options for reading the container.
#[derive(Debug, Clone, Serialize)]
pub struct ReadOptions {
    /// Largest record or decompressed chunk accepted (bytes). Larger ones are
    /// skipped with a finding instead of being allocated.
    pub record_length_limit: u64,
    /// Validate chunk, data-section and summary CRCs (when the writer stored them).
    pub validate_crcs: bool,
    /// Decode chunks on all cores.
    pub parallel: bool,
    /// Compressed bytes per decode batch: bounds the memory held at once.
    pub batch_bytes: u64,
}

impl Default for ReadOptions {
    fn default() -> Self {
        ReadOptions {
            record_length_limit: 256 << 20,
            validate_crcs: true,
            parallel: true,
            batch_bytes: 32 << 20,
        }
    }
}

enum Bytes {
    Map(Mmap),
    Owned(Vec<u8>),
}

/// The bytes of one log: a read-only memory map of the file (or an owned
/// buffer, for tests and in-memory data).
pub struct Source {
    name: String,
    bytes: Bytes,
}

impl Source {
    /// Maps a file read-only. The file must not be truncated by another
    /// process while it is mapped (that would be a SIGBUS, as with any map).
    pub fn open(path: &Path) -> Result<Source, LogError> {
        let file = std::fs::File::open(path).map_err(|e| LogError::io(path, e))?;
        let len = file.metadata().map_err(|e| LogError::io(path, e))?.len();
        let name = path.display().to_string();
        if len == 0 {
            return Err(LogError::Empty { file: name });
        }
        // SAFETY: the map is read-only and private to this process; the
        // usual caveat of file maps (another process truncating the file)
        // is documented above.
        let map = unsafe { Mmap::map(&file) }.map_err(|e| LogError::io(path, e))?;
        Ok(Source {
            name,
            bytes: Bytes::Map(map),
        })
    }

    /// Wraps bytes already in memory.
    pub fn from_vec(name: impl Into<String>, bytes: Vec<u8>) -> Source {
        Source {
            name: name.into(),
            bytes: Bytes::Owned(bytes),
        }
    }

    pub fn name(&self) -> &str {
        &self.name
    }

    pub fn bytes(&self) -> &[u8] {
        match &self.bytes {
            Bytes::Map(m) => m,
            Bytes::Owned(v) => v,
        }
    }

    /// Tells the kernel the pages of `[offset, offset+len)` will not be read
    /// again, so they leave this process's resident set (they stay in the
    /// page cache). Keeps the resident memory of a streamed multi-GiB log bounded.
    pub fn release(&self, offset: u64, len: u64) {
        if let Bytes::Map(m) = &self.bytes {
            let page = 4096u64;
            let start = offset.div_ceil(page) * page;
            let end = (offset + len).min(m.len() as u64) / page * page;
            if end > start {
                // SAFETY: the map is read-only and file-backed: MADV_DONTNEED
                // only drops this process's page-table entries, the content is
                // re-read from the file if it is touched again.
                let _ = unsafe {
                    m.unchecked_advise_range(
                        memmap2::UncheckedAdvice::DontNeed,
                        start as usize,
                        (end - start) as usize,
                    )
                };
            }
        }
    }
}

/// A schema record.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct SchemaDef {
    pub id: u16,
    pub name: String,
    pub encoding: String,
    pub data: Vec<u8>,
}

/// A channel record.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct ChannelDef {
    pub id: u16,
    pub schema_id: u16,
    pub topic: String,
    pub message_encoding: String,
}

impl SchemaDef {
    /// The schema record of a record body (None: not one, or damaged),
    /// parsed by the mcap crate; the scan, the item reader and the live
    /// tail take their schemas from here.
    pub fn parse(body: &[u8]) -> Option<Self> {
        match mcap::parse_record(mcap::records::op::SCHEMA, body).ok()? {
            mcap::records::Record::Schema { header, data } => Some(SchemaDef {
                id: header.id,
                name: header.name,
                encoding: header.encoding,
                data: data.into_owned(),
            }),
            _ => None,
        }
    }
}

impl ChannelDef {
    /// The channel record of a record body (None: not one, or damaged).
    pub fn parse(body: &[u8]) -> Option<Self> {
        match mcap::parse_record(mcap::records::op::CHANNEL, body).ok()? {
            mcap::records::Record::Channel(c) => Some(ChannelDef {
                id: c.id,
                schema_id: c.schema_id,
                topic: c.topic,
                message_encoding: c.message_encoding,
            }),
            _ => None,
        }
    }
}

/// A metadata record.
#[derive(Debug, Clone)]
pub struct MetadataRecord {
    pub name: String,
    pub map: BTreeMap<String, String>,
    pub offset: u64,
}

/// An attachment record (the content stays in the file: `data_offset`, `data_len`).
#[derive(Debug, Clone)]
pub struct AttachmentRecord {
    pub name: String,
    pub media_type: String,
    pub log_time: u64,
    pub create_time: u64,
    pub offset: u64,
    pub data_offset: u64,
    pub data_len: u64,
}

/// What a work item holds.
#[derive(Debug, Clone)]
pub enum ItemKind {
    /// A chunk record. `data_start..data_start+data_len` are its (compressed) records.
    Chunk {
        compression: String,
        uncompressed_size: u64,
        crc: u32,
        data_start: u64,
        data_len: u64,
        /// False for a chunk cut by the end of the file.
        complete: bool,
    },
    /// Consecutive top-level message records (unchunked files), `start..end`.
    Records { start: u64, end: u64, messages: u64 },
}

/// A unit of decoding work: one chunk, or a run of top-level messages.
#[derive(Debug, Clone)]
pub struct WorkItem {
    /// Byte offset of the (first) record in the file.
    pub offset: u64,
    /// Bytes of the file the item covers.
    pub len: u64,
    pub kind: ItemKind,
}

impl WorkItem {
    /// Decompressed bytes the item will produce (an estimate for top-level records).
    pub fn decoded_size(&self) -> u64 {
        match &self.kind {
            ItemKind::Chunk {
                uncompressed_size, ..
            } => *uncompressed_size,
            ItemKind::Records { start, end, .. } => end - start,
        }
    }
}

/// Summary statistics record, when present.
#[derive(Debug, Clone, Serialize)]
pub struct SummaryStats {
    pub message_count: u64,
    pub chunk_count: u32,
    pub message_start_time: u64,
    pub message_end_time: u64,
    pub channel_message_counts: BTreeMap<u16, u64>,
}

/// Facts about the container (plain data for reports).
#[derive(Debug, Clone, Default, Serialize)]
pub struct ContainerInfo {
    pub file_size: u64,
    pub profile: Option<String>,
    pub library: Option<String>,
    pub chunked: bool,
    pub chunks: u64,
    /// Chunk compressions seen ("" = uncompressed).
    pub compressions: Vec<String>,
    /// A summary section was found and used.
    pub summary: bool,
    pub statistics: bool,
    pub chunk_index: bool,
    pub message_indexes: bool,
    pub end_magic: bool,
    pub data_end: bool,
    pub metadata_records: Vec<String>,
    pub attachments: u64,
    /// Message count of the summary's statistics record.
    pub statistics_message_count: Option<u64>,
}

/// The result of walking the container.
#[derive(Debug, Default)]
pub struct Scan {
    pub info: ContainerInfo,
    pub schemas: BTreeMap<u16, SchemaDef>,
    pub channels: BTreeMap<u16, ChannelDef>,
    pub items: Vec<WorkItem>,
    pub metadata: Vec<MetadataRecord>,
    pub attachments: Vec<AttachmentRecord>,
    pub stats: Option<SummaryStats>,
    pub findings: Vec<Finding>,
    /// Byte offset where the file was found truncated.
    pub truncated_at: Option<u64>,
}

fn u64_at(b: &[u8], pos: usize) -> Option<u64> {
    b.get(pos..pos.checked_add(8)?)
        .and_then(|s| s.try_into().ok())
        .map(u64::from_le_bytes)
}

fn u32_at(b: &[u8], pos: usize) -> Option<u32> {
    b.get(pos..pos.checked_add(4)?)
        .and_then(|s| s.try_into().ok())
        .map(u32::from_le_bytes)
}

fn u16_at(b: &[u8], pos: usize) -> Option<u16> {
    b.get(pos..pos.checked_add(2)?)
        .and_then(|s| s.try_into().ok())
        .map(u16::from_le_bytes)
}

/// Human name of a record opcode.
pub fn opcode_name(opcode: u8) -> String {
    match opcode {
        op::HEADER => "header".into(),
        op::FOOTER => "footer".into(),
        op::SCHEMA => "schema".into(),
        op::CHANNEL => "channel".into(),
        op::MESSAGE => "message".into(),
        op::CHUNK => "chunk".into(),
        op::MESSAGE_INDEX => "message index".into(),
        op::CHUNK_INDEX => "chunk index".into(),
        op::ATTACHMENT => "attachment".into(),
        op::ATTACHMENT_INDEX => "attachment index".into(),
        op::STATISTICS => "statistics".into(),
        op::METADATA => "metadata".into(),
        op::METADATA_INDEX => "metadata index".into(),
        op::SUMMARY_OFFSET => "summary offset".into(),
        op::DATA_END => "data end".into(),
        o => format!("unknown (opcode 0x{o:02X})"),
    }
}

/// Length of the fixed chunk header before the compression string.
const CHUNK_FIXED: usize = 8 + 8 + 8 + 4 + 4;

/// Parsed chunk header with the offset of its data relative to the record body.
struct ChunkHead {
    uncompressed_size: u64,
    crc: u32,
    compression: String,
    compressed_size: u64,
    data_rel: usize,
}

/// Parses a chunk record's header from (possibly only the start of) its body.
fn chunk_head(body: &[u8]) -> Option<ChunkHead> {
    let uncompressed_size = u64_at(body, 16)?;
    let crc = u32_at(body, 24)?;
    let clen = u32_at(body, 28)? as usize;
    if clen > 64 {
        return None;
    }
    let cstart = CHUNK_FIXED;
    let compression = std::str::from_utf8(body.get(cstart..cstart + clen)?)
        .ok()?
        .to_string();
    let compressed_size = u64_at(body, cstart + clen)?;
    Some(ChunkHead {
        uncompressed_size,
        crc,
        compression,
        compressed_size,
        data_rel: cstart + clen + 8,
    })
}

/// Reads the footer when the file ends with the magic. Returns (footer record offset, footer).
fn read_footer(b: &[u8]) -> Option<(usize, records::Footer)> {
    let n = b.len();
    if n < 8 + 8 + 29 || &b[n - 8..] != MAGIC {
        return None;
    }
    let fpos = n - 8 - 29;
    if b[fpos] != op::FOOTER || u64_at(b, fpos + 1)? != 20 {
        return None;
    }
    Some((
        fpos,
        records::Footer {
            summary_start: u64_at(b, fpos + 9)?,
            summary_offset_start: u64_at(b, fpos + 17)?,
            summary_crc: u32_at(b, fpos + 25)?,
        },
    ))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn walk_records_stops_on_overrun() {
        let mut buf = vec![op::MESSAGE];
        buf.extend_from_slice(&3u64.to_le_bytes());
        buf.extend_from_slice(&[1, 2, 3]);
        buf.push(op::MESSAGE);
        buf.extend_from_slice(&(u64::MAX).to_le_bytes());
        let mut seen = 0;
        let r = walk_records(&buf, |_, body, _| {
            assert_eq!(body, &[1, 2, 3]);
            seen += 1;
            true
        });
        assert_eq!(seen, 1);
        assert_eq!(r, Err((12, u64::MAX)));
    }

    #[test]
    fn bad_magic_and_empty() {
        let opts = ReadOptions::default();
        assert!(matches!(
            scan(&Source::from_vec("e", vec![]), &opts),
            Err(LogError::Empty { .. })
        ));
        assert!(matches!(
            scan(
                &Source::from_vec("m", b"PK\x03\x04 not mcap".to_vec()),
                &opts
            ),
            Err(LogError::BadMagic { .. })
        ));
        assert!(matches!(
            scan(&Source::from_vec("t", MAGIC[..4].to_vec()), &opts),
            Err(LogError::Unreadable { .. })
        ));
    }

    #[test]
    fn magic_only_is_truncated() {
        let s = scan(
            &Source::from_vec("m", MAGIC.to_vec()),
            &ReadOptions::default(),
        )
        .unwrap();
        assert!(s.truncated_at.is_some());
        assert!(s.items.is_empty());
    }
}
