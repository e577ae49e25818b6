//! What decoding collects: one signal's samples and counters ([`SigBuf`],
//! merged across work items), per-channel message counts, and the image
//! messages found.

use super::super::channel_map::SignalSource;
use super::super::json::Num;

/// Maximum sample times remembered per kind of problem (for messages).
pub const KEEP_TIMES: usize = 50;

/// Counts of samples that are not usable numbers.
#[derive(Debug, Clone, Default, serde::Serialize)]
pub struct InvalidCounts {
    /// Written as the token `NaN`.
    pub nan_token: u64,
    /// Written as `null`.
    pub null: u64,
    /// ±Infinity, or a number beyond f64.
    pub non_finite: u64,
    /// Not a number (string, bool, object).
    pub not_number: u64,
}

impl InvalidCounts {
    pub fn total(&self) -> u64 {
        self.nan_token + self.null + self.non_finite + self.not_number
    }

    pub fn add(&mut self, o: &InvalidCounts) {
        self.nan_token += o.nan_token;
        self.null += o.null;
        self.non_finite += o.non_finite;
        self.not_number += o.not_number;
    }
}

/// Samples and counters of one signal from one work item (or merged).
#[derive(Debug, Clone, Default)]
pub struct SigBuf {
    /// log_time (ns) and value per sample, in file order; NaN marks an invalid sample.
    pub t: Vec<i64>,
    pub v: Vec<f64>,
    pub messages: u64,
    pub blocks: u64,
    pub invalid: InvalidCounts,
    /// Times of the first invalid samples: (time, kind).
    pub invalid_times: Vec<(i64, &'static str)>,
    pub missing_field: u64,
    pub missing_field_first: Option<i64>,
    pub wrong_shape: u64,
    pub wrong_shape_first: Option<(i64, String)>,
    pub malformed: u64,
    pub malformed_first: Option<(i64, String)>,
    pub block_time_mismatch: u64,
    pub block_time_mismatch_first: Option<(i64, i64)>,
    pub time_out_of_range: u64,
}

impl SigBuf {
    pub fn append(&mut self, o: &mut SigBuf) {
        self.t.append(&mut o.t);
        self.v.append(&mut o.v);
        self.messages += o.messages;
        self.blocks += o.blocks;
        self.invalid.add(&o.invalid);
        let room = KEEP_TIMES.saturating_sub(self.invalid_times.len());
        self.invalid_times
            .extend(o.invalid_times.iter().take(room).copied());
        self.missing_field += o.missing_field;
        self.missing_field_first = self.missing_field_first.or(o.missing_field_first);
        self.wrong_shape += o.wrong_shape;
        if self.wrong_shape_first.is_none() {
            self.wrong_shape_first = o.wrong_shape_first.take();
        }
        self.malformed += o.malformed;
        if self.malformed_first.is_none() {
            self.malformed_first = o.malformed_first.take();
        }
        self.block_time_mismatch += o.block_time_mismatch;
        self.block_time_mismatch_first = self
            .block_time_mismatch_first
            .or(o.block_time_mismatch_first);
        self.time_out_of_range += o.time_out_of_range;
    }

    pub(super) fn invalid(&mut self, t: i64, n: Num) {
        let kind = match n {
            Num::NanToken => {
                self.invalid.nan_token += 1;
                "NaN"
            }
            Num::Null => {
                self.invalid.null += 1;
                "null"
            }
            Num::NonFinite => {
                self.invalid.non_finite += 1;
                "±Infinity"
            }
            _ => {
                self.invalid.not_number += 1;
                "not a number"
            }
        };
        if self.invalid_times.len() < KEEP_TIMES {
            self.invalid_times.push((t, kind));
        }
        self.t.push(t);
        self.v.push(f64::NAN);
    }

    /// A number from a binary message (NaN and infinities counted as invalid).
    #[inline]
    pub(super) fn push_f64(&mut self, t: i64, x: f64, src: &SignalSource) {
        let n = if x.is_nan() {
            Num::NanToken
        } else if x.is_infinite() {
            Num::NonFinite
        } else {
            Num::Finite(x)
        };
        self.push(t, n, src);
    }

    /// The start and spacing of a block message logged at `log_time`
    /// (`t` as a signed time), counting the block and, when its `t0_ns`
    /// is not the log time, the mismatch; `None` (counted out of range)
    /// when either does not fit a signed time.
    pub(super) fn block_times(
        &mut self,
        t: i64,
        log_time: u64,
        t0_ns: u64,
        dt_ns: u64,
    ) -> Option<(i64, i64)> {
        let (Ok(t0), Ok(dt)) = (i64::try_from(t0_ns), i64::try_from(dt_ns)) else {
            self.time_out_of_range += 1;
            return None;
        };
        self.blocks += 1;
        if t0_ns != log_time {
            self.block_time_mismatch += 1;
            self.block_time_mismatch_first.get_or_insert((t, t0));
        }
        Some((t0, dt))
    }

    pub(super) fn wrong_shape_at(&mut self, t: i64, why: &str) {
        self.wrong_shape += 1;
        if self.wrong_shape_first.is_none() {
            self.wrong_shape_first = Some((t, why.to_string()));
        }
    }

    pub(super) fn malformed_at(&mut self, t: i64, why: &str) {
        self.malformed += 1;
        if self.malformed_first.is_none() {
            self.malformed_first = Some((t, why.to_string()));
        }
    }

    #[inline]
    pub(super) fn push(&mut self, t: i64, n: Num, src: &SignalSource) {
        match n {
            Num::Finite(x) => {
                let v = src.convert(x);
                if v.is_finite() {
                    self.t.push(t);
                    self.v.push(v);
                } else {
                    self.invalid(t, Num::NonFinite);
                }
            }
            other => self.invalid(t, other),
        }
    }
}

/// Per-channel message counters (all channels, used or not).
#[derive(Debug, Clone, Copy, Default)]
pub struct ChanCount {
    pub messages: u64,
    pub first: u64,
    pub last: u64,
}

impl ChanCount {
    pub(super) fn add_time(&mut self, t: u64) {
        if self.messages == 0 {
            self.first = t;
            self.last = t;
        } else {
            self.first = self.first.min(t);
            self.last = self.last.max(t);
        }
        self.messages += 1;
    }

    pub fn merge(&mut self, o: &ChanCount) {
        if o.messages == 0 {
            return;
        }
        if self.messages == 0 {
            *self = *o;
        } else {
            self.first = self.first.min(o.first);
            self.last = self.last.max(o.last);
            self.messages += o.messages;
        }
    }
}

/// One image message as found (bytes decoded only in `full` mode).
#[derive(Debug, Clone)]
pub struct ImageEntry {
    pub channel: u16,
    pub log_time: u64,
    /// File offset of the chunk (or message record) holding it.
    pub item_offset: u64,
    pub frame_id: String,
    pub format: String,
    /// `timestamp` of the message (sec, nsec) as ns.
    pub stamp_ns: Option<u64>,
    /// Decoded size (exact in full mode, estimated from base64 otherwise).
    pub data_len: u64,
    pub data: Option<Vec<u8>>,
    pub error: Option<String>,
}

impl ImageEntry {
    /// An image message of `channel` at `log_time` in the item at
    /// `item_offset`, before its fields are read.
    pub fn new(channel: u16, log_time: u64, item_offset: u64) -> Self {
        ImageEntry {
            channel,
            log_time,
            item_offset,
            frame_id: String::new(),
            format: String::new(),
            stamp_ns: None,
            data_len: 0,
            data: None,
            error: None,
        }
    }
}
