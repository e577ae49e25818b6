//! Decoding the chunks a [`super::tail::McapTail`] read: the rig loader's
//! own decoder ([`crate::rig::decode::Decoder`]) with the plans of the
//! channels seen so far (schemas and channels are defined inside the first
//! chunks and stay known for the rest of the file), turned into samples per
//! signal and camera images.

use super::tail::TailItem;
use crate::rig::channel_map::{ChannelMap, SignalKind};
use crate::rig::decode::{Decoder, Plans};
use crate::rig::mcap_read::{ChannelDef, ReadOptions, SchemaDef, Scratch, decode_item};
use crate::rig::report::{FindingCode, Severity};
use std::collections::BTreeMap;
use std::sync::Arc;

/// Samples of one signal in file order (log_time ns, value in pinsight's unit).
pub type Samples = Vec<(i64, f64)>;

/// A camera image found on a log's image topic.
#[derive(Debug, Clone)]
pub struct LogImage {
    pub log_time_ns: u64,
    pub frame_id: String,
    pub cycle: Option<u64>,
    pub data: Option<Vec<u8>>,
    pub error: Option<String>,
}

/// What one item gave.
#[derive(Debug, Default)]
pub struct Decoded {
    pub samples: BTreeMap<SignalKind, Samples>,
    pub images: Vec<LogImage>,
    pub messages: u64,
    /// The item could not be decoded (code, severity, text).
    pub problem: Option<(FindingCode, Severity, String)>,
    /// The decoder's output was thrown away (the problem is data loss).
    pub discarded: bool,
}

/// The decoding state of one followed log.
pub struct LiveDecoder {
    map: ChannelMap,
    schemas: BTreeMap<u16, SchemaDef>,
    channels: BTreeMap<u16, ChannelDef>,
    plans: Arc<Plans>,
    scratch: Scratch,
    opts: ReadOptions,
}

impl LiveDecoder {
    pub fn new(map: ChannelMap) -> Self {
        let plans = Arc::new(Plans::build(&BTreeMap::new(), &BTreeMap::new(), &map, true));
        LiveDecoder {
            map,
            schemas: BTreeMap::new(),
            channels: BTreeMap::new(),
            plans,
            scratch: Scratch::default(),
            opts: ReadOptions::default(),
        }
    }

    /// Schemas and channels defined outside chunks (unchunked files).
    pub fn add_defs(&mut self, schemas: Vec<SchemaDef>, channels: Vec<ChannelDef>) -> bool {
        // (A channel defined again differently keeps its first definition.)
        let (changed, _) =
            crate::rig::load::merge_defs(&mut self.schemas, &mut self.channels, schemas, channels);
        if changed {
            self.plans = Arc::new(crate::rig::load::build_plans(
                &self.channels,
                &self.schemas,
                &self.map,
                true,
            ));
        }
        changed
    }

    /// Topics of the channels seen so far.
    pub fn topics(&self) -> Vec<String> {
        self.channels.values().map(|c| c.topic.clone()).collect()
    }

    /// Decodes one item.
    pub fn decode(&mut self, it: &TailItem) -> Decoded {
        let mut dec = Decoder::new(self.plans.clone(), it.item.offset);
        let mut out = decode_item(&it.bytes, &it.item, &self.opts, &mut self.scratch, &mut dec);
        let ns = std::mem::take(&mut dec.new_schemas);
        let nc = std::mem::take(&mut dec.new_channels);
        if self.add_defs(ns, nc) && dec.deferred.iter().any(|(c, _, _)| self.plans.contains(*c)) {
            // Messages on channels this very item defines: decode it again.
            dec = Decoder::new(self.plans.clone(), it.item.offset);
            out = decode_item(&it.bytes, &it.item, &self.opts, &mut self.scratch, &mut dec);
        }
        let mut d = Decoded {
            messages: out.messages,
            ..Default::default()
        };
        if let Some(p) = out.problem {
            d.problem = Some((p.code, p.severity, p.text));
            if p.discard {
                d.discarded = true;
                return d;
            }
        }
        let plans = dec.plans.clone();
        for (slot, b) in dec.out.sigs.iter().enumerate() {
            if b.t.is_empty() {
                continue;
            }
            let Some((_, sp)) = plans.slots().get(slot) else {
                continue;
            };
            d.samples
                .entry(sp.kind)
                .or_default()
                .extend(b.t.iter().copied().zip(b.v.iter().copied()));
        }
        for img in dec.out.images.drain(..) {
            d.images.push(LogImage {
                log_time_ns: img.log_time,
                cycle: crate::rig::load::parse_cycle(&img.frame_id),
                frame_id: img.frame_id,
                data: img.data,
                error: img.error,
            });
        }
        d
    }
}
