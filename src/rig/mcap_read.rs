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

use super::error::LogError;
use super::report::{Finding, FindingCode, Place, Severity};
use mcap::records::{self, op};
use memmap2::Mmap;
use rayon::prelude::*;
use serde::Serialize;
use std::collections::BTreeMap;
use std::io::Read;
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

/// Walks the records of `buf` (top-level section or decompressed chunk content).
/// Calls `f(opcode, body, offset_of_record_in_buf)`; stops at the first record
/// whose length runs past the buffer and returns its offset and declared length.
fn walk_records<'a>(
    buf: &'a [u8],
    mut f: impl FnMut(u8, &'a [u8], usize) -> bool,
) -> Result<(), (usize, u64)> {
    let mut pos = 0usize;
    while pos < buf.len() {
        let (Some(&opcode), Some(len)) = (buf.get(pos), u64_at(buf, pos + 1)) else {
            return Err((pos, 0));
        };
        let start = pos + 9;
        let avail = (buf.len() - start) as u64;
        if len > avail {
            return Err((pos, len));
        }
        let end = start + len as usize;
        if !f(opcode, &buf[start..end], pos) {
            return Ok(());
        }
        pos = end;
    }
    Ok(())
}

struct Walker<'a> {
    b: &'a [u8],
    name: &'a str,
    opts: &'a ReadOptions,
    scan: Scan,
    /// Chunk start offsets from the summary's chunk index (for re-synchronising).
    index_chunks: Vec<u64>,
    pending: Option<(u64, u64, u64)>,
    seen_chunks: std::collections::BTreeSet<u64>,
    unknown_records: u64,
    private_records: u64,
}

impl<'a> Walker<'a> {
    fn finding(&mut self, sev: Severity, code: FindingCode, place: Option<Place>, text: String) {
        self.scan
            .findings
            .push(Finding::new(sev, code, self.name, None, place, text));
    }

    fn flush_pending(&mut self) {
        if let Some((start, end, n)) = self.pending.take() {
            self.scan.items.push(WorkItem {
                offset: start,
                len: end - start,
                kind: ItemKind::Records {
                    start,
                    end,
                    messages: n,
                },
            });
        }
    }

    fn add_schema(&mut self, def: SchemaDef, pos: u64) {
        if def.id == 0 {
            return;
        }
        if let Some(old) = self.scan.schemas.get(&def.id) {
            if *old != def {
                self.finding(
                    Severity::Warning,
                    FindingCode::ChannelConflict,
                    Some(Place::byte(pos)),
                    format!(
                        "schema id {} redefined at byte {pos} ('{}' vs '{}'); the first definition is used",
                        def.id, old.name, def.name
                    ),
                );
            }
            return;
        }
        self.scan.schemas.insert(def.id, def);
    }

    fn add_channel(&mut self, def: ChannelDef, pos: u64) {
        if let Some(old) = self.scan.channels.get(&def.id) {
            if *old != def {
                self.finding(
                    Severity::Warning,
                    FindingCode::ChannelConflict,
                    Some(Place::byte(pos)),
                    format!(
                        "channel id {} redefined at byte {pos} ('{}' vs '{}'); the first definition is used",
                        def.id, old.topic, def.topic
                    ),
                );
            }
            return;
        }
        self.scan.channels.insert(def.id, def);
    }

    /// Handles one record of the data or summary section at absolute offset `pos`.
    /// Returns false to stop the walk (footer).
    fn record(&mut self, opcode: u8, body: &'a [u8], pos: u64, in_summary: bool) -> bool {
        if opcode != op::MESSAGE {
            self.flush_pending();
        }
        let rec_len = 9 + body.len() as u64;
        match opcode {
            op::MESSAGE if !in_summary => {
                let extend = matches!(self.pending, Some((s, end, _)) if end == pos && end - s < (4 << 20));
                if extend {
                    if let Some(p) = &mut self.pending {
                        p.1 = pos + rec_len;
                        p.2 += 1;
                    }
                } else {
                    self.flush_pending();
                    self.pending = Some((pos, pos + rec_len, 1));
                }
            }
            op::CHUNK if !in_summary => {
                self.scan.info.chunked = true;
                match chunk_head(body) {
                    Some(h) if (h.data_rel as u64).saturating_add(h.compressed_size) <= body.len() as u64 => {
                        self.push_chunk(pos, rec_len, h, true);
                    }
                    _ => self.finding(
                        Severity::DataLoss,
                        FindingCode::CorruptRecord,
                        Some(Place::byte(pos)),
                        format!("chunk record at byte {pos} has an inconsistent header; its messages are lost"),
                    ),
                }
            }
            op::HEADER => match mcap::parse_record(opcode, body) {
                Ok(records::Record::Header(h)) => {
                    self.scan.info.profile = Some(h.profile);
                    self.scan.info.library = Some(h.library);
                }
                _ => self.corrupt_small(opcode, pos),
            },
            op::SCHEMA => match mcap::parse_record(opcode, body) {
                Ok(records::Record::Schema { header, data }) => self.add_schema(
                    SchemaDef {
                        id: header.id,
                        name: header.name,
                        encoding: header.encoding,
                        data: data.into_owned(),
                    },
                    pos,
                ),
                _ => self.corrupt_small(opcode, pos),
            },
            op::CHANNEL => match mcap::parse_record(opcode, body) {
                Ok(records::Record::Channel(c)) => self.add_channel(
                    ChannelDef {
                        id: c.id,
                        schema_id: c.schema_id,
                        topic: c.topic,
                        message_encoding: c.message_encoding,
                    },
                    pos,
                ),
                _ => self.corrupt_small(opcode, pos),
            },
            op::MESSAGE_INDEX => self.scan.info.message_indexes = true,
            op::ATTACHMENT if !in_summary => match mcap::parse_record(opcode, body) {
                Ok(records::Record::Attachment { header, data, .. }) => {
                    let data_offset = data.as_ptr() as u64 - self.b.as_ptr() as u64;
                    self.scan.attachments.push(AttachmentRecord {
                        name: header.name,
                        media_type: header.media_type,
                        log_time: header.log_time,
                        create_time: header.create_time,
                        offset: pos,
                        data_offset,
                        data_len: data.len() as u64,
                    });
                }
                Err(mcap::McapError::BadAttachmentCrc { saved, calculated }) => self.finding(
                    Severity::DataLoss,
                    FindingCode::BadAttachmentCrc,
                    Some(Place::byte(pos)),
                    format!("attachment at byte {pos}: CRC mismatch (stored {saved:08x}, computed {calculated:08x}); attachment skipped"),
                ),
                _ => self.corrupt_small(opcode, pos),
            },
            op::METADATA if !in_summary => match mcap::parse_record(opcode, body) {
                Ok(records::Record::Metadata(m)) => self.scan.metadata.push(MetadataRecord {
                    name: m.name,
                    map: m.metadata,
                    offset: pos,
                }),
                _ => self.corrupt_small(opcode, pos),
            },
            op::DATA_END => {
                self.scan.info.data_end = true;
                if !self.scan.info.chunked && self.opts.validate_crcs {
                    if let Some(saved) = u32_at(body, 0) {
                        let calculated = crc32fast::hash(&self.b[..pos as usize]);
                        if saved != 0 && saved != calculated {
                            self.finding(
                                Severity::Warning,
                                FindingCode::BadDataCrc,
                                Some(Place::byte(pos)),
                                format!("data section CRC mismatch (stored {saved:08x}, computed {calculated:08x}): some message content may be corrupt"),
                            );
                        }
                    }
                }
            }
            op::CHUNK_INDEX => {
                if let Ok(records::Record::ChunkIndex(ci)) = mcap::parse_record(opcode, body) {
                    self.scan.info.chunk_index = true;
                    self.index_chunks.push(ci.chunk_start_offset);
                }
            }
            op::STATISTICS => {
                if let Ok(records::Record::Statistics(s)) = mcap::parse_record(opcode, body) {
                    self.scan.info.statistics = true;
                    self.scan.info.statistics_message_count = Some(s.message_count);
                    self.scan.stats = Some(SummaryStats {
                        message_count: s.message_count,
                        chunk_count: s.chunk_count,
                        message_start_time: s.message_start_time,
                        message_end_time: s.message_end_time,
                        channel_message_counts: s.channel_message_counts,
                    });
                }
            }
            op::FOOTER => return false,
            op::ATTACHMENT_INDEX | op::METADATA_INDEX | op::SUMMARY_OFFSET => {}
            op::ATTACHMENT | op::METADATA | op::MESSAGE | op::CHUNK => {}
            o if o >= 0x80 => self.private_records += 1,
            _ => self.unknown_records += 1,
        }
        true
    }

    fn corrupt_small(&mut self, opcode: u8, pos: u64) {
        self.finding(
            Severity::Warning,
            FindingCode::CorruptRecord,
            Some(Place::byte(pos)),
            format!(
                "{} record at byte {pos} cannot be parsed; skipped",
                opcode_name(opcode)
            ),
        );
    }

    fn push_chunk(&mut self, pos: u64, rec_len: u64, h: ChunkHead, complete: bool) {
        if !self.seen_chunks.insert(pos) {
            return;
        }
        let data_start = pos + 9 + h.data_rel as u64;
        let avail = (self.b.len() as u64).saturating_sub(data_start);
        if !self.scan.info.compressions.contains(&h.compression) {
            self.scan.info.compressions.push(h.compression.clone());
        }
        self.scan.info.chunks += 1;
        self.scan.items.push(WorkItem {
            offset: pos,
            len: rec_len.min(self.b.len() as u64 - pos),
            kind: ItemKind::Chunk {
                compression: h.compression,
                uncompressed_size: h.uncompressed_size,
                crc: h.crc,
                data_start,
                data_len: h.compressed_size.min(avail),
                complete,
            },
        });
    }

    /// Next place to resume after a corrupt record at `pos`: the next chunk of
    /// the summary's index, else a plausible chunk header found by search.
    fn resync(&self, pos: u64, limit: u64) -> Option<u64> {
        if let Some(&next) = self
            .index_chunks
            .iter()
            .filter(|&&c| c > pos && c < limit)
            .min()
        {
            return Some(next);
        }
        let b = &self.b[..limit as usize];
        let mut p = pos as usize + 1;
        while p + 9 + CHUNK_FIXED < b.len() {
            let off = b[p..].iter().position(|&x| x == op::CHUNK)?;
            p += off;
            if let Some(len) = u64_at(b, p + 1) {
                let body_start = p + 9;
                if len <= (b.len() - body_start.min(b.len())) as u64 {
                    let body = &b[body_start..body_start + len as usize];
                    if let Some(h) = chunk_head(body) {
                        let known = matches!(h.compression.as_str(), "" | "zstd" | "lz4");
                        if known
                            && (h.data_rel as u64).saturating_add(h.compressed_size) <= len
                            && h.uncompressed_size <= self.opts.record_length_limit
                        {
                            return Some(p as u64);
                        }
                    }
                }
            }
            p += 1;
        }
        None
    }
}

/// Walks the container: header, summary (from the footer), then the data
/// section. Never fails on content; only on "not MCAP at all".
pub fn scan(src: &Source, opts: &ReadOptions) -> Result<Scan, LogError> {
    let b = src.bytes();
    let name = src.name();
    if b.is_empty() {
        return Err(LogError::Empty {
            file: name.to_string(),
        });
    }
    if b.len() < 8 || &b[..8] != MAGIC {
        if b.len() < 8 && MAGIC.starts_with(b) {
            return Err(LogError::Unreadable {
                file: name.to_string(),
                message: format!(
                    "truncated to {} bytes, inside the MCAP magic: nothing to read",
                    b.len()
                ),
            });
        }
        let found = b
            .iter()
            .take(8)
            .map(|x| format!("{x:02X}"))
            .collect::<Vec<_>>()
            .join(" ");
        return Err(LogError::BadMagic {
            file: name.to_string(),
            found,
        });
    }
    let mut w = Walker {
        b,
        name,
        opts,
        scan: Scan::default(),
        index_chunks: Vec::new(),
        pending: None,
        seen_chunks: Default::default(),
        unknown_records: 0,
        private_records: 0,
    };
    w.scan.info.file_size = b.len() as u64;

    // Summary, located from the footer.
    let footer = read_footer(b);
    let mut data_limit = b.len() as u64;
    if let Some((fpos, f)) = &footer {
        w.scan.info.end_magic = true;
        data_limit = *fpos as u64;
        if f.summary_start != 0 {
            let ss = f.summary_start;
            if ss < 8 || ss > *fpos as u64 {
                w.finding(
                    Severity::Warning,
                    FindingCode::CorruptRecord,
                    Some(Place::byte(*fpos as u64)),
                    format!(
                        "footer points to a summary at byte {ss}, outside the file; summary ignored"
                    ),
                );
            } else {
                let crc_ok = if opts.validate_crcs && f.summary_crc != 0 {
                    let calculated = crc32fast::hash(&b[ss as usize..*fpos + 9 + 16]);
                    if calculated != f.summary_crc {
                        w.finding(
                            Severity::Warning,
                            FindingCode::BadSummaryCrc,
                            Some(Place::byte(ss)),
                            format!(
                                "summary section CRC mismatch (stored {:08x}, computed {calculated:08x}); summary ignored, file read linearly",
                                f.summary_crc
                            ),
                        );
                        false
                    } else {
                        true
                    }
                } else {
                    true
                };
                if crc_ok {
                    let summary = &b[ss as usize..*fpos];
                    let mut recs = Vec::new();
                    let walked = walk_records(summary, |o, body, rel| {
                        recs.push((o, body, ss + rel as u64));
                        true
                    });
                    match walked {
                        Ok(()) => {
                            for (o, body, pos) in recs {
                                w.record(o, body, pos, true);
                            }
                            w.scan.info.summary = true;
                            data_limit = ss;
                        }
                        Err((rel, len)) => w.finding(
                            Severity::Warning,
                            FindingCode::CorruptRecord,
                            Some(Place::byte(ss + rel as u64)),
                            format!(
                                "summary record at byte {} claims {len} bytes, past the summary's end; summary ignored",
                                ss + rel as u64
                            ),
                        ),
                    }
                }
            }
        }
    }
    if !w.scan.info.summary {
        w.index_chunks.clear();
        w.finding(
            Severity::Info,
            FindingCode::NoSummary,
            None,
            "no usable summary section: the file was read linearly".to_string(),
        );
    }

    // Data section.
    let mut pos: u64 = 8;
    let mut data_end_seen = false;
    while pos < data_limit {
        let p = pos as usize;
        let remaining = data_limit - pos;
        if remaining < 9 {
            w.flush_pending();
            let kind = opcode_name(b[p]);
            if footer.is_some() {
                w.finding(
                    Severity::Warning,
                    FindingCode::CorruptRecord,
                    Some(Place::byte(pos)),
                    format!(
                        "{remaining} stray bytes at byte {pos} before the summary/footer; ignored"
                    ),
                );
            } else {
                w.scan.truncated_at = Some(b.len() as u64);
                w.finding(
                    Severity::DataLoss,
                    FindingCode::Truncated,
                    Some(Place::byte(pos)),
                    format!(
                        "file truncated at byte {} inside the header of a {kind} record starting at byte {pos}: no footer / end magic, no summary; every record before byte {pos} was read",
                        b.len()
                    ),
                );
            }
            break;
        }
        let opcode = b[p];
        let len = u64_at(b, p + 1).unwrap_or(u64::MAX);
        let avail = remaining - 9;
        if len > avail {
            w.flush_pending();
            let kind = opcode_name(opcode);
            let next = w.resync(pos, data_limit);
            match next {
                Some(next) => {
                    w.finding(
                        Severity::DataLoss,
                        FindingCode::CorruptRecord,
                        Some(Place::byte(pos)),
                        format!(
                            "corrupt {kind} record at byte {pos}: its length {len} runs past the data section (ends at byte {data_limit}); bytes {pos}..{next} skipped, reading resumes at the chunk at byte {next}"
                        ),
                    );
                    pos = next;
                    continue;
                }
                None if footer.is_some() => {
                    w.finding(
                        Severity::DataLoss,
                        FindingCode::CorruptRecord,
                        Some(Place::byte(pos)),
                        format!(
                            "corrupt {kind} record at byte {pos}: its length {len} runs past the data section (ends at byte {data_limit}); the rest of the data section (bytes {pos}..{data_limit}) cannot be read"
                        ),
                    );
                }
                None => {
                    w.scan.truncated_at = Some(b.len() as u64);
                    let have = b.len() as u64 - pos;
                    let mut text = format!(
                        "file truncated at byte {} inside a {kind} record that starts at byte {pos} ({have} of its {} bytes present): no footer / end magic, no summary",
                        b.len(),
                        len.saturating_add(9)
                    );
                    if opcode == op::CHUNK {
                        if let Some(h) = chunk_head(&b[p + 9..]) {
                            text.push_str("; the messages of the cut chunk that can still be decompressed are recovered");
                            w.push_chunk(pos, have, h, false);
                        }
                    }
                    text.push_str(&format!("; every record before byte {pos} was read"));
                    w.finding(
                        Severity::DataLoss,
                        FindingCode::Truncated,
                        Some(Place::byte(pos)),
                        text,
                    );
                }
            }
            break;
        }
        if len > opts.record_length_limit && opcode != op::CHUNK {
            w.flush_pending();
            w.finding(
                Severity::DataLoss,
                FindingCode::RecordTooLarge,
                Some(Place::byte(pos)),
                format!(
                    "{} record at byte {pos} is {len} bytes, above the record-length limit of {} bytes; skipped",
                    opcode_name(opcode),
                    opts.record_length_limit
                ),
            );
            pos += 9 + len;
            continue;
        }
        let body = &b[p + 9..p + 9 + len as usize];
        if opcode == op::DATA_END {
            // The data section is complete; what follows is the summary
            // (already read from the footer when it was usable).
            w.record(opcode, body, pos, false);
            data_end_seen = true;
            break;
        }
        if !w.record(opcode, body, pos, false) {
            break;
        }
        pos += 9 + len;
    }
    w.flush_pending();
    if footer.is_none() && w.scan.truncated_at.is_none() && data_end_seen {
        w.finding(
            Severity::Warning,
            FindingCode::Truncated,
            Some(Place::byte(b.len() as u64)),
            format!(
                "file truncated at byte {} in the summary section (no footer / end magic): every message was read, only the summary is lost",
                b.len()
            ),
        );
    } else if footer.is_none() && w.scan.truncated_at.is_none() {
        w.scan.truncated_at = Some(b.len() as u64);
        w.finding(
            Severity::DataLoss,
            FindingCode::Truncated,
            Some(Place::byte(b.len() as u64)),
            format!(
                "file ends at byte {} after a complete record, without footer / end magic: the writer did not finish (truncated at a record boundary?); every record present was read",
                b.len()
            ),
        );
    }
    // Chunks the summary knows but the walk did not reach (after a corrupt region).
    let index_chunks = std::mem::take(&mut w.index_chunks);
    for c in index_chunks {
        if w.seen_chunks.contains(&c) || c < 8 || c + 9 > b.len() as u64 {
            continue;
        }
        let p = c as usize;
        if b[p] != op::CHUNK {
            continue;
        }
        let Some(len) = u64_at(b, p + 1) else {
            continue;
        };
        if len > b.len() as u64 - c - 9 {
            continue;
        }
        if let Some(h) = chunk_head(&b[p + 9..p + 9 + len as usize]) {
            if (h.data_rel as u64).saturating_add(h.compressed_size) <= len {
                w.push_chunk(c, 9 + len, h, true);
            }
        }
    }
    w.scan.items.sort_by_key(|i| i.offset);
    if w.unknown_records > 0 {
        let n = w.unknown_records;
        w.finding(
            Severity::Warning,
            FindingCode::UnknownRecord,
            None,
            format!("{n} record(s) with reserved, unknown opcodes skipped"),
        );
    }
    if w.private_records > 0 {
        let n = w.private_records;
        w.finding(
            Severity::Info,
            FindingCode::UnknownRecord,
            None,
            format!("{n} private (application-specific) record(s) skipped"),
        );
    }
    w.scan.info.attachments = w.scan.attachments.len() as u64;
    w.scan.info.metadata_records = w.scan.metadata.iter().map(|m| m.name.clone()).collect();
    Ok(w.scan)
}

/// Receives the records of a decoded work item.
pub trait RecordVisitor {
    fn schema(&mut self, def: SchemaDef);
    fn channel(&mut self, def: ChannelDef);
    /// One message: channel id, log_time, sequence and payload.
    fn message(&mut self, channel_id: u16, log_time: u64, data: &[u8]);
}

/// A problem met while decoding one work item.
#[derive(Debug, Clone)]
pub struct ItemProblem {
    pub code: FindingCode,
    pub severity: Severity,
    /// The visitor's output must be thrown away (content not trustworthy).
    pub discard: bool,
    pub text: String,
}

/// What decoding a work item gave.
#[derive(Debug, Clone, Default)]
pub struct ItemOutcome {
    pub messages: u64,
    pub decompressed: u64,
    pub problem: Option<ItemProblem>,
}

/// Per-thread reusable decompression state.
#[derive(Default)]
pub struct Scratch {
    zstd: Option<zstd::bulk::Decompressor<'static>>,
    buf: Vec<u8>,
}

fn problem(
    code: FindingCode,
    severity: Severity,
    discard: bool,
    text: String,
) -> Option<ItemProblem> {
    Some(ItemProblem {
        code,
        severity,
        discard,
        text,
    })
}

/// Visits the records of a record buffer; returns (messages, error at offset).
fn visit_records<V: RecordVisitor>(buf: &[u8], v: &mut V) -> (u64, Option<(usize, u64)>) {
    let mut n = 0u64;
    let r = walk_records(buf, |opcode, body, _| {
        match opcode {
            op::MESSAGE => {
                if let (Some(ch), Some(t)) = (u16_at(body, 0), u64_at(body, 6)) {
                    if body.len() >= 22 {
                        v.message(ch, t, &body[22..]);
                        n += 1;
                    }
                }
            }
            op::SCHEMA => {
                if let Ok(records::Record::Schema { header, data }) =
                    mcap::parse_record(opcode, body)
                {
                    v.schema(SchemaDef {
                        id: header.id,
                        name: header.name,
                        encoding: header.encoding,
                        data: data.into_owned(),
                    });
                }
            }
            op::CHANNEL => {
                if let Ok(records::Record::Channel(c)) = mcap::parse_record(opcode, body) {
                    v.channel(ChannelDef {
                        id: c.id,
                        schema_id: c.schema_id,
                        topic: c.topic,
                        message_encoding: c.message_encoding,
                    });
                }
            }
            _ => {}
        }
        true
    });
    (n, r.err())
}

/// Decodes one work item into a visitor. Never panics on content.
pub fn decode_item<V: RecordVisitor>(
    b: &[u8],
    item: &WorkItem,
    opts: &ReadOptions,
    scratch: &mut Scratch,
    v: &mut V,
) -> ItemOutcome {
    let pos = item.offset;
    match &item.kind {
        ItemKind::Records { start, end, .. } => {
            let buf = &b[*start as usize..*end as usize];
            let (messages, err) = visit_records(buf, v);
            ItemOutcome {
                messages,
                decompressed: 0,
                problem: err.and_then(|(rel, _)| {
                    problem(
                        FindingCode::CorruptRecord,
                        Severity::DataLoss,
                        false,
                        format!("record at byte {} is corrupt; the records after it in this run are lost", start + rel as u64),
                    )
                }),
            }
        }
        ItemKind::Chunk {
            compression,
            uncompressed_size,
            crc,
            data_start,
            data_len,
            complete,
        } => {
            let data = &b[*data_start as usize..(*data_start + *data_len) as usize];
            if *uncompressed_size > opts.record_length_limit {
                return ItemOutcome {
                    problem: problem(
                        FindingCode::RecordTooLarge,
                        Severity::DataLoss,
                        true,
                        format!(
                            "chunk at byte {pos} declares {uncompressed_size} uncompressed bytes, above the record-length limit of {} bytes; chunk skipped",
                            opts.record_length_limit
                        ),
                    ),
                    ..Default::default()
                };
            }
            let content: &[u8] = match compression.as_str() {
                "" => &data[..data.len().min(*uncompressed_size as usize)],
                "zstd" | "lz4" => {
                    scratch.buf.clear();
                    let want = *uncompressed_size as usize;
                    if scratch.buf.capacity() < want {
                        scratch.buf.reserve_exact(want);
                    }
                    let res: std::io::Result<()> = if compression == "zstd" {
                        if *complete {
                            let z = match &mut scratch.zstd {
                                Some(z) => z,
                                None => match zstd::bulk::Decompressor::new() {
                                    Ok(z) => scratch.zstd.insert(z),
                                    Err(e) => {
                                        return ItemOutcome {
                                            problem: problem(
                                                FindingCode::ChunkDecompress,
                                                Severity::DataLoss,
                                                true,
                                                format!(
                                                    "chunk at byte {pos}: zstd unavailable: {e}"
                                                ),
                                            ),
                                            ..Default::default()
                                        };
                                    }
                                },
                            };
                            z.decompress_to_buffer(data, &mut scratch.buf).map(|_| ())
                        } else {
                            zstd::stream::read::Decoder::with_buffer(data).and_then(|d| {
                                d.take(want as u64)
                                    .read_to_end(&mut scratch.buf)
                                    .map(|_| ())
                            })
                        }
                    } else {
                        lz4::Decoder::new(data).and_then(|d| {
                            d.take(want as u64 + 1)
                                .read_to_end(&mut scratch.buf)
                                .map(|_| ())
                        })
                    };
                    if let Err(e) = res {
                        if *complete {
                            return ItemOutcome {
                                problem: problem(
                                    FindingCode::ChunkDecompress,
                                    Severity::DataLoss,
                                    true,
                                    format!(
                                        "chunk at byte {pos} ({compression}) cannot be decompressed ({e}); its messages are lost"
                                    ),
                                ),
                                ..Default::default()
                            };
                        }
                    }
                    &scratch.buf
                }
                other => {
                    return ItemOutcome {
                        problem: problem(
                            FindingCode::UnknownCompression,
                            Severity::DataLoss,
                            true,
                            format!(
                                "chunk at byte {pos} uses compression '{other}', which pinsight cannot decode (zstd, lz4 or none); its messages are lost"
                            ),
                        ),
                        ..Default::default()
                    };
                }
            };
            if *complete {
                if content.len() as u64 != *uncompressed_size {
                    return ItemOutcome {
                        problem: problem(
                            FindingCode::ChunkDecompress,
                            Severity::DataLoss,
                            true,
                            format!(
                                "chunk at byte {pos} decompresses to {} bytes instead of the declared {uncompressed_size}; its messages are lost",
                                content.len()
                            ),
                        ),
                        ..Default::default()
                    };
                }
                if opts.validate_crcs && *crc != 0 {
                    let calculated = crc32fast::hash(content);
                    if calculated != *crc {
                        return ItemOutcome {
                            problem: problem(
                                FindingCode::BadChunkCrc,
                                Severity::DataLoss,
                                true,
                                format!(
                                    "chunk at byte {pos}: CRC mismatch (stored {crc:08x}, computed {calculated:08x}); the chunk's messages are dropped"
                                ),
                            ),
                            ..Default::default()
                        };
                    }
                }
            }
            let (messages, err) = visit_records(content, v);
            let decompressed = content.len() as u64;
            let problem = if !*complete {
                problem(
                    FindingCode::PartialChunkRecovered,
                    Severity::DataLoss,
                    false,
                    format!(
                        "{messages} message(s) recovered from the chunk at byte {pos} cut by the truncation ({} of {uncompressed_size} bytes decompressed; CRC not verifiable)",
                        content.len()
                    ),
                )
            } else if let Some((rel, len)) = err {
                problem(
                    FindingCode::CorruptRecord,
                    Severity::DataLoss,
                    false,
                    format!(
                        "chunk at byte {pos}: record at content offset {rel} claims {len} bytes, past the chunk's end; the chunk's records after it are lost"
                    ),
                )
            } else {
                None
            };
            ItemOutcome {
                messages,
                decompressed,
                problem,
            }
        }
    }
}

/// Groups items into batches of about `opts.batch_bytes` file bytes (at most 64 items).
pub fn batches(
    items: &[WorkItem],
    opts: &ReadOptions,
    first_alone: bool,
) -> Vec<std::ops::Range<usize>> {
    let mut out = Vec::new();
    let mut i = 0;
    if first_alone && !items.is_empty() {
        out.push(0..1);
        i = 1;
    }
    while i < items.len() {
        let mut j = i;
        let mut bytes = 0u64;
        while j < items.len() && (j == i || (bytes < opts.batch_bytes && j - i < 64)) {
            bytes += items[j].len;
            j += 1;
        }
        out.push(i..j);
        i = j;
    }
    out
}

fn panic_text(e: &Box<dyn std::any::Any + Send>) -> String {
    e.downcast_ref::<&str>()
        .map(|s| s.to_string())
        .or_else(|| e.downcast_ref::<String>().cloned())
        .unwrap_or_else(|| "unknown panic".to_string())
}

/// Decodes a batch of items (in parallel when allowed); results in item order.
/// A panic inside the decoding of one item (a bug) is caught and reported as
/// that item's problem; the other items are unaffected.
pub fn decode_batch<V, F>(
    src: &Source,
    items: &[WorkItem],
    opts: &ReadOptions,
    make: F,
) -> Vec<(V, ItemOutcome)>
where
    V: RecordVisitor + Send,
    F: Fn(&WorkItem) -> V + Sync,
{
    let b = src.bytes();
    let one = |scratch: &mut Scratch, item: &WorkItem| {
        let mut v = make(item);
        let r = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
            decode_item(b, item, opts, scratch, &mut v)
        }));
        match r {
            Ok(o) => (v, o),
            Err(e) => {
                *scratch = Scratch::default();
                (
                    make(item),
                    ItemOutcome {
                        problem: problem(
                            FindingCode::InternalError,
                            Severity::DataLoss,
                            true,
                            format!(
                                "internal error while decoding the item at byte {} ({}); item skipped — please report this file",
                                item.offset,
                                panic_text(&e)
                            ),
                        ),
                        ..Default::default()
                    },
                )
            }
        }
    };
    if opts.parallel && items.len() > 1 {
        items
            .par_iter()
            .map_init(Scratch::default, |s, item| one(s, item))
            .collect()
    } else {
        let mut s = Scratch::default();
        items.iter().map(|item| one(&mut s, item)).collect()
    }
}

/// The work item that starts at `offset` (a chunk or a single message record),
/// for re-reading one item (e.g. one image) without scanning the file again.
pub fn item_at(b: &[u8], offset: u64) -> Option<WorkItem> {
    let p = usize::try_from(offset).ok()?;
    let opcode = *b.get(p)?;
    let len = u64_at(b, p + 1)?;
    let have = (b.len() as u64).checked_sub(offset + 9)?;
    if len > have {
        return None;
    }
    let body = &b[p + 9..p + 9 + len as usize];
    match opcode {
        op::CHUNK => {
            let h = chunk_head(body)?;
            if (h.data_rel as u64).saturating_add(h.compressed_size) > len {
                return None;
            }
            Some(WorkItem {
                offset,
                len: 9 + len,
                kind: ItemKind::Chunk {
                    compression: h.compression,
                    uncompressed_size: h.uncompressed_size,
                    crc: h.crc,
                    data_start: offset + 9 + h.data_rel as u64,
                    data_len: h.compressed_size,
                    complete: true,
                },
            })
        }
        op::MESSAGE => Some(WorkItem {
            offset,
            len: 9 + len,
            kind: ItemKind::Records {
                start: offset,
                end: offset + 9 + len,
                messages: 1,
            },
        }),
        _ => None,
    }
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
