//! Signals: per-channel, time-sorted sample arrays and what was found in
//! their time streams.
//!
//! A [`Signal`] holds `t_ns` (log_time, ns since the Unix epoch, i64) and
//! `values` (canonical unit), sorted by time, one sample per timestamp,
//! invalid samples removed: 16 bytes per sample. The loader collects them in
//! file order in the same two vectors; finishing works in place (a log
//! already in time order is not copied; one out of order is sorted through
//! a permutation, a transient 8 + 16 bytes per sample of that signal).
//!
//! Finishing a signal (file order → sorted) measures, per channel: steps
//! back in time in file order (a clock jump when there are a few, a file
//! written out of order when there are many), duplicated timestamps (the
//! first sample in file order is kept, rig-log.md), gaps (an interval longer
//! than 1.5 nominal intervals; the nominal interval is the median one), late
//! start / early end against the whole log, and the invalid samples counted
//! by the decoder.

use super::channel_map::SignalKind;
use super::decode::{InvalidCounts, SigBuf};
use super::report::{Finding, FindingCode, Place, Severity, fmt_time};
use serde::Serialize;

/// One signal's samples, sorted by time.
#[derive(Debug, Clone, Serialize)]
pub struct Signal {
    pub kind: SignalKind,
    pub topic: String,
    pub field: String,
    /// Canonical unit (rad, rpm, N, mm; "" for the cycle index).
    pub unit: String,
    /// Sample times, log_time ns since the Unix epoch, strictly increasing.
    pub t_ns: Vec<i64>,
    pub values: Vec<f64>,
}

impl Signal {
    pub fn len(&self) -> usize {
        self.t_ns.len()
    }

    pub fn is_empty(&self) -> bool {
        self.t_ns.is_empty()
    }

    /// Linear interpolation at `t` (None outside the samples or across a hole
    /// longer than `max_dt_ns`).
    pub fn interp(&self, t: i64, max_dt_ns: i64) -> Option<f64> {
        let i = self.t_ns.partition_point(|&x| x < t);
        if i < self.t_ns.len() && self.t_ns[i] == t {
            return Some(self.values[i]);
        }
        if i == 0 || i >= self.t_ns.len() {
            return None;
        }
        let (t0, t1) = (self.t_ns[i - 1], self.t_ns[i]);
        if t1 - t0 > max_dt_ns {
            return None;
        }
        let w = (t - t0) as f64 / (t1 - t0) as f64;
        Some(self.values[i - 1] + w * (self.values[i] - self.values[i - 1]))
    }
}

/// A gap in a channel's time stream.
#[derive(Debug, Clone, Serialize)]
pub struct Gap {
    /// Last sample before the gap.
    pub from_ns: i64,
    /// First sample after the gap.
    pub to_ns: i64,
    pub duration_s: f64,
    /// Samples missing at the nominal rate.
    pub missing_samples: u64,
}

/// A step back in time in file order.
#[derive(Debug, Clone, Serialize)]
pub struct BackStep {
    /// log_time of the message before it in file order.
    pub previous_ns: i64,
    pub log_time_ns: i64,
    /// Step of the clock: (t − previous) − nominal interval (negative), s.
    pub jump_s: f64,
    /// Position of the message among the channel's messages in file order (0-based).
    pub ordinal: u64,
}

/// What was found in one signal's stream (plain data for the Signals pane).
#[derive(Debug, Clone, Serialize)]
pub struct SignalStats {
    pub kind: SignalKind,
    pub topic: String,
    pub field: String,
    pub unit: String,
    pub messages: u64,
    /// Block messages (0 for scalar topics).
    pub blocks: u64,
    /// Samples received (including invalid and duplicated ones).
    pub samples_received: u64,
    /// Samples kept (valid, one per timestamp).
    pub samples: u64,
    pub first_ns: Option<i64>,
    pub last_ns: Option<i64>,
    pub span_s: f64,
    /// Nominal sample rate (from the median interval).
    pub rate_hz: Option<f64>,
    pub duplicates: u64,
    /// Duplicates whose value equals the kept sample's (exact duplicate messages).
    pub identical_duplicates: u64,
    pub duplicate_times_ns: Vec<i64>,
    pub invalid: InvalidCounts,
    pub invalid_times: Vec<(i64, String)>,
    pub missing_field: u64,
    pub wrong_shape: u64,
    pub malformed: u64,
    pub block_time_mismatch: u64,
    pub gap_count: u64,
    pub samples_missing_in_gaps: u64,
    /// The gaps (the first 1000).
    pub gaps: Vec<Gap>,
    /// Messages earlier than their predecessor in file order.
    pub backward_steps: u64,
    pub backward: Vec<BackStep>,
    /// Messages earlier than some message before them in file order.
    pub out_of_order: u64,
    /// First sample after the log's first message (s).
    pub start_delay_s: f64,
    /// Last sample before the log's last message (s).
    pub end_early_s: f64,
}

/// Median of up to 100 000 evenly spread positive intervals.
fn nominal_dt(t: &[i64]) -> Option<i64> {
    if t.len() < 3 {
        return None;
    }
    let n = t.len() - 1;
    let stride = n.div_ceil(100_000).max(1);
    let mut d: Vec<i64> = (0..n)
        .step_by(stride)
        .map(|i| t[i + 1] - t[i])
        .filter(|&x| x > 0)
        .collect();
    if d.is_empty() {
        return None;
    }
    let mid = d.len() / 2;
    let (_, m, _) = d.select_nth_unstable(mid);
    Some(*m)
}

fn list_times(ts: &[i64], n: usize) -> String {
    let mut s = ts
        .iter()
        .take(n)
        .map(|t| t.to_string())
        .collect::<Vec<_>>()
        .join(", ");
    if ts.len() > n {
        s.push_str(", …");
    }
    s
}

/// Turns the file-order samples of one signal into a [`Signal`], its
/// [`SignalStats`] and findings. `log_span` is the (first, last) log_time
/// of the whole log.
pub fn finish(
    kind: SignalKind,
    topic: &str,
    field: &str,
    mut buf: SigBuf,
    file: &str,
    log_span: Option<(i64, i64)>,
) -> (Signal, SignalStats, Vec<Finding>) {
    let label = format!("{topic} ({})", kind.name());
    let ch = Some(label.as_str());
    let t0 = log_span.map(|s| s.0);
    let mut findings = Vec::new();
    let mut push = |sev, code, place, text: String| {
        findings.push(Finding::new(sev, code, file, ch, place, text));
    };
    let mut t_ns = std::mem::take(&mut buf.t);
    let mut values = std::mem::take(&mut buf.v);
    let received = t_ns.len() as u64;

    // File order: steps back and out-of-order messages.
    let mut back: Vec<(usize, i64, i64)> = Vec::new();
    let mut backward_steps = 0u64;
    let mut out_of_order = 0u64;
    let mut run_max = i64::MIN;
    for (i, &t) in t_ns.iter().enumerate() {
        if i > 0 && t < t_ns[i - 1] {
            backward_steps += 1;
            if back.len() < 20 {
                back.push((i, t_ns[i - 1], t));
            }
        }
        if t < run_max {
            out_of_order += 1;
        }
        run_max = run_max.max(t);
    }

    // Sort (stable: duplicates keep file order). In time order already (the
    // usual case) nothing moves; otherwise through a permutation.
    if backward_steps > 0 {
        let mut perm: Vec<usize> = (0..t_ns.len()).collect();
        perm.sort_by_key(|&i| t_ns[i]);
        t_ns = perm.iter().map(|&i| t_ns[i]).collect();
        values = perm.iter().map(|&i| values[i]).collect();
    }

    // De-duplicate in place, the first sample of a timestamp is kept.
    let mut duplicates = 0u64;
    let mut identical = 0u64;
    let mut dup_times = Vec::new();
    let mut w = 0usize;
    for r in 0..t_ns.len() {
        if w > 0 && t_ns[r] == t_ns[w - 1] {
            duplicates += 1;
            let (a, b) = (values[w - 1], values[r]);
            if a.to_bits() == b.to_bits() || (a.is_nan() && b.is_nan()) {
                identical += 1;
            }
            if dup_times.len() < 50 {
                dup_times.push(t_ns[r]);
            }
            continue;
        }
        t_ns[w] = t_ns[r];
        values[w] = values[r];
        w += 1;
    }
    t_ns.truncate(w);
    values.truncate(w);

    let dt = if kind == SignalKind::Cycle {
        None
    } else {
        nominal_dt(&t_ns)
    };

    // Gaps (invalid samples count as received: a NaN is not a gap).
    let mut gaps = Vec::new();
    let mut gap_count = 0u64;
    let mut missing_total = 0u64;
    if let Some(dt) = dt {
        for p in t_ns.windows(2) {
            let d = p[1] - p[0];
            if d.saturating_mul(2) > dt.saturating_mul(3) {
                let missing = ((d as f64 / dt as f64).round() as u64)
                    .saturating_sub(1)
                    .max(1);
                gap_count += 1;
                missing_total += missing;
                if gaps.len() < 1000 {
                    gaps.push(Gap {
                        from_ns: p[0],
                        to_ns: p[1],
                        duration_s: d as f64 * 1e-9,
                        missing_samples: missing,
                    });
                }
            }
        }
    }
    let first_ns = t_ns.first().copied();
    let last_ns = t_ns.last().copied();

    // Invalid samples out, in place.
    if values.iter().any(|v| v.is_nan()) {
        let mut w = 0usize;
        for r in 0..t_ns.len() {
            if !values[r].is_nan() {
                t_ns[w] = t_ns[r];
                values[w] = values[r];
                w += 1;
            }
        }
        t_ns.truncate(w);
        values.truncate(w);
    }

    let span_s = match (first_ns, last_ns) {
        (Some(a), Some(b)) => (b - a) as f64 * 1e-9,
        _ => 0.0,
    };
    let (start_delay_s, end_early_s) = match (log_span, first_ns, last_ns) {
        (Some((ls, le)), Some(a), Some(b)) => ((a - ls) as f64 * 1e-9, (le - b) as f64 * 1e-9),
        _ => (0.0, 0.0),
    };

    // Findings.
    if received == 0 && buf.messages == 0 {
        push(
            Severity::Warning,
            FindingCode::EmptyChannel,
            None,
            "channel present but without any message".to_string(),
        );
    } else if t_ns.is_empty() {
        push(
            Severity::Warning,
            FindingCode::EmptyChannel,
            None,
            format!("{} message(s) but no valid sample", buf.messages),
        );
    }
    if buf.malformed > 0 {
        let (t, e) = buf.malformed_first.clone().unwrap_or((0, String::new()));
        // Binary decoders name their encoding at the start of the reason.
        let what = if e.starts_with("protobuf") || e.starts_with("cdr") {
            "do not decode against the channel's schema"
        } else {
            "are not valid JSON"
        };
        push(
            Severity::Warning,
            FindingCode::MalformedMessage,
            Some(Place::time(t)),
            format!(
                "{} message(s) {what} and were skipped; first at {}: {e}",
                buf.malformed,
                fmt_time(t, t0)
            ),
        );
    }
    if buf.missing_field > 0 {
        let t = buf.missing_field_first.unwrap_or(0);
        push(
            Severity::Warning,
            FindingCode::MissingField,
            Some(Place::time(t)),
            format!(
                "{} of {} message(s) have no field '{field}'; first at {}",
                buf.missing_field,
                buf.messages,
                fmt_time(t, t0)
            ),
        );
    }
    if buf.wrong_shape > 0 {
        let (t, e) = buf.wrong_shape_first.clone().unwrap_or((0, String::new()));
        push(
            Severity::Warning,
            FindingCode::WrongShape,
            Some(Place::time(t)),
            format!(
                "{} message(s) rejected, first at {}: {e}",
                buf.wrong_shape,
                fmt_time(t, t0)
            ),
        );
    }
    if buf.time_out_of_range > 0 {
        push(
            Severity::Warning,
            FindingCode::MalformedMessage,
            None,
            format!(
                "{} message(s) with a log_time beyond year 2262 (not representable) skipped",
                buf.time_out_of_range
            ),
        );
    }
    if buf.blocks > 0 {
        push(
            Severity::Info,
            FindingCode::BlockMessages,
            None,
            format!(
                "{} block message(s) (t0_ns, dt_ns, values) holding {received} samples",
                buf.blocks
            ),
        );
    }
    if buf.block_time_mismatch > 0 {
        let (t, b0) = buf.block_time_mismatch_first.unwrap_or((0, 0));
        push(
            Severity::Warning,
            FindingCode::BlockTimeMismatch,
            Some(Place::time(t)),
            format!(
                "{} block(s) whose t0_ns differs from the message log_time (first: log_time {t}, t0_ns {b0}); t0_ns is used",
                buf.block_time_mismatch
            ),
        );
    }
    let inv = &buf.invalid;
    if inv.total() > 0 {
        let mut parts = Vec::new();
        if inv.nan_token > 0 {
            parts.push(format!("{} written as the token NaN", inv.nan_token));
        }
        if inv.null > 0 {
            parts.push(format!("{} as null", inv.null));
        }
        if inv.non_finite > 0 {
            parts.push(format!("{} infinite", inv.non_finite));
        }
        if inv.not_number > 0 {
            parts.push(format!("{} not a number", inv.not_number));
        }
        let ts: Vec<i64> = buf.invalid_times.iter().map(|x| x.0).collect();
        push(
            Severity::Warning,
            FindingCode::InvalidSamples,
            ts.first()
                .map(|&t| Place::span(t, *ts.last().unwrap_or(&t))),
            format!(
                "{} invalid sample(s) ({}), treated as missing; at log_time {}",
                inv.total(),
                parts.join(", "),
                list_times(&ts, 8)
            ),
        );
    }
    if duplicates > 0 {
        let differing = duplicates - identical;
        push(
            Severity::Warning,
            FindingCode::DuplicateTimestamps,
            dup_times.first().map(|&t| Place::time(t)),
            format!(
                "{duplicates} duplicated timestamp(s) ({identical} exact duplicate message(s), {differing} with a different value); the first sample of each is kept; at log_time {}",
                list_times(&dup_times, 8)
            ),
        );
    }
    let dt_ns = dt.unwrap_or(0);
    let backward: Vec<BackStep> = back
        .iter()
        .map(|&(i, prev, t)| BackStep {
            previous_ns: prev,
            log_time_ns: t,
            jump_s: ((t - prev) - dt_ns) as f64 * 1e-9,
            ordinal: i as u64,
        })
        .collect();
    if backward_steps > 0 && backward_steps <= 10 {
        for b in &backward {
            push(
                Severity::Warning,
                FindingCode::TimeBackwards,
                Some(Place::span(b.log_time_ns, b.previous_ns)),
                format!(
                    "time goes backwards in file order: the clock jumps back by {:.3} ms at {} (message {} of the channel; the previous message is at log_time {}); samples were sorted by log_time",
                    -b.jump_s * 1e3,
                    fmt_time(b.log_time_ns, t0),
                    b.ordinal,
                    b.previous_ns
                ),
            );
        }
    } else if backward_steps > 10 {
        push(
            Severity::Info,
            FindingCode::OutOfOrder,
            None,
            format!(
                "{out_of_order} of {received} message(s) are earlier than a message before them in the file: written out of log_time order; sorted by log_time"
            ),
        );
    }
    if gap_count > 0 {
        let big: Vec<&Gap> = gaps.iter().filter(|g| g.missing_samples >= 3).collect();
        for g in big.iter().take(20) {
            push(
                Severity::Warning,
                FindingCode::Gap,
                Some(Place::span(g.from_ns, g.to_ns)),
                format!(
                    "gap of {:.1} ms ({} samples missing) between {} and log_time {}",
                    g.duration_s * 1e3,
                    g.missing_samples,
                    fmt_time(g.from_ns, t0),
                    g.to_ns
                ),
            );
        }
        let small: Vec<&Gap> = gaps.iter().filter(|g| g.missing_samples < 3).collect();
        let hidden_big = big.len().saturating_sub(20);
        if !small.is_empty() || hidden_big > 0 {
            let ts: Vec<i64> = small.iter().map(|g| g.from_ns).collect();
            push(
                Severity::Warning,
                FindingCode::Gap,
                ts.first().map(|&t| Place::time(t)),
                format!(
                    "{} short gap(s) of 1–2 missing samples{}; after log_time {}",
                    small.len(),
                    if hidden_big > 0 {
                        format!(" and {hidden_big} more long gap(s)")
                    } else {
                        String::new()
                    },
                    list_times(&ts, 8)
                ),
            );
        }
    }
    if kind == SignalKind::Cycle {
        let mut prev: Option<(i64, f64)> = None;
        let mut reported = 0;
        for (&t, &v) in t_ns.iter().zip(&values) {
            if let Some((pt, pv)) = prev {
                let step = v - pv;
                if step != 1.0 && reported < 20 {
                    reported += 1;
                    let text = if step > 1.0 {
                        format!(
                            "cycle index jumps from {pv} to {v} at {}: {} cycle mark(s) missing",
                            fmt_time(t, t0),
                            step - 1.0
                        )
                    } else {
                        format!(
                            "cycle index goes from {pv} to {v} at {} (previous mark at log_time {pt}): not increasing by one",
                            fmt_time(t, t0)
                        )
                    };
                    push(
                        Severity::Warning,
                        FindingCode::Cycle,
                        Some(Place::time(t)),
                        text,
                    );
                }
            }
            prev = Some((t, v));
        }
    } else if let (Some(dt), Some(_)) = (dt, first_ns) {
        let tol = dt.saturating_mul(10).max(5_000_000) as f64 * 1e-9;
        if start_delay_s > tol {
            push(
                Severity::Warning,
                FindingCode::Gap,
                first_ns.map(Place::time),
                format!(
                    "starts late: first sample {:.1} ms after the log's first message",
                    start_delay_s * 1e3
                ),
            );
        }
        if end_early_s > tol {
            push(
                Severity::Warning,
                FindingCode::Gap,
                last_ns.map(Place::time),
                format!(
                    "stops early: last sample {:.1} ms before the log's last message",
                    end_early_s * 1e3
                ),
            );
        }
    }

    let stats = SignalStats {
        kind,
        topic: topic.to_string(),
        field: field.to_string(),
        unit: kind.unit().to_string(),
        messages: buf.messages,
        blocks: buf.blocks,
        samples_received: received,
        samples: t_ns.len() as u64,
        first_ns,
        last_ns,
        span_s,
        rate_hz: dt.map(|d| 1e9 / d as f64),
        duplicates,
        identical_duplicates: identical,
        duplicate_times_ns: dup_times,
        invalid: buf.invalid.clone(),
        invalid_times: buf
            .invalid_times
            .iter()
            .map(|(t, k)| (*t, k.to_string()))
            .collect(),
        missing_field: buf.missing_field,
        wrong_shape: buf.wrong_shape,
        malformed: buf.malformed,
        block_time_mismatch: buf.block_time_mismatch,
        gap_count,
        samples_missing_in_gaps: missing_total,
        gaps,
        backward_steps,
        backward,
        out_of_order,
        start_delay_s,
        end_early_s,
    };
    let signal = Signal {
        kind,
        topic: topic.to_string(),
        field: field.to_string(),
        unit: kind.unit().to_string(),
        t_ns,
        values,
    };
    (signal, stats, findings)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn buf(samples: Vec<(i64, f64)>) -> SigBuf {
        SigBuf {
            messages: samples.len() as u64,
            t: samples.iter().map(|s| s.0).collect(),
            v: samples.iter().map(|s| s.1).collect(),
            ..Default::default()
        }
    }

    #[test]
    fn sorts_dedups_and_finds_gaps() {
        // 1 kHz stream with a 10 ms gap, a duplicate and a step back.
        let mut s: Vec<(i64, f64)> = (0..100).map(|i| (i * 1_000_000, i as f64)).collect();
        s.retain(|x| !(20_000_000..30_000_000).contains(&x.0) || x.0 == 20_000_000);
        s.push((50_000_000, -1.0)); // duplicate, different value
        s.push((40_000_000, 40.0)); // exact duplicate, earlier in time
        let (sig, st, f) = finish(
            SignalKind::Force,
            "/f",
            "force_n",
            buf(s),
            "x.mcap",
            Some((0, 99_000_000)),
        );
        assert_eq!(st.duplicates, 2);
        assert_eq!(st.identical_duplicates, 1);
        assert_eq!(
            sig.values[sig.t_ns.partition_point(|&t| t < 50_000_000)],
            50.0,
            "first kept"
        );
        assert_eq!(st.gap_count, 1);
        assert_eq!(st.gaps[0].missing_samples, 9);
        assert_eq!(
            (st.gaps[0].from_ns, st.gaps[0].to_ns),
            (20_000_000, 30_000_000)
        );
        assert_eq!(st.backward_steps, 2, "99 ms → 50 ms and 50 ms → 40 ms");
        assert!(
            f.iter().any(|x| x.code == FindingCode::TimeBackwards
                && x.message.contains("x.mcap: /f (force)"))
        );
        assert!(sig.t_ns.windows(2).all(|w| w[0] < w[1]));
        assert_eq!(st.rate_hz, Some(1000.0));
    }

    #[test]
    fn nan_samples_are_dropped_but_not_gaps() {
        let mut s: Vec<(i64, f64)> = (0..50).map(|i| (i * 100, 1.0)).collect();
        s[10].1 = f64::NAN;
        let mut b = buf(s);
        b.invalid.nan_token = 1;
        b.invalid_times.push((1000, "NaN"));
        let (sig, st, f) = finish(
            SignalKind::Displacement,
            "/d",
            "displacement_mm",
            b,
            "x",
            None,
        );
        assert_eq!(sig.len(), 49);
        assert_eq!(st.gap_count, 0);
        assert!(f.iter().any(|x| x.code == FindingCode::InvalidSamples));
        assert_eq!(sig.interp(1000, 250), Some(1.0));
        assert_eq!(sig.interp(1000, 150), None);
    }

    #[test]
    fn cycle_index_jumps_are_reported() {
        let s = vec![(0, 5.0), (10, 6.0), (20, 8.0)];
        let (_, _, f) = finish(SignalKind::Cycle, "/c", "index", buf(s), "x", None);
        assert!(
            f.iter()
                .any(|x| x.code == FindingCode::Cycle
                    && x.message.contains("1 cycle mark(s) missing"))
        );
    }
}
