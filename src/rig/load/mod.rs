//! [`load`]: the single entry point that reads a rig log into plain data.

use super::channel_map::{ChannelMap, SignalKind};
use super::decode::binary::BinaryCodec;
use super::decode::{ChanCount, ChannelPlan, Decoder, IMAGE_SCHEMAS, ImageEntry, Plans, SigBuf};
use super::error::LogError;
use super::mcap_read::{
    self, ChannelDef, ContainerInfo, ItemKind, ReadOptions, SchemaDef, Scratch, Source, WorkItem,
    decode_batch,
};
use super::meta::RigMeta;
use super::report::{Finding, FindingCode, LoadReport, Place, ReadCounts, Severity, status_of};
use super::signals::{Signal, SignalStats};
use crate::progress::Progress;
use serde::Serialize;
use std::collections::{BTreeMap, BTreeSet, HashMap};
use std::path::Path;
use std::sync::Arc;

mod finish;
use finish::{finish_signals, rig_metadata};

/// How to load a log.
#[derive(Debug, Clone, Default)]
pub struct LoadOptions {
    /// Which topics/fields hold the signals (default: rig-log.md).
    pub channel_map: ChannelMap,
    /// Session overrides of `rig` metadata keys (key → value as in the record).
    pub meta_overrides: BTreeMap<String, String>,
    pub read: ReadOptions,
}

/// One MCAP channel as found in the file.
#[derive(Debug, Clone, Serialize)]
pub struct ChannelInfo {
    pub id: u16,
    pub topic: String,
    pub schema: Option<String>,
    pub schema_encoding: Option<String>,
    pub message_encoding: String,
    pub messages: u64,
    pub first_ns: Option<u64>,
    pub last_ns: Option<u64>,
    /// Messages per second over the channel's span.
    pub rate_hz: Option<f64>,
    /// What pinsight uses it for ("angle", "speed", "images", ...; empty = unused).
    pub used_as: Vec<String>,
}

/// What an attachment is.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum AttachmentKind {
    /// A TOML vision recipe (has `part_number` and `view`).
    Recipe,
    /// A TOML parameter file.
    Parameters,
    /// TOML that does not parse.
    InvalidToml,
    Other,
}

/// An attachment of the log (TOML content kept as text).
#[derive(Debug, Clone, Serialize)]
pub struct LogAttachment {
    pub name: String,
    pub media_type: String,
    pub log_time_ns: u64,
    pub create_time_ns: u64,
    pub size: u64,
    /// Byte offset of the content in the file.
    pub data_offset: u64,
    pub kind: AttachmentKind,
    /// The content, for TOML attachments up to 1 MiB.
    pub text: Option<String>,
    pub error: Option<String>,
}

/// An image on the camera topic, not decoded (see [`crate::rig::images`]).
#[derive(Debug, Clone, Serialize)]
pub struct ImageRef {
    pub topic: String,
    /// Cycle index from a `frame_id` of the form `cycle-<index>`.
    pub cycle: Option<u64>,
    pub log_time_ns: u64,
    /// The message's own `timestamp` (capture time), ns.
    pub stamp_ns: Option<u64>,
    pub frame_id: String,
    pub format: String,
    /// Size of the image bytes (estimated from the base64 length).
    pub data_len: u64,
    /// File offset of the chunk or message record that holds it.
    pub item_offset: u64,
    pub channel_id: u16,
    pub error: Option<String>,
    /// The channel's decoder when its images are protobuf or ROS 2 (to
    /// decode one again without the summary); None for JSON.
    #[serde(skip)]
    pub codec: Option<Arc<BinaryCodec>>,
}

/// The signals of a log (None = not in the file / not mapped).
#[derive(Debug, Clone, Default, Serialize)]
pub struct Signals {
    pub angle: Option<Signal>,
    pub speed: Option<Signal>,
    pub force: Option<Signal>,
    pub displacement: Option<Signal>,
    pub cycle: Option<Signal>,
}

impl Signals {
    pub fn get(&self, k: SignalKind) -> Option<&Signal> {
        match k {
            SignalKind::Angle => self.angle.as_ref(),
            SignalKind::Speed => self.speed.as_ref(),
            SignalKind::Force => self.force.as_ref(),
            SignalKind::Displacement => self.displacement.as_ref(),
            SignalKind::Cycle => self.cycle.as_ref(),
        }
    }

    fn slot(&mut self, k: SignalKind) -> &mut Option<Signal> {
        match k {
            SignalKind::Angle => &mut self.angle,
            SignalKind::Speed => &mut self.speed,
            SignalKind::Force => &mut self.force,
            SignalKind::Displacement => &mut self.displacement,
            SignalKind::Cycle => &mut self.cycle,
        }
    }

    /// Total samples held.
    pub fn total_samples(&self) -> u64 {
        SignalKind::ALL
            .into_iter()
            .filter_map(|k| self.get(k))
            .map(|s| s.len() as u64)
            .sum()
    }
}

/// A loaded rig log: plain data.
#[derive(Debug, Clone, Serialize)]
pub struct RigLog {
    pub file: String,
    pub container: ContainerInfo,
    pub meta: RigMeta,
    pub channel_map: ChannelMap,
    pub channels: Vec<ChannelInfo>,
    pub signals: Signals,
    /// Per-signal load statistics (same order as `SignalKind::ALL`, present signals only).
    pub stats: Vec<SignalStats>,
    pub attachments: Vec<LogAttachment>,
    pub images: Vec<ImageRef>,
    /// First and last log_time over all channels.
    pub log_start_ns: Option<i64>,
    pub log_end_ns: Option<i64>,
    pub report: LoadReport,
}

impl RigLog {
    pub fn stats_of(&self, k: SignalKind) -> Option<&SignalStats> {
        self.stats.iter().find(|s| s.kind == k)
    }

    /// Duration of the log (s).
    pub fn duration_s(&self) -> f64 {
        match (self.log_start_ns, self.log_end_ns) {
            (Some(a), Some(b)) => (b - a) as f64 * 1e-9,
            _ => 0.0,
        }
    }
}

/// Reads a rig log. Fails only when the file cannot be read as MCAP at all;
/// every other problem is a finding in `report` and the rest still loads.
pub fn load(path: &Path, opts: &LoadOptions, progress: &Progress) -> Result<RigLog, LogError> {
    let src = Source::open(path)?;
    load_source(&src, opts, progress)
}

/// [`load`] from a [`Source`] (file map or bytes in memory).
pub fn load_source(
    src: &Source,
    opts: &LoadOptions,
    progress: &Progress,
) -> Result<RigLog, LogError> {
    Ok(load_inner(src, opts, progress, false)?.0)
}

struct State {
    schemas: BTreeMap<u16, SchemaDef>,
    channels: BTreeMap<u16, ChannelDef>,
    plans: Arc<Plans>,
    sigs: BTreeMap<SignalKind, (String, String, SigBuf)>,
    counts: HashMap<u16, ChanCount>,
    images: Vec<ImageEntry>,
    unknown_channel_msgs: BTreeMap<u16, (u64, u64)>,
    findings: Vec<Finding>,
    read: ReadCounts,
}

/// Adds the schema and channel definitions not known yet to `known_*`
/// (the first definition of an id is used; schema id 0 means "no
/// schema"). Returns whether any was new, and the channels defined again
/// differently (the new definition with the topic the id had before), for
/// the loader's findings; the live decoder reads them the same way.
pub(crate) fn merge_defs(
    known_schemas: &mut BTreeMap<u16, SchemaDef>,
    known_channels: &mut BTreeMap<u16, ChannelDef>,
    schemas: Vec<SchemaDef>,
    channels: Vec<ChannelDef>,
) -> (bool, Vec<(ChannelDef, String)>) {
    let mut changed = false;
    let mut conflicts = Vec::new();
    for s in schemas {
        if s.id != 0 && !known_schemas.contains_key(&s.id) {
            known_schemas.insert(s.id, s);
            changed = true;
        }
    }
    for c in channels {
        match known_channels.get(&c.id) {
            None => {
                known_channels.insert(c.id, c);
                changed = true;
            }
            Some(old) if *old != c => {
                let topic = old.topic.clone();
                conflicts.push((c, topic));
            }
            Some(_) => {}
        }
    }
    (changed, conflicts)
}

impl State {
    fn add_defs(
        &mut self,
        schemas: Vec<SchemaDef>,
        channels: Vec<ChannelDef>,
        map: &ChannelMap,
        full: bool,
        file: &str,
    ) {
        let (changed, conflicts) =
            merge_defs(&mut self.schemas, &mut self.channels, schemas, channels);
        for (c, old_topic) in conflicts {
            self.findings.push(Finding::new(
                Severity::Warning,
                FindingCode::ChannelConflict,
                file,
                Some(&c.topic),
                None,
                format!(
                    "channel id {} redefined inside a chunk ('{old_topic}' before); the first definition is used",
                    c.id
                ),
            ));
        }
        if changed {
            self.plans = Arc::new(build_plans(&self.channels, &self.schemas, map, full));
        }
    }

    fn absorb(&mut self, mut dec: Decoder, stats_counts: Option<&BTreeMap<u16, u64>>) {
        for (ch, c) in dec.counts.iter().enumerate() {
            if c.messages > 0 {
                self.counts.entry(ch as u16).or_default().merge(c);
            }
        }
        let plans = dec.plans.clone();
        for (slot, b) in dec.out.sigs.iter_mut().enumerate() {
            if b.messages == 0 && b.t.is_empty() {
                continue;
            }
            let Some((ch, sp)) = plans.slots().get(slot) else {
                continue;
            };
            let entry = self.sigs.entry(sp.kind).or_insert_with(|| {
                let mut sb = SigBuf::default();
                if let Some(sc) = stats_counts {
                    let n: u64 = sc.get(ch).copied().unwrap_or(0);
                    sb.t.reserve(n.min(1 << 30) as usize);
                    sb.v.reserve(n.min(1 << 30) as usize);
                }
                (sp.src.topic.clone(), sp.src.field.clone(), sb)
            });
            entry.2.append(b);
        }
        self.images.append(&mut dec.out.images);
        for (ch, t, _) in dec.deferred.drain(..) {
            let e = self.unknown_channel_msgs.entry(ch).or_insert((0, t));
            e.0 += 1;
        }
    }
}

pub(crate) fn build_plans(
    channels: &BTreeMap<u16, ChannelDef>,
    schemas: &BTreeMap<u16, SchemaDef>,
    map: &ChannelMap,
    full_images: bool,
) -> Plans {
    let mut p = Plans::build(channels, schemas, map, full_images);
    // Images are recognised by schema too, whatever their topic.
    for c in channels.values() {
        let schema = schemas.get(&c.schema_id);
        if !matches!(p.get(c.id), Some(ChannelPlan::Ignore))
            || !schema.is_some_and(|s| IMAGE_SCHEMAS.contains(&s.name.as_str()))
        {
            continue;
        }
        if c.message_encoding == "json" {
            p.insert(c.id, ChannelPlan::Image { full: full_images });
        } else if BinaryCodec::handles(c) {
            // An image topic nobody mapped that does not compile stays ignored.
            let plan = Plans::binary_image_plan(c, schema, full_images);
            if matches!(plan, ChannelPlan::BinaryImage { .. }) {
                p.insert(c.id, plan);
            }
        }
    }
    p
}

pub(crate) fn parse_cycle(frame_id: &str) -> Option<u64> {
    frame_id.strip_prefix("cycle-")?.trim().parse().ok()
}

/// Loads a log; with `full_images` the image bytes are decoded and returned.
pub(crate) fn load_inner(
    src: &Source,
    opts: &LoadOptions,
    progress: &Progress,
    full_images: bool,
) -> Result<(RigLog, Vec<ImageEntry>), LogError> {
    let started = std::time::Instant::now();
    let file = src.name().to_string();
    let map = &opts.channel_map;
    let scan = mcap_read::scan(src, &opts.read)?;
    let mcap_read::Scan {
        info,
        schemas,
        channels,
        items,
        metadata,
        attachments,
        stats,
        findings,
        ..
    } = scan;
    let plans = Arc::new(build_plans(&channels, &schemas, map, full_images));
    let mut st = State {
        schemas,
        channels,
        plans,
        sigs: BTreeMap::new(),
        counts: HashMap::new(),
        images: Vec::new(),
        unknown_channel_msgs: BTreeMap::new(),
        findings,
        read: ReadCounts {
            chunks: info.chunks,
            ..Default::default()
        },
    };
    let stats_counts = stats.as_ref().map(|s| s.channel_message_counts.clone());

    // Decode the work items batch by batch.
    progress.set_total(items.iter().map(|i| i.len).sum());
    progress.set_message("reading log");
    let first_alone = st.channels.is_empty();
    let mut scratch = Scratch::default();
    let b = src.bytes();
    for range in mcap_read::batches(&items, &opts.read, first_alone) {
        if progress.is_cancelled() {
            let at = items[range.start].offset;
            st.findings.push(Finding::new(
                Severity::DataLoss,
                FindingCode::Cancelled,
                &file,
                None,
                Some(Place::byte(at)),
                format!("loading cancelled by the user at byte {at}; what was read before is kept"),
            ));
            break;
        }
        let batch = &items[range.clone()];
        let plans = st.plans.clone();
        let results = decode_batch(src, batch, &opts.read, |item: &WorkItem| {
            Decoder::new(plans.clone(), item.offset)
        });
        for (item, (mut dec, mut out)) in batch.iter().zip(results) {
            let new_s = std::mem::take(&mut dec.new_schemas);
            let new_c = std::mem::take(&mut dec.new_channels);
            st.add_defs(new_s, new_c, map, full_images, &file);
            // Messages on channels defined inside this very item (or an item
            // decoded alongside it): decode the item again with the new plans,
            // which keeps the file order exact.
            if !dec.deferred.is_empty()
                && dec.deferred.iter().any(|(c, _, _)| st.plans.contains(*c))
            {
                let mut again = Decoder::new(st.plans.clone(), item.offset);
                out = mcap_read::decode_item(b, item, &opts.read, &mut scratch, &mut again);
                dec = again;
                dec.new_schemas.clear();
                dec.new_channels.clear();
            }
            progress.inc(item.len);
            st.read.bytes_read += item.len;
            if let Some(p) = &out.problem {
                st.findings.push(Finding::new(
                    p.severity,
                    p.code,
                    &file,
                    None,
                    Some(Place::byte(item.offset)),
                    &p.text,
                ));
                if p.discard {
                    if matches!(item.kind, ItemKind::Chunk { .. }) {
                        st.read.chunks_failed += 1;
                    }
                    continue;
                }
            }
            if matches!(item.kind, ItemKind::Chunk { .. }) {
                st.read.chunks_read += 1;
            }
            st.read.messages += out.messages;
            st.read.bytes_decompressed += out.decompressed;
            st.absorb(dec, stats_counts.as_ref());
        }
        if let (Some(first), Some(last)) = (batch.first(), batch.last()) {
            src.release(first.offset, last.offset + last.len - first.offset);
        }
    }

    let meta = rig_metadata(&metadata, opts, &file, &mut st.findings);

    // Log span over all channels.
    let mut log_start: Option<i64> = None;
    let mut log_end: Option<i64> = None;
    for c in st.counts.values().filter(|c| c.messages > 0) {
        if let (Ok(a), Ok(b)) = (i64::try_from(c.first), i64::try_from(c.last)) {
            log_start = Some(log_start.map_or(a, |x| x.min(a)));
            log_end = Some(log_end.map_or(b, |x| x.max(b)));
        }
    }
    let span = log_start.zip(log_end);

    let (sigs, sig_stats) = finish_signals(&mut st, &file, span);

    // Channels.
    let mut chan_infos = Vec::new();
    for c in st.channels.values() {
        let cnt = st.counts.get(&c.id).copied().unwrap_or_default();
        let schema = st.schemas.get(&c.schema_id);
        let mut used_as: Vec<String> = map
            .signals_on(&c.topic)
            .iter()
            .map(|(k, _)| k.name().to_string())
            .collect();
        if matches!(
            st.plans.get(c.id),
            Some(ChannelPlan::Image { .. } | ChannelPlan::BinaryImage { .. })
        ) {
            used_as.push("images".into());
        }
        let span_s = (cnt.last.saturating_sub(cnt.first)) as f64 * 1e-9;
        chan_infos.push(ChannelInfo {
            id: c.id,
            topic: c.topic.clone(),
            schema: schema.map(|s| s.name.clone()),
            schema_encoding: schema.map(|s| s.encoding.clone()),
            message_encoding: c.message_encoding.clone(),
            messages: cnt.messages,
            first_ns: (cnt.messages > 0).then_some(cnt.first),
            last_ns: (cnt.messages > 0).then_some(cnt.last),
            rate_hz: (cnt.messages > 1 && span_s > 0.0).then(|| (cnt.messages - 1) as f64 / span_s),
            used_as,
        });
    }

    // Mapped signals without a channel, undecodable channels.
    let topics: BTreeSet<&str> = st.channels.values().map(|c| c.topic.as_str()).collect();
    let listing = if topics.is_empty() {
        "none".to_string()
    } else {
        topics.iter().copied().collect::<Vec<_>>().join(", ")
    };
    for kind in SignalKind::ALL {
        let src_opt = map.get(kind);
        let present = sigs.get(kind).is_some_and(|s| !s.is_empty());
        match src_opt {
            Some(s) if !topics.contains(s.topic.as_str()) => {
                let (sev, code, text) = match kind {
                    SignalKind::Speed if map.is_default() => (
                        Severity::Info,
                        FindingCode::DerivedSignal,
                        "no speed channel: motor speed is derived from the crank angle".to_string(),
                    ),
                    SignalKind::Cycle if map.is_default() => (
                        Severity::Info,
                        FindingCode::DerivedSignal,
                        "no cycle topic: cycles are taken from the crank angle (top dead centre at π)".to_string(),
                    ),
                    _ => (
                        Severity::Warning,
                        FindingCode::MissingChannel,
                        format!(
                            "channel missing: no topic '{}' in the file, so {} is unavailable; topics in the file: {listing}",
                            s.topic,
                            kind.name()
                        ),
                    ),
                };
                let label = format!("{} ({})", s.topic, kind.name());
                st.findings
                    .push(Finding::new(sev, code, &file, Some(&label), None, text));
            }
            Some(s) if !present => {
                let undecodable = st.channels.values().find_map(|c| match st.plans.get(c.id) {
                    Some(ChannelPlan::Undecodable(why)) if c.topic == s.topic => Some(why),
                    _ => None,
                });
                if let Some(why) = undecodable {
                    let label = format!("{} ({})", s.topic, kind.name());
                    st.findings.push(Finding::new(
                        Severity::Warning,
                        FindingCode::UnknownEncoding,
                        &file,
                        Some(&label),
                        None,
                        format!("{why}; {} is unavailable", kind.name()),
                    ));
                }
            }
            None => {
                let derived = match kind {
                    SignalKind::Speed => {
                        Some("no speed channel: motor speed is derived from the crank angle")
                    }
                    SignalKind::Cycle => Some(
                        "no cycle topic: cycles are taken from the crank angle (top dead centre at π)",
                    ),
                    _ => None,
                };
                if let Some(how) = derived {
                    st.findings.push(Finding::new(
                        Severity::Info,
                        FindingCode::DerivedSignal,
                        &file,
                        None,
                        None,
                        format!("the channel map ({}) has {how}", map.source),
                    ));
                }
            }
            _ => {}
        }
    }
    let unused: Vec<String> = chan_infos
        .iter()
        .filter(|c| c.used_as.is_empty())
        .map(|c| format!("{} ({} messages)", c.topic, c.messages))
        .collect();
    if !unused.is_empty() {
        st.findings.push(Finding::new(
            Severity::Info,
            FindingCode::UnusedChannel,
            &file,
            None,
            None,
            format!(
                "channels not used by the channel map ({}): {}",
                map.source,
                unused.join(", ")
            ),
        ));
    }
    for (ch, (n, t)) in &st.unknown_channel_msgs {
        st.findings.push(Finding::new(
            Severity::Warning,
            FindingCode::UnknownChannel,
            &file,
            None,
            Some(Place::time(*t as i64)),
            format!("{n} message(s) on channel id {ch}, which is not defined before them; skipped (first at log_time {t})"),
        ));
    }

    // Summary statistics versus what was read (only when nothing was lost).
    let lost = st.findings.iter().any(|f| f.severity >= Severity::DataLoss);
    if let (Some(s), false) = (&stats, lost) {
        for (ch, &n) in &s.channel_message_counts {
            let got = st.counts.get(ch).map(|c| c.messages).unwrap_or(0);
            if got != n {
                let topic = st
                    .channels
                    .get(ch)
                    .map(|c| c.topic.clone())
                    .unwrap_or_else(|| format!("channel {ch}"));
                st.findings.push(Finding::new(
                    Severity::Warning,
                    FindingCode::SummaryMismatch,
                    &file,
                    Some(&topic),
                    None,
                    format!("the summary's statistics count {n} messages, {got} were read"),
                ));
            }
        }
    }

    // Attachments.
    let mut atts = Vec::new();
    for a in &attachments {
        let is_toml = a.media_type == "application/toml" || a.name.ends_with(".toml");
        let mut att = LogAttachment {
            name: a.name.clone(),
            media_type: a.media_type.clone(),
            log_time_ns: a.log_time,
            create_time_ns: a.create_time,
            size: a.data_len,
            data_offset: a.data_offset,
            kind: AttachmentKind::Other,
            text: None,
            error: None,
        };
        if is_toml && a.data_len <= (1 << 20) {
            let bytes = &b[a.data_offset as usize..(a.data_offset + a.data_len) as usize];
            match std::str::from_utf8(bytes) {
                Ok(text) => {
                    match text.parse::<toml::Table>() {
                        Ok(t) => {
                            att.kind = if t.contains_key("part_number") && t.contains_key("view") {
                                AttachmentKind::Recipe
                            } else {
                                AttachmentKind::Parameters
                            };
                        }
                        Err(e) => {
                            att.kind = AttachmentKind::InvalidToml;
                            att.error = Some(e.message().to_string());
                        }
                    }
                    att.text = Some(text.to_string());
                }
                Err(_) => {
                    att.kind = AttachmentKind::InvalidToml;
                    att.error = Some("not UTF-8".into());
                }
            }
        }
        let (sev, what) = match att.kind {
            AttachmentKind::Recipe => (Severity::Info, "vision recipe".to_string()),
            AttachmentKind::Parameters => (Severity::Info, "parameter file".to_string()),
            AttachmentKind::InvalidToml => (
                Severity::Warning,
                format!(
                    "TOML that does not parse: {}",
                    att.error.clone().unwrap_or_default()
                ),
            ),
            AttachmentKind::Other => (Severity::Info, "not used".to_string()),
        };
        st.findings.push(Finding::new(
            sev,
            FindingCode::Attachment,
            &file,
            None,
            Some(Place::byte(a.offset)),
            format!(
                "attachment '{}' ({}, {} bytes): {what}",
                att.name, att.media_type, att.size
            ),
        ));
        atts.push(att);
    }

    // Images.
    st.images.sort_by_key(|e| e.log_time);
    let mut images = Vec::new();
    let mut formats: BTreeMap<String, u64> = BTreeMap::new();
    let mut bad = 0;
    for e in &st.images {
        let topic = st
            .channels
            .get(&e.channel)
            .map(|c| c.topic.clone())
            .unwrap_or_default();
        *formats.entry(e.format.clone()).or_default() += 1;
        if let Some(err) = &e.error {
            bad += 1;
            if bad <= 20 {
                st.findings.push(Finding::new(
                    Severity::Warning,
                    FindingCode::Images,
                    &file,
                    Some(&topic),
                    Some(Place::time(e.log_time as i64)),
                    format!(
                        "image at log_time {} (frame_id '{}') unusable: {err}",
                        e.log_time, e.frame_id
                    ),
                ));
            }
        }
        images.push(ImageRef {
            topic,
            cycle: parse_cycle(&e.frame_id),
            log_time_ns: e.log_time,
            stamp_ns: e.stamp_ns,
            frame_id: e.frame_id.clone(),
            format: e.format.clone(),
            data_len: e.data_len,
            item_offset: e.item_offset,
            channel_id: e.channel,
            error: e.error.clone(),
            codec: match st.plans.get(e.channel) {
                Some(ChannelPlan::BinaryImage { codec, .. }) => Some(codec.clone()),
                _ => None,
            },
        });
    }
    if !images.is_empty() {
        let fm = formats
            .iter()
            .map(|(k, v)| format!("{k}: {v}"))
            .collect::<Vec<_>>()
            .join(", ");
        let topics: BTreeSet<&str> = images.iter().map(|i| i.topic.as_str()).collect();
        st.findings.push(Finding::new(
            Severity::Info,
            FindingCode::Images,
            &file,
            Some(&topics.into_iter().collect::<Vec<_>>().join(", ")),
            None,
            format!(
                "{} image(s) ({fm}); {} carry a cycle index in frame_id",
                images.len(),
                images.iter().filter(|i| i.cycle.is_some()).count()
            ),
        ));
    }

    // Nothing usable at all?
    let any_signal = sigs.total_samples() > 0;
    if !any_signal && images.is_empty() {
        st.findings.push(Finding::new(
            Severity::Error,
            FindingCode::MissingChannel,
            &file,
            None,
            None,
            format!(
                "no samples of any mapped signal (channel map: {}); topics in the file: {listing}. A rig that names its channels differently needs a channel map (--channels MAP.toml)",
                map.source
            ),
        ));
    }

    let status = status_of(&st.findings);
    let report = LoadReport {
        file: file.clone(),
        status,
        findings: st.findings,
        counts: st.read,
        elapsed_s: started.elapsed().as_secs_f64(),
    };
    let log = RigLog {
        file,
        container: info,
        meta,
        channel_map: map.clone(),
        channels: chan_infos,
        signals: sigs,
        stats: sig_stats,
        attachments: atts,
        images,
        log_start_ns: log_start,
        log_end_ns: log_end,
        report,
    };
    Ok((log, st.images))
}
