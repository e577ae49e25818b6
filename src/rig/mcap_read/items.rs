//! Pass 2: decoding the work items (chunks and runs of messages) in
//! parallel, bounded batches; a bad chunk is dropped and reported.

use super::*;
use crate::rig::report::{FindingCode, Severity};
use mcap::records::op;
use rayon::prelude::*;
use std::io::Read;

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

impl ItemOutcome {
    /// An item whose messages are lost, with the reason.
    fn lost(code: FindingCode, text: String) -> Self {
        ItemOutcome {
            problem: problem(code, Severity::DataLoss, true, text),
            ..Default::default()
        }
    }
}

/// Per-thread reusable decompression state.
#[derive(Default)]
pub struct Scratch {
    zstd: Option<zstd::bulk::Decompressor<'static>>,
    buf: Vec<u8>,
}

pub(super) fn problem(
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
pub(super) fn visit_records<V: RecordVisitor>(
    buf: &[u8],
    v: &mut V,
) -> (u64, Option<(usize, u64)>) {
    let mut n = 0u64;
    let r = walk_records(buf, |opcode, body, _| {
        match opcode {
            op::MESSAGE => {
                if let (Some(ch), Some(t)) = (u16_at(body, 0), u64_at(body, 6))
                    && body.len() >= 22
                {
                    v.message(ch, t, &body[22..]);
                    n += 1;
                }
            }
            op::SCHEMA => {
                if let Some(s) = SchemaDef::parse(body) {
                    v.schema(s);
                }
            }
            op::CHANNEL => {
                if let Some(c) = ChannelDef::parse(body) {
                    v.channel(c);
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
                return ItemOutcome::lost(
                    FindingCode::RecordTooLarge,
                    format!(
                        "chunk at byte {pos} declares {uncompressed_size} uncompressed bytes, above the record-length limit of {} bytes; chunk skipped",
                        opts.record_length_limit
                    ),
                );
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
                                        return ItemOutcome::lost(
                                            FindingCode::ChunkDecompress,
                                            format!("chunk at byte {pos}: zstd unavailable: {e}"),
                                        );
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
                    if let Err(e) = res
                        && *complete
                    {
                        return ItemOutcome::lost(
                            FindingCode::ChunkDecompress,
                            format!(
                                "chunk at byte {pos} ({compression}) cannot be decompressed ({e}); its messages are lost"
                            ),
                        );
                    }
                    &scratch.buf
                }
                other => {
                    return ItemOutcome::lost(
                        FindingCode::UnknownCompression,
                        format!(
                            "chunk at byte {pos} uses compression '{other}', which pinsight cannot decode (zstd, lz4 or none); its messages are lost"
                        ),
                    );
                }
            };
            if *complete {
                if content.len() as u64 != *uncompressed_size {
                    return ItemOutcome::lost(
                        FindingCode::ChunkDecompress,
                        format!(
                            "chunk at byte {pos} decompresses to {} bytes instead of the declared {uncompressed_size}; its messages are lost",
                            content.len()
                        ),
                    );
                }
                if opts.validate_crcs && *crc != 0 {
                    let calculated = crc32fast::hash(content);
                    if calculated != *crc {
                        return ItemOutcome::lost(
                            FindingCode::BadChunkCrc,
                            format!(
                                "chunk at byte {pos}: CRC mismatch (stored {crc:08x}, computed {calculated:08x}); the chunk's messages are dropped"
                            ),
                        );
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

pub(super) fn panic_text(e: &Box<dyn std::any::Any + Send>) -> String {
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
                    ItemOutcome::lost(
                        FindingCode::InternalError,
                        format!(
                            "internal error while decoding the item at byte {} ({}); item skipped — please report this file",
                            item.offset,
                            panic_text(&e)
                        ),
                    ),
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
