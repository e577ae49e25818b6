//! Pass 1: the sequential walk over the top-level records and the summary
//! section, re-synchronising on the next chunk after a bad length.

use super::*;
use crate::rig::error::LogError;
use crate::rig::report::{Finding, FindingCode, Place, Severity};
use mcap::records::{self, op};

/// Walks the records of `buf` (top-level section or decompressed chunk content).
/// Calls `f(opcode, body, offset_of_record_in_buf)`; stops at the first record
/// whose length runs past the buffer and returns its offset and declared length.
pub(super) fn walk_records<'a>(
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

pub(super) struct Walker<'a> {
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
        let (id, name) = (def.id, def.name.clone());
        let conflict = keep_first(&mut self.scan.schemas, id, def, |d| d.name.clone());
        self.redefined("schema", id, pos, conflict, &name);
    }

    fn add_channel(&mut self, def: ChannelDef, pos: u64) {
        let (id, topic) = (def.id, def.topic.clone());
        let conflict = keep_first(&mut self.scan.channels, id, def, |d| d.topic.clone());
        self.redefined("channel", id, pos, conflict, &topic);
    }

    /// Warns of a schema or channel id defined again differently (`old`
    /// names the first definition, which is kept).
    fn redefined(&mut self, what: &str, id: u16, pos: u64, old: Option<String>, new: &str) {
        if let Some(old) = old {
            self.finding(
                Severity::Warning,
                FindingCode::ChannelConflict,
                Some(Place::byte(pos)),
                format!(
                    "{what} id {id} redefined at byte {pos} ('{old}' vs '{new}'); the first definition is used"
                ),
            );
        }
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
            op::SCHEMA => match SchemaDef::parse(body) {
                Some(s) => self.add_schema(s, pos),
                None => self.corrupt_small(opcode, pos),
            },
            op::CHANNEL => match ChannelDef::parse(body) {
                Some(c) => self.add_channel(c, pos),
                None => self.corrupt_small(opcode, pos),
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
                if !self.scan.info.chunked && self.opts.validate_crcs
                    && let Some(saved) = u32_at(body, 0) {
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
                    if opcode == op::CHUNK
                        && let Some(h) = chunk_head(&b[p + 9..])
                    {
                        text.push_str("; the messages of the cut chunk that can still be decompressed are recovered");
                        w.push_chunk(pos, have, h, false);
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
        if let Some(h) = chunk_head(&b[p + 9..p + 9 + len as usize])
            && (h.data_rel as u64).saturating_add(h.compressed_size) <= len
        {
            w.push_chunk(c, 9 + len, h, true);
        }
    }
    w.scan.items.sort_by_key(|i| i.offset);
    for (n, severity, what) in [
        (
            w.unknown_records,
            Severity::Warning,
            "record(s) with reserved, unknown opcodes skipped",
        ),
        (
            w.private_records,
            Severity::Info,
            "private (application-specific) record(s) skipped",
        ),
    ] {
        if n > 0 {
            w.finding(
                severity,
                FindingCode::UnknownRecord,
                None,
                format!("{n} {what}"),
            );
        }
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

/// Records `def` under `id` unless the id is already defined: the first
/// definition wins. Returns the first one's name (by `name`) when the new
/// one differs from it.
fn keep_first<V: PartialEq>(
    map: &mut std::collections::BTreeMap<u16, V>,
    id: u16,
    def: V,
    name: impl Fn(&V) -> String,
) -> Option<String> {
    match map.get(&id) {
        Some(old) if *old != def => Some(name(old)),
        Some(_) => None,
        None => {
            map.insert(id, def);
            None
        }
    }
}
