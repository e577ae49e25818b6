//! Message decoding: which channel carries what ([`Plans`]) and the visitor
//! that turns JSON messages into samples ([`Decoder`]).
//!
//! Scalar messages carry one sample per message in a JSON field. Block
//! messages (`{"t0_ns", "dt_ns", "values": [...]}`, field name in the
//! schema's `title`) carry many; sample i is at `t0_ns + i·dt_ns`. Whether a
//! channel holds blocks is decided from its JSON schema (properties
//! `t0_ns`/`dt_ns`/`values`), or per message when there is no schema. A
//! block is never read as a scalar (it has no scalar field: it is counted
//! as a wrong-shape message if its channel's schema says scalar), and a block
//! whose schema title names another field than the map's is rejected, not
//! guessed.
//!
//! Invalid samples (`NaN`, `null`, `±Infinity`, a string...) are kept in
//! the stream as NaN so that time-stream checks (duplicates, gaps) see the
//! message, and counted by kind; they are removed from the final arrays.

pub mod binary;
mod buffers;
mod plan;

pub use buffers::*;
pub use plan::*;

use super::json::{self, Val};
use super::mcap_read::{ChannelDef, RecordVisitor, SchemaDef};
use binary::BinaryCodec;
use std::sync::Arc;

/// The visitor: decodes the messages of one work item.
pub struct Decoder {
    pub plans: Arc<Plans>,
    pub out: DecodeOut,
    /// Message counters indexed by channel id.
    pub counts: Vec<ChanCount>,
    pub new_schemas: Vec<SchemaDef>,
    pub new_channels: Vec<ChannelDef>,
    /// Messages on channels the plans do not know (yet): (channel, log_time, payload).
    pub deferred: Vec<(u16, u64, Vec<u8>)>,
}

/// A learned message layout of one channel (see [`json::Layout`]).
#[derive(Debug, Clone)]
struct LayoutEntry {
    /// The channel's first signal slot (identifies the channel).
    base: usize,
    layout: json::Layout,
    /// For each signal of the plan, the position of its value in the layout.
    field_pos: Vec<Option<usize>>,
}

/// What a [`Decoder`] produced.
#[derive(Debug, Default)]
pub struct DecodeOut {
    /// Signal buffers, one per slot of the plans ([`Plans::slots`]).
    pub sigs: Vec<SigBuf>,
    layouts: Vec<LayoutEntry>,
    pub images: Vec<ImageEntry>,
    pub item_offset: u64,
    /// Scratch of the binary (protobuf, CDR) decoders.
    scratch: binary::Slots,
}

impl Decoder {
    pub fn new(plans: Arc<Plans>, item_offset: u64) -> Self {
        Decoder {
            out: DecodeOut {
                item_offset,
                sigs: vec![SigBuf::default(); plans.slots.len()],
                ..Default::default()
            },
            counts: vec![ChanCount::default(); plans.channel_bound()],
            plans,
            new_schemas: Vec::new(),
            new_channels: Vec::new(),
            deferred: Vec::new(),
        }
    }
}

impl DecodeOut {
    #[inline]
    fn sig(&mut self, base: usize, i: usize) -> &mut SigBuf {
        &mut self.sigs[base + i]
    }

    #[allow(clippy::too_many_arguments)]
    fn decode_signals(
        &mut self,
        base: usize,
        log_time: u64,
        data: &[u8],
        shape: Shape,
        title: Option<&str>,
        signals: &[SignalPlan],
    ) {
        let t = match i64::try_from(log_time) {
            Ok(t) => t,
            Err(_) => {
                for i in 0..signals.len() {
                    self.sig(base, i).time_out_of_range += 1;
                }
                return;
            }
        };
        // Fast path: the channel's learned layout (numbers only).
        if shape != Shape::Block
            && let Some(e) = self.layouts.iter().find(|e| e.base == base)
        {
            let mut vals: [&[u8]; 8] = [&[]; 8];
            if e.layout.matches(data, &mut vals) {
                for (i, s) in signals.iter().enumerate() {
                    let b = &mut self.sigs[base + i];
                    b.messages += 1;
                    match e.field_pos.get(i).copied().flatten() {
                        Some(k) => b.push(t, Val::Num(vals[k]).num(), &s.src),
                        None => {
                            b.missing_field += 1;
                            b.missing_field_first.get_or_insert(t);
                        }
                    }
                }
                return;
            }
        }
        // One pass over the object: the mapped fields and the block fields.
        let mut found: [Option<Val>; 5] = [None; 5];
        let mut t0 = None;
        let mut dt = None;
        let mut values = None;
        let res = json::for_each_member(data, |k, v| {
            let mut hit = false;
            for (i, s) in signals.iter().enumerate().take(5) {
                if json::key_is(k, &s.src.field) {
                    found[i] = Some(v);
                    hit = true;
                }
            }
            // Block keys: 5 or 6 bytes long (a cheap filter before comparing).
            if !hit && (k.len() == 5 || k.len() == 6 || k.contains(&b'\\')) {
                if json::key_is(k, "t0_ns") {
                    t0 = Some(v);
                } else if json::key_is(k, "dt_ns") {
                    dt = Some(v);
                } else if json::key_is(k, "values") {
                    values = Some(v);
                }
            }
        });
        if let Err(e) = res {
            for i in 0..signals.len() {
                let b = self.sig(base, i);
                b.messages += 1;
                b.malformed += 1;
                if b.malformed_first.is_none() {
                    b.malformed_first = Some((t, e.to_string()));
                }
            }
            return;
        }
        let looks_block = values.is_some() && (t0.is_some() || dt.is_some());
        if !looks_block
            && shape != Shape::Block
            && !self.layouts.iter().any(|e| e.base == base)
            && let Some((layout, keys)) = json::Layout::learn(data).filter(|(l, _)| l.values() <= 8)
        {
            // The last occurrence of a key wins, as in the scan above.
            let field_pos = signals
                .iter()
                .map(|s| keys.iter().rposition(|k| json::key_is(k, &s.src.field)))
                .collect();
            self.layouts.push(LayoutEntry {
                base,
                layout,
                field_pos,
            });
        }
        let is_block = match shape {
            Shape::Block => true,
            Shape::Scalar => false,
            Shape::Auto => looks_block && found.iter().all(Option::is_none),
        };
        for (i, s) in signals.iter().enumerate() {
            let src = &s.src;
            let b = &mut self.sigs[base + i];
            b.messages += 1;
            if is_block {
                // A block topic names its field in the schema title.
                if let Some(title) = title
                    && title != src.field
                {
                    b.wrong_shape_at(
                        t,
                        &format!(
                            "block schema title is '{title}', the map expects field '{}'",
                            src.field
                        ),
                    );
                    continue;
                }
                let (Some(t0v), Some(dtv), Some(Val::Array(arr))) = (t0, dt, values) else {
                    b.wrong_shape_at(t, "block message without t0_ns, dt_ns and a values array");
                    continue;
                };
                let (Some(t0n), Some(dtn)) = (t0v.u64(), dtv.u64()) else {
                    b.wrong_shape_at(t, "block t0_ns / dt_ns are not unsigned integers");
                    continue;
                };
                let Some((t0i, dti)) = b.block_times(t, log_time, t0n, dtn) else {
                    continue;
                };
                let mut k: i64 = 0;
                let r = json::for_each_element(arr, |v| {
                    let ts = t0i.saturating_add(dti.saturating_mul(k));
                    b.push(ts, v.num(), src);
                    k += 1;
                });
                if let Err(e) = r {
                    b.malformed += 1;
                    if b.malformed_first.is_none() {
                        b.malformed_first = Some((t, format!("values array: {e}")));
                    }
                }
            } else {
                match found.get(i).copied().flatten() {
                    Some(v) => b.push(t, v.num(), src),
                    None if looks_block => {
                        b.wrong_shape += 1;
                        if b.wrong_shape_first.is_none() {
                            b.wrong_shape_first = Some((
                                t,
                                "a block message (t0_ns, dt_ns, values) on a channel whose schema says one sample per message; not read as a scalar".into(),
                            ));
                        }
                    }
                    None => {
                        b.missing_field += 1;
                        b.missing_field_first.get_or_insert(t);
                    }
                }
            }
        }
    }

    /// The signals of one protobuf or CDR message (see [`binary`]).
    fn decode_binary(
        &mut self,
        base: usize,
        log_time: u64,
        data: &[u8],
        codec: &BinaryCodec,
        signals: &[SignalPlan],
    ) {
        let Ok(t) = i64::try_from(log_time) else {
            for i in 0..signals.len() {
                self.sig(base, i).time_out_of_range += 1;
            }
            return;
        };
        let decoded = codec.decode(data, &mut self.scratch);
        for (i, s) in signals.iter().enumerate() {
            let b = &mut self.sigs[base + i];
            b.messages += 1;
            if let Err(e) = &decoded {
                b.malformed_at(t, e);
                continue;
            }
            match codec.signal(i, &self.scratch) {
                binary::Extracted::Scalar(x) => b.push_f64(t, x, &s.src),
                binary::Extracted::Missing => {
                    b.missing_field += 1;
                    b.missing_field_first.get_or_insert(t);
                }
                binary::Extracted::WrongShape(why) => b.wrong_shape_at(t, why),
                binary::Extracted::Block {
                    t0_ns,
                    dt_ns,
                    values,
                } => {
                    let (Some(t0n), Some(dtn)) = (t0_ns, dt_ns) else {
                        b.wrong_shape_at(t, "block message without t0_ns and dt_ns");
                        continue;
                    };
                    let Some((t0i, dti)) = b.block_times(t, log_time, t0n, dtn) else {
                        continue;
                    };
                    for (k, v) in values.iter().enumerate() {
                        let ts = t0i.saturating_add(dti.saturating_mul(k as i64));
                        b.push_f64(ts, v.f64(), &s.src);
                    }
                }
            }
        }
    }

    /// One protobuf or CDR image message.
    fn decode_binary_image(
        &mut self,
        ch: u16,
        log_time: u64,
        data: &[u8],
        codec: &BinaryCodec,
        full: bool,
    ) {
        let mut e = ImageEntry::new(ch, log_time, self.item_offset);
        match codec.decode(data, &mut self.scratch) {
            Err(err) => e.error = Some(err),
            Ok(()) => {
                let f = codec.image(&self.scratch);
                e.frame_id = f.frame_id;
                e.format = f.format;
                e.stamp_ns = f.stamp_ns;
                match f.data {
                    None => e.error = Some("no `data` field".into()),
                    Some(bytes) => {
                        e.data_len = bytes.len() as u64;
                        if full {
                            e.data = Some(bytes.to_vec());
                        }
                    }
                }
            }
        }
        self.images.push(e);
    }

    fn decode_image(&mut self, ch: u16, log_time: u64, data: &[u8], full: bool) {
        let mut e = ImageEntry::new(ch, log_time, self.item_offset);
        let mut raw_data: Option<&[u8]> = None;
        let mut stamp: Option<Val> = None;
        let res = json::for_each_member(data, |k, v| {
            if json::key_is(k, "frame_id") {
                e.frame_id = v.string().unwrap_or_default();
            } else if json::key_is(k, "format") {
                e.format = v.string().unwrap_or_default();
            } else if json::key_is(k, "data") {
                if let Val::Str(s) = v {
                    raw_data = Some(s);
                }
            } else if json::key_is(k, "timestamp") {
                stamp = Some(v);
            }
        });
        if let Err(err) = res {
            e.error = Some(format!("message is not valid JSON: {err}"));
            self.images.push(e);
            return;
        }
        if let Some(Val::Object(o)) = stamp {
            let (mut sec, mut nsec) = (None, None);
            let _ = json::for_each_member(o, |k, v| {
                if json::key_is(k, "sec") {
                    sec = v.u64();
                } else if json::key_is(k, "nsec") {
                    nsec = v.u64();
                }
            });
            if let (Some(s), Some(n)) = (sec, nsec) {
                e.stamp_ns = s.checked_mul(1_000_000_000).and_then(|x| x.checked_add(n));
            }
        }
        match raw_data {
            None => e.error = Some("no base64 `data` string".into()),
            Some(raw) => {
                e.data_len = (raw.len() as u64 / 4) * 3;
                if full {
                    use base64::Engine;
                    let decoded = if raw.contains(&b'\\') {
                        json::unescape(raw)
                            .ok_or_else(|| "bad string escape".to_string())
                            .and_then(|s| {
                                base64::engine::general_purpose::STANDARD
                                    .decode(s.as_bytes())
                                    .map_err(|x| x.to_string())
                            })
                    } else {
                        base64::engine::general_purpose::STANDARD
                            .decode(raw)
                            .map_err(|x| x.to_string())
                    };
                    match decoded {
                        Ok(bytes) => {
                            e.data_len = bytes.len() as u64;
                            e.data = Some(bytes);
                        }
                        Err(x) => e.error = Some(format!("`data` is not valid base64: {x}")),
                    }
                }
            }
        }
        self.images.push(e);
    }
}

impl RecordVisitor for Decoder {
    fn schema(&mut self, def: SchemaDef) {
        self.new_schemas.push(def);
    }

    fn channel(&mut self, def: ChannelDef) {
        self.new_channels.push(def);
    }

    fn message(&mut self, channel_id: u16, log_time: u64, data: &[u8]) {
        let Some(plan) = self.plans.get(channel_id) else {
            self.deferred.push((channel_id, log_time, data.to_vec()));
            return;
        };
        if let Some(c) = self.counts.get_mut(channel_id as usize) {
            c.add_time(log_time);
        }
        match plan {
            ChannelPlan::Signals {
                shape,
                title,
                signals,
                base,
            } => {
                self.out
                    .decode_signals(*base, log_time, data, *shape, title.as_deref(), signals);
            }
            ChannelPlan::Binary {
                codec,
                signals,
                base,
            } => self
                .out
                .decode_binary(*base, log_time, data, codec, signals),
            ChannelPlan::Image { full } => self.out.decode_image(channel_id, log_time, data, *full),
            ChannelPlan::BinaryImage { codec, full } => self
                .out
                .decode_binary_image(channel_id, log_time, data, codec, *full),
            _ => {}
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rig::channel_map::SignalKind;
    use crate::rig::channel_map::SignalSource;

    fn plans_for(shape: Shape, title: Option<&str>, kinds: &[(SignalKind, &str)]) -> Plans {
        let mut p = Plans::default();
        p.insert(
            1,
            ChannelPlan::Signals {
                base: 0,
                shape,
                title: title.map(str::to_string),
                signals: kinds
                    .iter()
                    .map(|(k, f)| SignalPlan {
                        kind: *k,
                        src: SignalSource {
                            topic: "/t".into(),
                            field: f.to_string(),
                            unit: k.unit().into(),
                            scale: 2.0,
                            offset: 1.0,
                            unit_factor: 1.0,
                        },
                    })
                    .collect(),
            },
        );
        p
    }

    #[test]
    fn scalar_messages_and_invalid_tokens() {
        let p = plans_for(
            Shape::Scalar,
            None,
            &[
                (SignalKind::Angle, "angle_rad"),
                (SignalKind::Speed, "speed_rpm"),
            ],
        );
        let mut d = Decoder::new(Arc::new(p), 0);
        d.message(1, 10, br#"{"angle_rad": 1.0, "speed_rpm": NaN}"#);
        d.message(1, 20, br#"{"angle_rad": null, "speed_rpm": 3}"#);
        d.message(1, 30, br#"{"speed_rpm": 3"#);
        d.message(1, 40, br#"{"t0_ns": 40, "dt_ns": 1, "values": [1,2]}"#);
        let a = &d.out.sigs[0];
        assert_eq!((a.t[0], a.v[0]), (10, 3.0));
        assert!(a.v[1].is_nan());
        assert_eq!(a.invalid.null, 1);
        assert_eq!(a.malformed, 1);
        assert_eq!(
            a.wrong_shape, 1,
            "a block on a scalar channel is never read as a scalar"
        );
        let s = &d.out.sigs[1];
        assert_eq!(s.invalid.nan_token, 1);
        assert_eq!((s.t[1], s.v[1]), (20, 7.0));
        assert_eq!(d.counts[1].messages, 4);
    }

    /// A decoder of block messages on channel 1 (schema title `title`)
    /// for the force field `force_n`.
    fn force_block_decoder(title: &str) -> Decoder {
        let p = plans_for(Shape::Block, Some(title), &[(SignalKind::Force, "force_n")]);
        Decoder::new(Arc::new(p), 0)
    }

    #[test]
    fn block_messages_expand_and_check_title() {
        let mut d = force_block_decoder("force_n");
        d.message(
            1,
            1000,
            br#"{"t0_ns": 1000, "dt_ns": 100, "values": [0.5, NaN, 1.5]}"#,
        );
        d.message(1, 5000, br#"{"t0_ns": 4000, "dt_ns": 100, "values": [2]}"#);
        let f = &d.out.sigs[0];
        assert_eq!(f.t.len(), 4);
        assert_eq!((f.t[0], f.v[0]), (1000, 2.0));
        assert_eq!((f.t[2], f.v[2]), (1200, 4.0));
        assert_eq!(f.t[3], 4000);
        assert_eq!(f.invalid.nan_token, 1);
        assert_eq!(f.blocks, 2);
        assert_eq!(f.block_time_mismatch, 1);
        let mut d2 = force_block_decoder("displacement_mm");
        d2.message(
            1,
            1000,
            br#"{"t0_ns": 1000, "dt_ns": 100, "values": [0.5]}"#,
        );
        assert_eq!(d2.out.sigs[0].wrong_shape, 1);
        assert!(d2.out.sigs[0].t.is_empty());
    }

    #[test]
    fn auto_shape_detects_blocks_and_defers_unknown_channels() {
        let p = plans_for(Shape::Auto, None, &[(SignalKind::Force, "force_n")]);
        let mut d = Decoder::new(Arc::new(p), 0);
        d.message(
            1,
            1000,
            br#"{"t0_ns": 1000, "dt_ns": 100, "values": [0.5, 1]}"#,
        );
        d.message(1, 2000, br#"{"force_n": 1}"#);
        d.message(9, 3000, br#"{"x": 1}"#);
        assert_eq!(d.out.sigs[0].t.len(), 3);
        assert_eq!(d.deferred.len(), 1);
    }

    #[test]
    fn images_decode_base64() {
        let mut p = Plans::default();
        p.insert(2, ChannelPlan::Image { full: true });
        let mut d = Decoder::new(Arc::new(p), 77);
        d.message(
            2,
            5,
            br#"{"timestamp": {"sec": 1, "nsec": 2}, "frame_id": "cycle-3", "format": "png", "data": "aGVsbG8="}"#,
        );
        let e = &d.out.images[0];
        assert_eq!(e.data.as_deref(), Some(&b"hello"[..]));
        assert_eq!(
            (
                e.frame_id.as_str(),
                e.format.as_str(),
                e.stamp_ns,
                e.item_offset
            ),
            ("cycle-3", "png", Some(1_000_000_002), 77)
        );
    }
}
