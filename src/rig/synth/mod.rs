//! Synthetic rig logs: a mechanism's "true" stroke and load-cell force seen
//! through sensor models, written as MCAP in the rig-log.md convention with
//! the `mcap` crate. Used by `examples/gen_logs.rs` (fixtures, the benchmark
//! log) and by the tests (bad-input cases are made by editing a generated
//! message list before writing it).
//!
//! Time: the crank turns at ω = 2π·motor_rpm/60/gear_ratio with a speed
//! ripple applied as a time warp (as in the interop logs):
//! t_sim = τ + a/ω·(sin(ωτ + φ) − sin φ), θ2 = θ_start + ω·t_sim, so the
//! crank speed is ω(1 + a cos(ωτ + φ)).
//!
//! Sensors (each optional part set to 0 to switch it off):
//! - spindle: encoder of N counts, `floor` quantisation, zero at
//!   `encoder_offset_rad` (logged angle = θ2 − offset, wrapped to [0, 2π));
//!   motor speed with relative noise, printed to 0.01 rpm;
//! - displacement: stroke − laser zero mark, first-order lag, noise,
//!   quantisation;
//! - force: load cell through a first-order filter, noise, a tare that
//!   drifts linearly, resolution;
//! - a latency (sample stamped later than it was taken) per sensor,
//!   drop-out windows, and `/rig/cycle` marks at the exact TDC times.
//!
//! The "truth" is a [`Truth`]: [`IdealTruth`] is the closed-form ideal
//! mechanism with a quasi-static process load; [`ModelTruth`] is the
//! clearance-joint model's simulated trajectory (the fixtures calibration is
//! tested on).

pub mod faults;
mod truth;
pub mod wear_series;
mod write;

pub use truth::*;
pub use write::*;

use super::channel_map::SignalKind;
use std::collections::BTreeMap;
use std::f64::consts::{PI, TAU};

/// A window with no samples of one signal.
#[derive(Debug, Clone, serde::Serialize)]
pub struct Dropout {
    pub signal: SignalKind,
    /// Seconds from the log start.
    pub from_s: f64,
    pub to_s: f64,
}

/// Everything about a synthetic run.
#[derive(Debug, Clone, serde::Serialize)]
pub struct SynthConfig {
    /// log_time of the log start (ns since the Unix epoch).
    pub start_ns: u64,
    pub motor_rpm: f64,
    pub gear_ratio: f64,
    /// Length of the log in crank revolutions.
    pub revolutions: f64,
    /// θ2 at the log start (rad).
    pub start_theta: f64,
    pub spindle_hz: f64,
    pub force_hz: f64,
    pub displacement_hz: f64,
    /// Encoder counts per turn (0: angle not quantised).
    pub encoder_counts: u32,
    /// Encoder zero (θ2 at which it reads 0): logged angle = θ2 − offset.
    pub encoder_offset_rad: f64,
    /// Relative speed ripple at the crank frequency and its phase.
    pub speed_ripple: f64,
    pub ripple_phase: f64,
    /// Motor-speed noise, fraction of the set-point.
    pub speed_noise: f64,
    pub laser_zero_mm: f64,
    pub laser_lag_s: f64,
    pub laser_noise_mm: f64,
    pub laser_quantum_mm: f64,
    pub force_lag_s: f64,
    pub force_noise_n: f64,
    /// Load-cell tare at the start and its change over the log (N).
    pub force_tare_n: f64,
    pub force_drift_n: f64,
    pub force_resolution_n: f64,
    /// Latency of each sensor: the sample taken at t is stamped t + latency (s).
    pub latency_spindle_s: f64,
    pub latency_force_s: f64,
    pub latency_displacement_s: f64,
    pub dropouts: Vec<Dropout>,
    pub cycle_topic: bool,
    /// Force and displacement as blocks of `block_len` samples.
    pub blocks: bool,
    pub block_len: usize,
    pub metadata: Option<BTreeMap<String, String>>,
    pub seed: u64,
}

impl Default for SynthConfig {
    /// A 1200 rpm run of the `paper` head, sensors as in the interop logs.
    fn default() -> Self {
        SynthConfig {
            start_ns: 1_795_156_933_118_000_000,
            motor_rpm: 1200.0,
            gear_ratio: 1.0,
            revolutions: 10.6,
            start_theta: PI + 0.3 * TAU,
            spindle_hz: 5000.0,
            force_hz: 10_000.0,
            displacement_hz: 10_000.0,
            encoder_counts: 4096,
            encoder_offset_rad: 0.0,
            speed_ripple: 0.005,
            ripple_phase: 0.75,
            speed_noise: 0.003,
            laser_zero_mm: 10.0,
            laser_lag_s: 1.0 / (TAU * 3000.0),
            laser_noise_mm: 0.002,
            laser_quantum_mm: 0.001,
            force_lag_s: 1.0 / (TAU * 1000.0),
            force_noise_n: 0.05,
            force_tare_n: -0.02,
            force_drift_n: 0.02,
            force_resolution_n: 1e-4,
            latency_spindle_s: 0.0,
            latency_force_s: 0.0,
            latency_displacement_s: 0.0,
            dropouts: Vec::new(),
            cycle_topic: true,
            blocks: false,
            block_len: 100,
            metadata: None,
            seed: 1,
        }
    }
}

impl SynthConfig {
    /// Crank speed (rad/s).
    pub fn omega(&self) -> f64 {
        TAU * self.motor_rpm / 60.0 / self.gear_ratio
    }

    /// Duration of the log (s).
    pub fn duration_s(&self) -> f64 {
        self.revolutions * TAU / self.omega()
    }

    /// Simulation time of log time τ (s from the log start): the speed-ripple warp.
    pub fn t_sim(&self, tau: f64) -> f64 {
        let w = self.omega();
        let (a, p) = (self.speed_ripple, self.ripple_phase);
        tau + a / w * ((w * tau + p).sin() - p.sin())
    }

    /// θ2 and crank speed at log time τ.
    pub fn crank(&self, tau: f64) -> (f64, f64) {
        let w = self.omega();
        let th = self.start_theta + w * self.t_sim(tau);
        let om = w * (1.0 + self.speed_ripple * (w * tau + self.ripple_phase).cos());
        (th, om)
    }

    /// Log times (s from the start) where θ2 = TDC (π + 2πn), with n.
    pub fn tdc_times(&self) -> Vec<(f64, i64)> {
        let tdc = PI;
        let (th0, _) = self.crank(0.0);
        let (th1, _) = self.crank(self.duration_s());
        let n0 = ((th0 - tdc) / TAU).ceil() as i64;
        let n1 = ((th1 - tdc) / TAU).floor() as i64;
        (n0..=n1)
            .map(|n| {
                let target = tdc + n as f64 * TAU;
                let mut tau = (target - self.start_theta) / self.omega();
                for _ in 0..50 {
                    let (th, om) = self.crank(tau);
                    let step = (th - target) / om;
                    tau -= step;
                    if step.abs() < 1e-13 {
                        break;
                    }
                }
                (tau, n)
            })
            .collect()
    }

    /// The `rig` record: the configured one, else one describing this run.
    pub fn rig_metadata(&self) -> BTreeMap<String, String> {
        if let Some(m) = &self.metadata {
            return m.clone();
        }
        let mut m = BTreeMap::new();
        m.insert("rig_id".into(), "synthetic".into());
        m.insert("clearance_mm".into(), "0.1".into());
        m.insert("material".into(), "alloy_steel".into());
        m.insert("motor_rpm".into(), format!("{}", self.motor_rpm));
        m.insert("gear_ratio".into(), format!("{}", self.gear_ratio));
        m.insert("standoff_mm".into(), "14.0".into());
        m.insert("part_number".into(), "HDR-2x10-2.54".into());
        m.insert("lot".into(), "SYNTH".into());
        m
    }
}

/// The rig generator's random numbers (see [`crate::rng`]).
pub type Rng = crate::rng::SplitMix64<0x9E37_79B9_7F4A_7C15>;

/// A channel of a synthetic log.
#[derive(Debug, Clone)]
pub struct SynthChannel {
    pub topic: String,
    pub schema_name: String,
    pub schema_encoding: String,
    pub schema: String,
    pub message_encoding: String,
}

/// A message of a synthetic log.
#[derive(Debug, Clone)]
pub struct SynthMessage {
    /// Index into [`SynthLog::channels`].
    pub channel: usize,
    pub log_time: u64,
    pub publish_time: u64,
    pub data: Vec<u8>,
}

/// A whole synthetic log in memory (small logs: tests edit it before writing).
#[derive(Debug, Clone, Default)]
pub struct SynthLog {
    pub channels: Vec<SynthChannel>,
    pub messages: Vec<SynthMessage>,
    pub metadata: Vec<(String, BTreeMap<String, String>)>,
    /// (name, media type, content).
    pub attachments: Vec<(String, String, Vec<u8>)>,
    pub profile: String,
}

impl SynthLog {
    pub fn channel_index(&self, topic: &str) -> Option<usize> {
        self.channels.iter().position(|c| c.topic == topic)
    }
}

fn scalar_schema(title: &str, fields: &[&str]) -> String {
    let props: Vec<String> = fields
        .iter()
        .map(|f| format!("\"{f}\": {{\"type\": \"number\"}}"))
        .collect();
    format!(
        "{{\"title\": \"{title}\", \"type\": \"object\", \"properties\": {{{}}}}}",
        props.join(", ")
    )
}

fn block_schema(field: &str) -> String {
    format!(
        "{{\"title\": \"{field}\", \"type\": \"object\", \"properties\": {{\"t0_ns\": {{\"type\": \"integer\"}}, \"dt_ns\": {{\"type\": \"integer\"}}, \"values\": {{\"type\": \"array\", \"items\": {{\"type\": \"number\"}}}}}}}}"
    )
}

/// The channels of the default convention for a config.
pub fn default_channels(cfg: &SynthConfig) -> Vec<SynthChannel> {
    let ch = |topic: &str, name: &str, schema: String| SynthChannel {
        topic: topic.into(),
        schema_name: name.into(),
        schema_encoding: "jsonschema".into(),
        schema,
        message_encoding: "json".into(),
    };
    let mut v = vec![ch(
        "/rig/spindle",
        "rig.Spindle",
        scalar_schema("rig.Spindle", &["angle_rad", "speed_rpm"]),
    )];
    if cfg.blocks {
        v.push(ch(
            "/rig/displacement",
            "rig.DisplacementBlock",
            block_schema("displacement_mm"),
        ));
        v.push(ch("/rig/force", "rig.ForceBlock", block_schema("force_n")));
    } else {
        v.push(ch(
            "/rig/displacement",
            "rig.Displacement",
            scalar_schema("rig.Displacement", &["displacement_mm"]),
        ));
        v.push(ch(
            "/rig/force",
            "rig.Force",
            scalar_schema("rig.Force", &["force_n"]),
        ));
    }
    v.push(ch(
        "/rig/cycle",
        "rig.Cycle",
        scalar_schema("rig.Cycle", &["index"]),
    ));
    v
}

/// A first-order low-pass filter run on the truth between samples.
struct Lag {
    tau: f64,
    y: Option<f64>,
    t: f64,
}

impl Lag {
    fn step(&mut self, t: f64, x_at: impl Fn(f64) -> f64) -> f64 {
        match self.y {
            None => {
                let y = x_at(t);
                self.y = Some(y);
                self.t = t;
                y
            }
            Some(mut y) => {
                if self.tau <= 0.0 {
                    self.t = t;
                    let v = x_at(t);
                    self.y = Some(v);
                    return v;
                }
                let k = 8;
                let h = (t - self.t) / k as f64;
                let a = 1.0 - (-h / self.tau).exp();
                for i in 1..=k {
                    let ti = self.t + h * (i as f64 - 0.5);
                    y += a * (x_at(ti) - y);
                }
                self.y = Some(y);
                self.t = t;
                y
            }
        }
    }
}

struct Stream {
    kind: u8,
    period: f64,
    phase: f64,
    i: u64,
}

impl Stream {
    fn t(&self) -> f64 {
        self.phase + self.i as f64 * self.period
    }
}

fn in_dropout(cfg: &SynthConfig, k: SignalKind, tau: f64) -> bool {
    cfg.dropouts
        .iter()
        .any(|d| d.signal == k && tau >= d.from_s && tau < d.to_s)
}

fn round_to(x: f64, q: f64) -> f64 {
    if q > 0.0 { (x / q).round() * q } else { x }
}

/// Generates the messages of a run in log_time order and hands each to `sink`
/// (channel index into [`default_channels`], log_time, publish_time, payload).
/// Streams: memory does not grow with the length of the run.
pub fn generate_with(
    cfg: &SynthConfig,
    truth: &dyn Truth,
    sink: impl FnMut(usize, u64, u64, &[u8]),
) {
    generate_until(cfg, truth, &std::sync::atomic::AtomicBool::new(false), sink);
}

/// [`generate_with`] that ends early when `stop` is set (checked before
/// every message): a live simulated line of 8 h stops when it is told to,
/// not after generating the rest of its samples.
pub fn generate_until(
    cfg: &SynthConfig,
    truth: &dyn Truth,
    stop: &std::sync::atomic::AtomicBool,
    mut sink: impl FnMut(usize, u64, u64, &[u8]),
) {
    let mut rng = Rng::new(cfg.seed);
    let dur = cfg.duration_s();
    let ns = |tau: f64| cfg.start_ns + (tau * 1e9).round().max(0.0) as u64;
    let motor_scale = 60.0 / TAU * cfg.gear_ratio;
    let q = if cfg.encoder_counts > 0 {
        TAU / cfg.encoder_counts as f64
    } else {
        0.0
    };
    let stroke_at = |tau: f64| {
        let (th, om) = cfg.crank(tau);
        truth.eval(cfg.t_sim(tau), th, om).0
    };
    let force_at = |tau: f64| {
        let (th, om) = cfg.crank(tau);
        truth.eval(cfg.t_sim(tau), th, om).1
    };
    let mut disp_lag = Lag {
        tau: cfg.laser_lag_s,
        y: None,
        t: 0.0,
    };
    let mut force_lag = Lag {
        tau: cfg.force_lag_s,
        y: None,
        t: 0.0,
    };
    let tdcs = cfg.tdc_times();
    let mut streams = [
        Stream {
            kind: 0,
            period: 1.0 / cfg.spindle_hz,
            phase: 0.0,
            i: 0,
        },
        Stream {
            kind: 1,
            period: 1.0 / cfg.displacement_hz,
            phase: 0.0,
            i: 0,
        },
        Stream {
            kind: 2,
            period: 1.0 / cfg.force_hz,
            phase: 0.0,
            i: 0,
        },
    ];
    let mut next_tdc = 0usize;
    let mut first_index: Option<i64> = None;
    let mut buf = String::with_capacity(128);
    // Pending blocks: (t0, samples) for displacement (1) and force (2).
    let mut blocks: [(f64, Vec<f64>); 3] =
        [(0.0, Vec::new()), (0.0, Vec::new()), (0.0, Vec::new())];
    let fmt_block = |buf: &mut String, t0: u64, dt: u64, vals: &[f64], digits: usize| {
        use std::fmt::Write as _;
        buf.clear();
        let _ = write!(buf, "{{\"t0_ns\": {t0}, \"dt_ns\": {dt}, \"values\": [");
        for (i, v) in vals.iter().enumerate() {
            if i > 0 {
                buf.push_str(", ");
            }
            let _ = write!(buf, "{v:.digits$}");
        }
        buf.push_str("]}");
    };
    loop {
        // Next event: the earliest stream sample or TDC mark.
        let (si, ts) = streams
            .iter()
            .enumerate()
            .map(|(i, s)| (i, s.t()))
            .min_by(|a, b| a.1.total_cmp(&b.1))
            .unwrap_or((0, f64::INFINITY));
        let tdc_t = tdcs.get(next_tdc).map(|x| x.0).unwrap_or(f64::INFINITY);
        if (ts > dur && tdc_t > dur) || stop.load(std::sync::atomic::Ordering::Relaxed) {
            break;
        }
        use std::fmt::Write as _;
        if cfg.cycle_topic && tdc_t <= ts {
            let (tt, n) = tdcs[next_tdc];
            next_tdc += 1;
            let k0 = *first_index.get_or_insert(n);
            buf.clear();
            let _ = write!(buf, "{{\"index\": {}}}", n - k0);
            let lt = ns(tt);
            sink(3, lt, lt + 200_000, buf.as_bytes());
            continue;
        } else if !cfg.cycle_topic && tdc_t <= ts {
            next_tdc += 1;
            continue;
        }
        let s = &mut streams[si];
        s.i += 1;
        let kind = s.kind;
        let tau = ts;
        match kind {
            0 => {
                let lt = ns(tau + cfg.latency_spindle_s);
                if in_dropout(cfg, SignalKind::Angle, tau) {
                    continue;
                }
                let (th, om) = cfg.crank(tau);
                let raw = (th - cfg.encoder_offset_rad).rem_euclid(TAU);
                let ang = if q > 0.0 {
                    ((raw / q).floor() * q).rem_euclid(TAU)
                } else {
                    raw
                };
                let speed = om * motor_scale + rng.normal() * cfg.speed_noise * cfg.motor_rpm;
                buf.clear();
                let _ = write!(buf, "{{\"angle_rad\": {ang:?}, \"speed_rpm\": {speed:.2}}}");
                sink(0, lt, lt + 300_000, buf.as_bytes());
            }
            1 | 2 => {
                let (kindsig, lat) = if kind == 1 {
                    (SignalKind::Displacement, cfg.latency_displacement_s)
                } else {
                    (SignalKind::Force, cfg.latency_force_s)
                };
                let v = if kind == 1 {
                    let y = disp_lag.step(tau, stroke_at);
                    round_to(
                        y - cfg.laser_zero_mm + rng.normal() * cfg.laser_noise_mm,
                        cfg.laser_quantum_mm,
                    )
                } else {
                    let y = force_lag.step(tau, force_at);
                    let tare = cfg.force_tare_n + cfg.force_drift_n * tau / dur;
                    round_to(
                        y + tare + rng.normal() * cfg.force_noise_n,
                        cfg.force_resolution_n,
                    )
                };
                let dropped = in_dropout(cfg, kindsig, tau);
                let digits = if kind == 1 { 3 } else { 4 };
                if cfg.blocks {
                    let b = &mut blocks[kind as usize];
                    let period = streams[si].period;
                    if (dropped || b.1.len() >= cfg.block_len) && !b.1.is_empty() {
                        let t0 = ns(b.0 + lat);
                        fmt_block(&mut buf, t0, (period * 1e9).round() as u64, &b.1, digits);
                        sink(kind as usize, t0, t0 + 500_000, buf.as_bytes());
                        b.1.clear();
                    }
                    if !dropped {
                        if b.1.is_empty() {
                            b.0 = tau;
                        }
                        b.1.push(v);
                    }
                } else if !dropped {
                    let lt = ns(tau + lat);
                    buf.clear();
                    if kind == 1 {
                        let _ = write!(buf, "{{\"displacement_mm\": {v:.digits$}}}");
                    } else {
                        let _ = write!(buf, "{{\"force_n\": {v:.digits$}}}");
                    }
                    sink(kind as usize, lt, lt + 300_000, buf.as_bytes());
                }
            }
            _ => {}
        }
    }
    if cfg.blocks {
        for kind in [1usize, 2] {
            let b = &blocks[kind];
            if !b.1.is_empty() {
                let period = streams[kind].period;
                let lat = if kind == 1 {
                    cfg.latency_displacement_s
                } else {
                    cfg.latency_force_s
                };
                let t0 = ns(b.0 + lat);
                fmt_block(
                    &mut buf,
                    t0,
                    (period * 1e9).round() as u64,
                    &b.1,
                    if kind == 1 { 3 } else { 4 },
                );
                sink(kind, t0, t0 + 500_000, buf.as_bytes());
            }
        }
    }
}

/// Generates a whole run in memory.
pub fn generate(cfg: &SynthConfig, truth: &dyn Truth) -> SynthLog {
    let mut log = SynthLog {
        channels: default_channels(cfg),
        metadata: vec![("rig".into(), cfg.rig_metadata())],
        ..Default::default()
    };
    generate_with(cfg, truth, |c, lt, pt, d| {
        log.messages.push(SynthMessage {
            channel: c,
            log_time: lt,
            publish_time: pt,
            data: d.to_vec(),
        })
    });
    if !cfg.cycle_topic {
        log.channels.truncate(3);
    }
    // Blocks are emitted when full; keep file order = log_time order.
    log.messages.sort_by_key(|m| m.log_time);
    log
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::Params;

    #[test]
    fn tdc_times_solve_the_warp() {
        let cfg = SynthConfig::default();
        for (tau, n) in cfg.tdc_times() {
            let (th, _) = cfg.crank(tau);
            assert!((th - (PI + n as f64 * TAU)).abs() < 1e-9);
        }
        assert_eq!(cfg.tdc_times().len(), 10);
    }

    #[test]
    fn generates_in_time_order_with_the_right_counts() {
        let cfg = SynthConfig {
            revolutions: 2.0,
            ..SynthConfig::default()
        };
        let log = generate(&cfg, &IdealTruth::from_params(&Params::paper()));
        let per: Vec<usize> = (0..4)
            .map(|c| log.messages.iter().filter(|m| m.channel == c).count())
            .collect();
        let dur = cfg.duration_s();
        assert!((per[0] as f64 - dur * 5000.0).abs() <= 1.0);
        assert!((per[1] as f64 - dur * 10_000.0).abs() <= 1.0);
        assert_eq!(per[3], 2);
        assert!(
            log.messages
                .windows(2)
                .all(|w| w[0].log_time <= w[1].log_time)
        );
        let mut r = Rng::new(3);
        let x: Vec<f64> = (0..20000).map(|_| r.normal()).collect();
        let m = x.iter().sum::<f64>() / x.len() as f64;
        let v = x.iter().map(|a| (a - m).powi(2)).sum::<f64>() / x.len() as f64;
        assert!(m.abs() < 0.03 && (v - 1.0).abs() < 0.05);
    }
}
