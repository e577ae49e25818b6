//! The growing MCAP: each poll reads only the bytes written since the last
//! complete top-level record and hands back the complete chunks (or runs of
//! unchunked messages) found in them. Never re-reads from the start.
//!
//! What a writer leaves at the end of a growing file is not corruption:
//! - fewer than 9 bytes of a record header, or a record whose length runs
//!   past the end of the file: the rest is still being written;
//! - a chunk whose length is the `mcap` crate's placeholder (all ones,
//!   `u64::MAX`): the chunk is open and its data streams in; the length is
//!   patched when the chunk is finished;
//! - a last chunk whose header is inconsistent or whose CRC does not match:
//!   the header may be caught half-patched. It is read again at the next
//!   poll, and reported only if it is still wrong once the file has grown
//!   past it or [`SUSPECT_S`] seconds have passed.
//!
//! What is corruption (a finding, then reading resumes at the next
//! plausible chunk header, searched as the file grows): an unknown opcode,
//! a length above the record limit that is not the placeholder, a chunk
//! whose header disagrees with its record length with more data after it,
//! a chunk that fails its CRC or does not decompress after the retry.

use crate::rig::mcap_read::{ChannelDef, ItemKind, MAGIC, MetadataRecord, SchemaDef, WorkItem};
use crate::rig::report::{Finding, FindingCode, Place, Severity};
use mcap::records::{self, op};
use std::fs::File;
use std::os::unix::fs::{FileExt, MetadataExt};
use std::path::{Path, PathBuf};
use std::time::Instant;

/// Seconds a suspect last chunk is given before it is reported.
pub const SUSPECT_S: f64 = 2.0;
/// Most bytes read in one poll (a larger backlog is read over several,
/// one after the other without waiting: [`McapTail::behind`]); a single
/// record longer than this is still read whole, up to [`RECORD_LIMIT`].
///
/// Small on purpose: what one poll reads is decoded into one batch, and a
/// follower that has fallen behind (a rig replayed at full speed, an
/// interface that drew slowly) would otherwise decode minutes of signals
/// at once, and the allocator keeps such a peak for the rest of a shift.
pub const MAX_READ: u64 = 1 << 20;
/// Largest record accepted (as the loader's default limit).
pub const RECORD_LIMIT: u64 = 256 << 20;

/// One unit of decoding work read from the file, with its bytes.
#[derive(Debug, Clone)]
pub struct TailItem {
    /// The work item, its offsets relative to `bytes` (the file offset in `offset`).
    pub item: WorkItem,
    pub bytes: Vec<u8>,
    /// The item ends at the end of the file as it was read (may be re-read once).
    pub at_eof: bool,
}

/// What one poll found.
#[derive(Debug, Default)]
pub struct TailRead {
    pub items: Vec<TailItem>,
    /// New `rig` (and other) metadata records.
    pub metadata: Vec<MetadataRecord>,
    /// Top-level schema and channel records (unchunked files).
    pub schemas: Vec<SchemaDef>,
    pub channels: Vec<ChannelDef>,
    pub findings: Vec<Finding>,
    /// Bytes consumed by this poll.
    pub bytes: u64,
}

/// Where the follower is in the file.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum TailState {
    /// Waiting for the magic.
    Opening,
    Following,
    /// The data section ended (DataEnd or footer read): the writer finished.
    Finished,
}

/// A growing MCAP file followed from its last complete record.
pub struct McapTail {
    pub path: PathBuf,
    name: String,
    file: Option<File>,
    /// Device and inode of the open file (a replaced file is another one).
    ident: Option<(u64, u64)>,
    /// Offset of the next top-level record to read.
    pub pos: u64,
    pub state: TailState,
    /// Searching for the next chunk from this offset after corruption.
    resync_from: Option<u64>,
    /// The last poll left complete records for the next ([`Self::behind`]).
    behind: bool,
    /// A last chunk that failed once: (offset, when, file length then).
    suspect: Option<(u64, Instant, u64)>,
    /// Length of the file at the last poll and when it last grew.
    pub len: u64,
    pub last_growth: Instant,
    /// The path no longer names the file being read (deleted or replaced).
    pub detached: bool,
}

fn u64_at(b: &[u8], p: usize) -> Option<u64> {
    b.get(p..p.checked_add(8)?)
        .and_then(|s| s.try_into().ok())
        .map(u64::from_le_bytes)
}

fn u32_at(b: &[u8], p: usize) -> Option<u32> {
    b.get(p..p.checked_add(4)?)
        .and_then(|s| s.try_into().ok())
        .map(u32::from_le_bytes)
}

/// A chunk's header: (uncompressed size, crc, compression, offset of its
/// data in the body, compressed size); None if it does not parse.
fn chunk_head(body: &[u8]) -> Option<(u64, u32, String, usize, u64)> {
    let usize_ = u64_at(body, 16)?;
    let crc = u32_at(body, 24)?;
    let clen = u32_at(body, 28)? as usize;
    if clen > 64 {
        return None;
    }
    let comp = std::str::from_utf8(body.get(32..32 + clen)?)
        .ok()?
        .to_string();
    let csize = u64_at(body, 32 + clen)?;
    Some((usize_, crc, comp, 40 + clen, csize))
}

/// A plausible chunk record at `p` in `b`: known compression, sizes that
/// agree, all of it present.
fn plausible_chunk(b: &[u8], p: usize) -> bool {
    if b.get(p) != Some(&op::CHUNK) {
        return false;
    }
    let Some(len) = u64_at(b, p + 1) else {
        return false;
    };
    if len > RECORD_LIMIT || len > (b.len() - p - 9) as u64 {
        return false;
    }
    let body = &b[p + 9..p + 9 + len as usize];
    matches!(chunk_head(body), Some((u, _, c, rel, cs))
        if matches!(c.as_str(), "" | "zstd" | "lz4") && rel as u64 + cs == len && u <= RECORD_LIMIT)
}

impl McapTail {
    pub fn new(path: &Path) -> Self {
        McapTail {
            path: path.to_path_buf(),
            name: path.display().to_string(),
            file: None,
            ident: None,
            pos: 0,
            state: TailState::Opening,
            resync_from: None,
            behind: false,
            suspect: None,
            len: 0,
            last_growth: Instant::now(),
            detached: false,
        }
    }

    fn finding(&self, sev: Severity, code: FindingCode, at: u64, text: String) -> Finding {
        Finding::new(sev, code, &self.name, None, Some(Place::byte(at)), text)
    }

    /// Reads what was written since the last poll (at most about
    /// [`MAX_READ`] bytes of it).
    pub fn poll(&mut self) -> TailRead {
        let mut out = TailRead::default();
        self.behind = false;
        if self.state == TailState::Finished {
            return out;
        }
        if self.file.is_none() {
            match File::open(&self.path) {
                Ok(f) => {
                    self.ident = f.metadata().ok().map(|m| (m.dev(), m.ino()));
                    self.file = Some(f);
                }
                Err(_) => return out, // not there yet (or gone): the follower says which
            }
        }
        // Is the path still this file?
        let now_ident = std::fs::metadata(&self.path)
            .ok()
            .map(|m| (m.dev(), m.ino()));
        if now_ident != self.ident && !self.detached {
            self.detached = true;
            let what = if now_ident.is_none() {
                "deleted"
            } else {
                "replaced by another file"
            };
            out.findings.push(self.finding(
                Severity::Warning,
                FindingCode::Truncated,
                self.pos,
                format!(
                    "{} was {what} while being followed; reading goes on from the open file (byte {})",
                    self.name, self.pos
                ),
            ));
        }
        let Some(file) = &self.file else {
            return out;
        };
        let len = file.metadata().map(|m| m.len()).unwrap_or(self.len);
        if len > self.len {
            self.last_growth = Instant::now();
        }
        if len < self.len || len < self.pos {
            out.findings.push(self.finding(
                Severity::DataLoss,
                FindingCode::Truncated,
                len,
                format!(
                    "{} shrank from {} to {len} bytes while being followed (rewritten?); following stops here",
                    self.name, self.len
                ),
            ));
            self.len = len;
            self.state = TailState::Finished;
            return out;
        }
        self.len = len;
        if self.pos == 0 {
            if len < 8 {
                return out;
            }
            let mut m = [0u8; 8];
            if file.read_exact_at(&mut m, 0).is_err() {
                return out;
            }
            if &m != MAGIC {
                out.findings.push(self.finding(
                    Severity::Error,
                    FindingCode::CorruptRecord,
                    0,
                    format!(
                        "{} does not start with the MCAP magic: not followed",
                        self.name
                    ),
                ));
                self.state = TailState::Finished;
                return out;
            }
            self.pos = 8;
            self.state = TailState::Following;
        }
        let start = self.resync_from.unwrap_or(self.pos);
        if len <= start {
            return out;
        }
        let mut n = (len - start).min(MAX_READ);
        if n < len - start && self.resync_from.is_none() {
            // The first record whole, however long (within the limit).
            let mut head = [0u8; 9];
            if file.read_exact_at(&mut head, start).is_ok()
                && let Some(rlen) = u64_at(&head, 1)
                && rlen <= RECORD_LIMIT
            {
                n = n.max((9 + rlen).min(len - start));
            }
        }
        let n = n as usize;
        let mut buf = vec![0u8; n];
        if let Err(e) = file.read_exact_at(&mut buf, start) {
            out.findings.push(self.finding(
                Severity::Warning,
                FindingCode::Truncated,
                start,
                format!(
                    "{}: reading bytes {start}..{len} failed ({e}); tried again at the next poll",
                    self.name
                ),
            ));
            return out;
        }
        let eof = start + n as u64 == len;
        let mut p = 0usize;
        if self.resync_from.is_some() {
            match (0..n).find(|&i| plausible_chunk(&buf, i)) {
                Some(i) => {
                    let at = start + i as u64;
                    out.findings.push(self.finding(
                        Severity::Info,
                        FindingCode::CorruptRecord,
                        at,
                        format!("{}: reading resumes at the chunk at byte {at}", self.name),
                    ));
                    self.resync_from = None;
                    self.pos = at;
                    p = i;
                }
                None => {
                    // Keep the last bytes: a header may straddle the next read.
                    self.resync_from = Some(len.saturating_sub(64).max(start));
                    return out;
                }
            }
        }
        let mut run: Option<(usize, usize, u64)> = None; // unchunked messages
        let flush_run = |run: &mut Option<(usize, usize, u64)>, out: &mut TailRead, buf: &[u8]| {
            if let Some((a, b, k)) = run.take() {
                out.items.push(TailItem {
                    item: WorkItem {
                        offset: start + a as u64,
                        len: (b - a) as u64,
                        kind: ItemKind::Records {
                            start: 0,
                            end: (b - a) as u64,
                            messages: k,
                        },
                    },
                    bytes: buf[a..b].to_vec(),
                    at_eof: false,
                });
            }
        };
        loop {
            let rem = n - p;
            if rem < 9 {
                break; // a header still being written
            }
            let opcode = buf[p];
            let rlen = u64_at(&buf, p + 1).unwrap_or(u64::MAX);
            let at = start + p as u64;
            if opcode == op::CHUNK && rlen == u64::MAX {
                break; // the mcap crate's open chunk: its length comes at its end
            }
            let known = matches!(opcode, 0x01..=0x0F) || opcode >= 0x80;
            if !known || rlen > RECORD_LIMIT {
                flush_run(&mut run, &mut out, &buf);
                out.findings.push(self.finding(
                    Severity::DataLoss,
                    FindingCode::CorruptRecord,
                    at,
                    format!(
                        "{}: corrupt record at byte {at} (opcode 0x{opcode:02X}, length {rlen}); its data is lost, reading resumes at the next chunk",
                        self.name
                    ),
                ));
                self.pos = at;
                self.resync_from = Some(at + 1);
                out.bytes += p as u64;
                return out;
            }
            if rlen > (rem - 9) as u64 {
                break; // the rest of the record is still being written
            }
            let body = &buf[p + 9..p + 9 + rlen as usize];
            let end = p + 9 + rlen as usize;
            let is_last = eof && end == n;
            if opcode != op::MESSAGE {
                flush_run(&mut run, &mut out, &buf);
            }
            match opcode {
                op::MESSAGE => match &mut run {
                    Some((_, b, k)) if *b == p => {
                        *b = end;
                        *k += 1;
                    }
                    _ => {
                        flush_run(&mut run, &mut out, &buf);
                        run = Some((p, end, 1));
                    }
                },
                op::CHUNK => match chunk_head(body) {
                    Some((usz, crc, comp, rel, cs)) if rel as u64 + cs == rlen => {
                        out.items.push(TailItem {
                            item: WorkItem {
                                offset: at,
                                len: 9 + rlen,
                                kind: ItemKind::Chunk {
                                    compression: comp,
                                    uncompressed_size: usz,
                                    crc,
                                    data_start: 0,
                                    data_len: cs,
                                    complete: true,
                                },
                            },
                            bytes: body[rel..].to_vec(),
                            at_eof: is_last,
                        });
                    }
                    _ if is_last && !self.suspect_expired(at) => break,
                    _ => {
                        out.findings.push(self.finding(
                            Severity::DataLoss,
                            FindingCode::CorruptRecord,
                            at,
                            format!(
                                "{}: chunk at byte {at} has an inconsistent header; its messages are lost",
                                self.name
                            ),
                        ));
                    }
                },
                op::METADATA => {
                    if let Ok(records::Record::Metadata(m)) = mcap::parse_record(opcode, body) {
                        out.metadata.push(MetadataRecord {
                            name: m.name,
                            map: m.metadata,
                            offset: at,
                        });
                    }
                }
                op::SCHEMA => out.schemas.extend(SchemaDef::parse(body)),
                op::CHANNEL => out.channels.extend(ChannelDef::parse(body)),
                op::DATA_END | op::FOOTER => {
                    flush_run(&mut run, &mut out, &buf);
                    self.pos = start + end as u64;
                    out.bytes += end as u64;
                    self.state = TailState::Finished;
                    return out;
                }
                _ => {}
            }
            p = end;
        }
        flush_run(&mut run, &mut out, &buf);
        self.pos = start + p as u64;
        out.bytes += p as u64;
        self.behind = !eof && p > 0;
        out
    }

    /// The last poll stopped at [`MAX_READ`] with complete records still
    /// unread: the next poll should come at once, not at the next wake-up.
    pub fn behind(&self) -> bool {
        self.behind
    }

    /// Whether a suspect last chunk at `at` has had its time (and marks it
    /// suspect the first time it is seen).
    fn suspect_expired(&mut self, at: u64) -> bool {
        match self.suspect {
            Some((p, when, len0)) if p == at => {
                when.elapsed().as_secs_f64() > SUSPECT_S || self.len > len0
            }
            _ => {
                self.suspect = Some((at, Instant::now(), self.len));
                false
            }
        }
    }

    /// A chunk at the end of the file failed to decode: read it again at
    /// the next poll unless it has already had its second chance. Returns
    /// whether it will be re-read (then it must not be reported).
    pub fn retry(&mut self, item_offset: u64) -> bool {
        if self.suspect_expired(item_offset) {
            return false;
        }
        self.pos = item_offset;
        if self.state == TailState::Finished {
            self.state = TailState::Following;
        }
        true
    }

    /// The file will not be written any more (the writer moved on): what
    /// is left after the last complete record is reported.
    pub fn abandon(&mut self) -> Option<Finding> {
        if self.state == TailState::Finished {
            return None;
        }
        self.state = TailState::Finished;
        let left = self.len.saturating_sub(self.pos);
        Some(if left > 0 {
            self.finding(
                Severity::DataLoss,
                FindingCode::Truncated,
                self.pos,
                format!(
                    "{}: the writer left without finishing the file; the {left} byte(s) after byte {} (an unfinished record) are lost",
                    self.name, self.pos
                ),
            )
        } else {
            self.finding(
                Severity::Warning,
                FindingCode::Truncated,
                self.pos,
                format!(
                    "{}: the writer left without a footer after byte {}; every record was read",
                    self.name, self.pos
                ),
            )
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use mcap::records::MessageHeader;

    /// A finished MCAP written by the mcap crate: `n` messages of `size`
    /// bytes in uncompressed chunks of about `chunk` bytes.
    fn log(n: usize, size: usize, chunk: u64) -> tempfile::NamedTempFile {
        let f = tempfile::NamedTempFile::new().unwrap();
        let mut w = mcap::WriteOptions::new()
            .compression(None)
            .chunk_size(Some(chunk))
            .create(std::io::BufWriter::new(f.reopen().unwrap()))
            .unwrap();
        let ch = w
            .add_channel(0, "/blob", "application/octet-stream", &Default::default())
            .unwrap();
        for i in 0..n {
            let data = vec![(i % 251) as u8; size];
            let h = MessageHeader {
                channel_id: ch,
                sequence: i as u32,
                log_time: i as u64,
                publish_time: i as u64,
            };
            w.write_to_known_channel(&h, &data).unwrap();
        }
        w.finish().unwrap();
        drop(w);
        f
    }

    /// Polls until the tail is finished; (bytes of each poll, chunks read,
    /// whether each poll said it was behind).
    fn follow(path: &Path) -> (Vec<u64>, usize, Vec<bool>) {
        let mut t = McapTail::new(path);
        let (mut bytes, mut chunks, mut behind) = (Vec::new(), 0, Vec::new());
        for _ in 0..1000 {
            let r = t.poll();
            assert!(r.findings.is_empty(), "{:?}", r.findings);
            bytes.push(r.bytes);
            chunks += r
                .items
                .iter()
                .filter(|i| matches!(i.item.kind, ItemKind::Chunk { .. }))
                .count();
            behind.push(t.behind());
            if t.state == TailState::Finished {
                return (bytes, chunks, behind);
            }
        }
        panic!("never finished: {bytes:?}");
    }

    #[test]
    fn a_backlog_is_read_over_several_polls_each_at_most_max_read() {
        // 12 MB in chunks of ~256 kB: three polls or more.
        let f = log(12 * 1024, 1024, 256 << 10);
        let len = std::fs::metadata(f.path()).unwrap().len();
        let (bytes, chunks, behind) = follow(f.path());
        assert!(bytes.len() >= 3, "{bytes:?}");
        assert!(bytes.iter().all(|&b| b <= MAX_READ), "{bytes:?}");
        // Every poll but the last leaves work for the next and says so.
        assert!(behind[..behind.len() - 1].iter().all(|&b| b), "{behind:?}");
        assert!(!behind[behind.len() - 1]);
        // Every chunk read once: the mcap crate's own count.
        let summary = mcap::Summary::read(&std::fs::read(f.path()).unwrap())
            .unwrap()
            .unwrap();
        assert_eq!(chunks, summary.chunk_indexes.len());
        // Up to the data section's end (the summary and footer are not read).
        assert!(bytes.iter().sum::<u64>() <= len);
    }

    #[test]
    fn a_chunk_longer_than_max_read_is_read_whole() {
        // One chunk of ~6 MB (over MAX_READ), then the end.
        let f = log(6 * 1024, 1024, 64 << 20);
        let (bytes, chunks, _) = follow(f.path());
        assert_eq!(chunks, 1);
        // (The file's header records come in a poll of their own.)
        assert!(bytes.iter().any(|&b| b > MAX_READ), "{bytes:?}");
    }
}
