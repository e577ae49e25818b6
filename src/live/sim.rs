//! `pinsight rig-sim`: a rig that writes its log in real time (or N times
//! faster), for demos and tests of the live mode.
//!
//! The log follows rig-log.md: JSON messages, zstd chunks written by the
//! `mcap` crate's streaming writer and finished every `flush_s` of log time
//! (a chunk in progress has the crate's placeholder length until then), the
//! footer only at the end. The signals are [`crate::rig::synth`]'s sensor
//! models over a truth made of:
//! - the stroke: the ideal mechanism plus the clearance joint's deviation,
//!   simulated with the clearance model ([`crate::rig::synth::ModelTruth`])
//!   for [`MODEL_REVS`] revolutions at the chosen speed and clearance and
//!   replayed in a loop (the motion is chaotic: a loop of realisations, not
//!   one cycle repeated). A worn joint (`wear=`) scales the deviation with
//!   the clearance reached (c(t)/c₀; the deviation grows about linearly
//!   with c at a given speed: an approximation, said in docs/live.md);
//! - the load cell: each cycle's insertion drawn by
//!   [`crate::rig::synth::faults`] (part-to-part spread, faults);
//! - connector photographs from [`crate::process::synth`] (one per cycle,
//!   the fault's signature, debris), written as PNG files into a folder
//!   (rename into place) and/or on the camera topic.
//!
//! Faults (`--faults`, comma-separated): `nok=0.05` (fault rate per
//! cycle), `burst@10s-20s` (every cycle faulty), `wear=0.2mm/h`,
//! `debris=0.02`, `corrupt@30s` (a byte of the chunk written then is
//! flipped on its way to the disk), `stop=force@40s-45s` (a sensor
//! stops; also `displacement`, `angle`).

use crate::model::Params;
use crate::model::kinematics::Geometry;
use crate::process::synth::{IMAGE_SCHEMA, connector_scene, png_of};
use crate::rig::channel_map::SignalKind;
use crate::rig::synth::faults::{CycleDraw, DrawStream, FaultRates, insertion_force};
use crate::rig::synth::{
    Dropout, IdealTruth, ModelTruth, SynthChannel, SynthConfig, Truth, default_channels,
    generate_until,
};
use crate::vision::Recipe;
use crate::vision::result::Verdict;
use mcap::records::{MessageHeader, Metadata};
use serde::Serialize;
use std::collections::{BTreeMap, HashMap, VecDeque};
use std::f64::consts::{PI, TAU};
use std::io::{BufWriter, Seek, SeekFrom, Write};
use std::path::{Path, PathBuf};
use std::sync::Mutex;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};

/// Revolutions of the clearance model replayed in a loop.
pub const MODEL_REVS: usize = 60;
/// The recipe of the simulated connector (a 1 × 6 side view).
pub const RECIPE: &str = include_str!("../../fixtures/vision/side-1x6.toml");

/// Faults to inject.
#[derive(Debug, Clone, Default, PartialEq, Serialize)]
pub struct FaultSpec {
    pub nok_rate: f64,
    /// Windows (s of log time) in which every cycle is faulty.
    pub bursts: Vec<(f64, f64)>,
    pub wear_mm_per_h: f64,
    pub debris_rate: f64,
    pub corrupt_at_s: Option<f64>,
    pub stops: Vec<(SignalKind, f64, f64)>,
}

impl FaultSpec {
    pub fn parse(spec: &str) -> Result<Self, String> {
        let mut f = FaultSpec::default();
        let dur = super::parse_duration;
        let range = |r: &str| -> Result<(f64, f64), String> {
            let (a, b) = r
                .split_once('-')
                .ok_or_else(|| format!("`{r}`: a window is FROM-TO, e.g. 10s-20s"))?;
            let (a, b) = (dur(a)?, dur(b)?);
            if b <= a {
                return Err(format!("`{r}`: the window ends before it starts"));
            }
            Ok((a, b))
        };
        let num = |v: &str, what: &str| -> Result<f64, String> {
            v.trim()
                .parse::<f64>()
                .ok()
                .filter(|x| x.is_finite() && *x >= 0.0)
                .ok_or_else(|| format!("{what}: `{v}` is not a non-negative number"))
        };
        for part in spec.split(',').map(str::trim).filter(|p| !p.is_empty()) {
            if let Some(v) = part.strip_prefix("nok=") {
                f.nok_rate = num(v, "nok")?.min(1.0);
            } else if let Some(v) = part.strip_prefix("debris=") {
                f.debris_rate = num(v, "debris")?.min(1.0);
            } else if let Some(v) = part.strip_prefix("wear=") {
                let v = v.strip_suffix("mm/h").unwrap_or(v);
                f.wear_mm_per_h = num(v, "wear")?;
            } else if let Some(r) = part.strip_prefix("burst@") {
                f.bursts.push(range(r)?);
            } else if let Some(t) = part.strip_prefix("corrupt@") {
                f.corrupt_at_s = Some(dur(t)?);
            } else if let Some(v) = part.strip_prefix("stop=") {
                let (sig, r) = v
                    .split_once('@')
                    .ok_or_else(|| format!("`{part}`: stop=SIGNAL@FROM-TO"))?;
                let k = match sig {
                    "force" => SignalKind::Force,
                    "displacement" => SignalKind::Displacement,
                    "angle" | "spindle" => SignalKind::Angle,
                    o => {
                        return Err(format!(
                            "stop: unknown signal `{o}` (force, displacement, angle)"
                        ));
                    }
                };
                let (a, b) = range(r)?;
                f.stops.push((k, a, b));
            } else {
                return Err(format!(
                    "unknown fault `{part}` (nok=RATE, burst@FROM-TO, wear=MM/h, debris=RATE, corrupt@T, stop=SIGNAL@FROM-TO)"
                ));
            }
        }
        Ok(f)
    }
}

/// What to simulate.
#[derive(Debug, Clone)]
pub struct SimOptions {
    pub out: PathBuf,
    pub rpm: f64,
    pub clearance_mm: f64,
    /// Log seconds per wall second (1 = real time; infinite = as fast as possible).
    pub rate: f64,
    pub duration_s: f64,
    /// Folder the connector photographs are written to.
    pub images: Option<PathBuf>,
    /// Photographs also on the log's camera topic.
    pub images_in_log: bool,
    /// Distinct photographs rendered per fault kind (0: one per cycle).
    pub image_pool: usize,
    pub faults: FaultSpec,
    pub seed: u64,
    pub flush_s: f64,
    /// A new file every this many seconds of log time.
    pub rotate_s: Option<f64>,
    pub spindle_hz: f64,
    pub force_hz: f64,
    pub displacement_hz: f64,
    pub lot: String,
    /// Keep every connector's truth in the report (`--truth`): one entry
    /// per cycle, so off unless asked for (a shift is 720 000 connectors).
    pub record_truth: bool,
    /// Told of every finished chunk (benchmarks: the flush-to-screen
    /// latency of the live mode starts here).
    pub on_flush: Option<std::sync::mpsc::Sender<FlushMark>>,
}

/// A chunk finished and flushed to the file.
#[derive(Debug, Clone, Copy)]
pub struct FlushMark {
    /// Log time of the newest sample (spindle, force, displacement) in it.
    pub sample_ns: u64,
    /// When the flush returned.
    pub at: Instant,
}

impl Default for SimOptions {
    fn default() -> Self {
        SimOptions {
            out: PathBuf::from("run.mcap"),
            rpm: 1200.0,
            clearance_mm: 0.1,
            rate: 1.0,
            duration_s: 60.0,
            images: None,
            images_in_log: false,
            image_pool: 8,
            faults: FaultSpec::default(),
            seed: 1,
            flush_s: 0.25,
            rotate_s: None,
            spindle_hz: 5000.0,
            force_hz: 10_000.0,
            displacement_hz: 10_000.0,
            lot: "LIVE".into(),
            record_truth: false,
            on_flush: None,
        }
    }
}

/// A pooled photograph: the fault drawn, debris, the variant.
type PoolKey = (
    Option<crate::rig::synth::faults::InsertionFault>,
    bool,
    usize,
);

/// One connector as written.
#[derive(Debug, Clone, Serialize)]
pub struct SimConnector {
    pub file: String,
    pub cycle: u64,
    pub fault: Option<crate::rig::synth::faults::InsertionFault>,
    pub debris: bool,
    pub vision: Option<Verdict>,
}

/// What was written.
#[derive(Debug, Clone, Serialize)]
pub struct SimReport {
    pub files: Vec<String>,
    pub cycles: u64,
    pub messages: u64,
    pub images: u64,
    pub connectors: Vec<SimConnector>,
    pub faults: FaultSpec,
    pub wall_s: f64,
    pub warnings: Vec<String>,
}

/// The truth of the live line (see the module doc).
struct LiveTruth {
    ideal: IdealTruth,
    model: Option<ModelTruth>,
    tdc: f64,
    clearance_mm: f64,
    wear_mm_per_s: f64,
    first_tdc: i64,
    rev_s: f64,
    pins: u32,
    bursts: Vec<(f64, f64)>,
    nok_rate: f64,
    draws: Mutex<(DrawStream, VecDeque<CycleDraw>)>,
}

impl LiveTruth {
    /// The draw of cycle `k` (the `/rig/cycle` index).
    fn draw(&self, k: u64) -> Option<CycleDraw> {
        let mut g = self.draws.lock().ok()?;
        let (stream, cache) = &mut *g;
        while cache.back().is_none_or(|d| d.index < k) {
            let t = (cache.back().map_or(0, |d| d.index + 1)) as f64 * self.rev_s;
            let burst = self.bursts.iter().any(|(a, b)| t >= *a && t < *b);
            cache.push_back(stream.next_with_rate(if burst { 1.0 } else { self.nok_rate }));
            while cache.len() > 16 {
                cache.pop_front();
            }
        }
        cache.iter().find(|d| d.index == k).copied()
    }
}

impl Truth for LiveTruth {
    fn eval(&self, t: f64, theta2: f64, omega2: f64) -> (f64, f64) {
        let g = &self.ideal.geometry;
        let pose = g.pose(theta2, omega2, 0.0);
        let s = pose.x4 - g.x4_tdc();
        let mut stroke_mm = s * 1e3;
        if let Some(m) = &self.model {
            let span = MODEL_REVS as f64 * TAU;
            let th = self.tdc + (theta2 - self.tdc).rem_euclid(span);
            let dev = m.eval(0.0, th, omega2).0 - g.stroke_at(th) * 1e3;
            let c = self.clearance_mm + self.wear_mm_per_s * t;
            stroke_mm += dev * c / self.clearance_mm;
        }
        let rev = ((theta2 - self.tdc) / TAU).floor() as i64 - self.first_tdc;
        let f = match u64::try_from(rev).ok().and_then(|k| self.draw(k)) {
            Some(d) => insertion_force(&self.ideal, self.pins, &d, s, pose.v4),
            None => self.ideal.eval(t, theta2, omega2).1,
        };
        (stroke_mm, f)
    }
}

/// The log's file writer: a file that can flip a byte on its way to the
/// disk (the `corrupt@` fault).
struct Disk {
    file: std::fs::File,
    flip: std::sync::Arc<AtomicBool>,
}

impl Write for Disk {
    fn write(&mut self, buf: &[u8]) -> std::io::Result<usize> {
        if buf.len() >= 1024 && self.flip.swap(false, Ordering::SeqCst) {
            let mut b = buf.to_vec();
            let i = b.len() / 2;
            b[i] ^= 0x5A;
            b[i + 1] ^= 0xA5;
            return self.file.write_all(&b).map(|_| buf.len());
        }
        self.file.write(buf)
    }
    fn flush(&mut self) -> std::io::Result<()> {
        self.file.flush()
    }
}

impl Seek for Disk {
    fn seek(&mut self, pos: SeekFrom) -> std::io::Result<u64> {
        self.file.seek(pos)
    }
}

type Mcap = mcap::Writer<BufWriter<Disk>>;

struct Out {
    w: Mcap,
    ids: Vec<u16>,
    seq: Vec<u32>,
}

impl Out {
    /// Writes one message on the `c`-th channel, numbered in sequence.
    fn message(
        &mut self,
        c: usize,
        log_time: u64,
        publish_time: u64,
        data: &[u8],
    ) -> Result<(), mcap::McapError> {
        self.seq[c] += 1;
        self.w.write_to_known_channel(
            &MessageHeader {
                channel_id: self.ids[c],
                sequence: self.seq[c],
                log_time,
                publish_time,
            },
            data,
        )
    }
}

fn file_name(out: &Path, part: Option<usize>) -> PathBuf {
    match part {
        None => out.to_path_buf(),
        Some(n) => {
            let stem = out
                .file_stem()
                .map(|s| s.to_string_lossy().to_string())
                .unwrap_or_default();
            out.with_file_name(format!("{stem}-{n:03}.mcap"))
        }
    }
}

fn open(
    path: &Path,
    meta: &BTreeMap<String, String>,
    chans: &[SynthChannel],
    flip: &std::sync::Arc<AtomicBool>,
) -> Result<Out, String> {
    let file = std::fs::File::create(path).map_err(|e| format!("{}: {e}", path.display()))?;
    let disk = Disk {
        file,
        flip: flip.clone(),
    };
    let err = |e: mcap::McapError| format!("{}: {e}", path.display());
    let mut w = mcap::WriteOptions::new()
        .compression(Some(mcap::Compression::Zstd))
        .use_chunks(true)
        .chunk_size(Some(64 << 20))
        .library(format!("pinsight-rig-sim/{}", env!("CARGO_PKG_VERSION")))
        .create(BufWriter::new(disk))
        .map_err(err)?;
    w.write_metadata(&Metadata {
        name: "rig".into(),
        metadata: meta.clone(),
    })
    .map_err(err)?;
    let mut ids = Vec::new();
    for c in chans {
        let sid = w
            .add_schema(&c.schema_name, &c.schema_encoding, c.schema.as_bytes())
            .map_err(err)?;
        ids.push(
            w.add_channel(sid, &c.topic, &c.message_encoding, &BTreeMap::new())
                .map_err(err)?,
        );
    }
    w.flush().map_err(err)?;
    Ok(Out {
        seq: vec![0; ids.len()],
        ids,
        w,
    })
}

/// Writes the line until `duration_s` of log time or until `stop` is set;
/// `progress` is told every log second.
pub fn run(opts: &SimOptions, stop: &AtomicBool) -> Result<SimReport, String> {
    let started = Instant::now();
    // A rig writes for a shift too (run K: 44 MB with glibc's defaults
    // against 23–25 MB with these settings in run J).
    crate::allocator::settle_for_a_shift();
    let params = Params::paper();
    let geom = Geometry::of(&params);
    let tdc = geom.tdc_angle();
    let cfg = SynthConfig {
        motor_rpm: opts.rpm,
        revolutions: opts.duration_s * opts.rpm / 60.0,
        spindle_hz: opts.spindle_hz,
        force_hz: opts.force_hz,
        displacement_hz: opts.displacement_hz,
        seed: opts.seed,
        start_ns: (std::time::SystemTime::now()
            .duration_since(std::time::UNIX_EPOCH)
            .map(|d| d.as_nanos() as u64)
            .unwrap_or(0))
            / 1_000_000
            * 1_000_000,
        force_drift_n: 0.0,
        dropouts: opts
            .faults
            .stops
            .iter()
            .map(|&(signal, from_s, to_s)| Dropout {
                signal,
                from_s,
                to_s,
            })
            .collect(),
        ..SynthConfig::default()
    };
    let recipe = Recipe::from_toml_str(RECIPE, "side-1x6 (embedded)").map_err(|e| e.to_string())?;
    // A calibrated rig: every zero in the metadata.
    let mut meta = cfg.rig_metadata();
    meta.insert("clearance_mm".into(), format!("{}", opts.clearance_mm));
    meta.insert("laser_zero_mm".into(), format!("{}", cfg.laser_zero_mm));
    meta.insert("force_tare_n".into(), format!("{}", cfg.force_tare_n));
    meta.insert(
        "angle_offset_rad".into(),
        format!("{}", cfg.encoder_offset_rad),
    );
    meta.insert("part_number".into(), recipe.part_number.clone());
    meta.insert("rig_id".into(), "rig-sim".into());
    meta.insert("lot".into(), opts.lot.clone());
    let model = if opts.clearance_mm > 0.0 {
        let mut p = params.clone();
        p.clearance = opts.clearance_mm * 1e-3;
        let mc = SynthConfig {
            motor_rpm: opts.rpm,
            revolutions: MODEL_REVS as f64 + 1.0,
            start_theta: tdc,
            speed_ripple: 0.0,
            ..SynthConfig::default()
        };
        Some(
            ModelTruth::simulate(&p, &mc, 3.0, 0.5, 1e-6)
                .map_err(|e| format!("clearance model: {e}"))?,
        )
    } else {
        None
    };
    let first_tdc = cfg.tdc_times().first().map_or(0, |x| x.1);
    let rev_s = 60.0 / opts.rpm;
    let rates = FaultRates {
        fault_rate: opts.faults.nok_rate,
        ..FaultRates::default()
    };
    let truth = LiveTruth {
        ideal: IdealTruth::from_params(&params),
        model,
        tdc,
        clearance_mm: opts.clearance_mm.max(1e-9),
        wear_mm_per_s: opts.faults.wear_mm_per_h / 3600.0,
        first_tdc,
        rev_s,
        pins: rates.pins,
        bursts: opts.faults.bursts.clone(),
        nok_rate: opts.faults.nok_rate,
        draws: Mutex::new((DrawStream::new(rates, opts.seed), VecDeque::new())),
    };
    let mut chans = default_channels(&cfg);
    let cam = chans.len();
    if opts.images_in_log {
        chans.push(SynthChannel {
            topic: crate::rig::images::CAMERA_TOPIC.into(),
            schema_name: "foxglove.CompressedImage".into(),
            schema_encoding: "jsonschema".into(),
            schema: IMAGE_SCHEMA.into(),
            message_encoding: "json".into(),
        });
    }
    if let Some(d) = &opts.images {
        std::fs::create_dir_all(d).map_err(|e| format!("{}: {e}", d.display()))?;
    }
    let flip = std::sync::Arc::new(AtomicBool::new(false));
    let mut part = opts.rotate_s.map(|_| 1usize);
    let mut path = file_name(&opts.out, part);
    let mut out = open(&path, &meta, &chans, &flip)?;
    let mut report = SimReport {
        files: vec![path.display().to_string()],
        cycles: 0,
        messages: 0,
        images: 0,
        connectors: Vec::new(),
        faults: opts.faults.clone(),
        wall_s: 0.0,
        warnings: Vec::new(),
    };
    let tdcs: Vec<f64> = cfg.tdc_times().into_iter().map(|x| x.0).collect();
    let mut next_image = 0usize; // connector k is photographed after tdcs[k + 1]
    let mut next_flush = opts.flush_s;
    let mut next_rotate = opts.rotate_s;
    let mut corrupt_at = opts.faults.corrupt_at_s;
    let mut newest_sample: Option<u64> = None;
    let mut debris_rng = crate::rng::SplitMix64::<0xDEB0_1500_0000_0018>::new(opts.seed);
    let mut pool: HashMap<PoolKey, (std::sync::Arc<Vec<u8>>, Verdict)> = HashMap::new();
    let mut error: Option<String> = None;
    let mut images_ok = opts.images.is_some();
    let stem = opts
        .out
        .file_stem()
        .map(|s| s.to_string_lossy().to_string())
        .unwrap_or_else(|| "run".into());
    let wall0 = Instant::now();
    let start_ns = cfg.start_ns;
    let pace = |lt_s: f64| {
        if opts.rate.is_finite() && opts.rate > 0.0 {
            let due = Duration::from_secs_f64(lt_s / opts.rate);
            let el = wall0.elapsed();
            if due > el {
                std::thread::sleep(due - el);
            }
        }
    };
    generate_until(&cfg, &truth, stop, |c, lt, pt, d| {
        if error.is_some() || stop.load(Ordering::Relaxed) {
            return;
        }
        let lt_s = (lt - start_ns) as f64 * 1e-9;
        // Photographs of the connectors finished by now (5 ms after the cycle).
        while next_image + 1 < tdcs.len() && tdcs[next_image + 1] + 0.005 <= lt_s {
            let k = next_image as u64;
            next_image += 1;
            let Some(dr) = truth.draw(k) else { continue };
            let debris = debris_rng.uniform() < opts.faults.debris_rate;
            if !(images_ok || opts.images_in_log) {
                if !opts.record_truth {
                    continue;
                }
                report.connectors.push(SimConnector {
                    file: path.display().to_string(),
                    cycle: k,
                    fault: dr.fault,
                    debris,
                    vision: None,
                });
                continue;
            }
            let key = (
                dr.fault,
                debris,
                if opts.image_pool == 0 {
                    k as usize
                } else {
                    k as usize % opts.image_pool
                },
            );
            let (png, verdict) = match pool.get(&key) {
                Some(v) => v.clone(),
                None => {
                    let sc = connector_scene(&recipe, &dr, debris, opts.seed ^ ((k + 1) << 20));
                    let (g, t) = sc.render();
                    let v = (std::sync::Arc::new(png_of(&g)), t.verdict);
                    if opts.image_pool > 0 {
                        pool.insert(key, v.clone());
                    }
                    v
                }
            };
            if opts.record_truth {
                report.connectors.push(SimConnector {
                    file: path.display().to_string(),
                    cycle: k,
                    fault: dr.fault,
                    debris,
                    vision: Some(verdict),
                });
            }
            report.images += 1;
            let img_lt = start_ns + ((tdcs[k as usize + 1] + 0.005) * 1e9).round() as u64;
            if opts.images_in_log {
                let data =
                    base64::Engine::encode(&base64::engine::general_purpose::STANDARD, &*png);
                let msg = serde_json::json!({
                    "timestamp": {"sec": img_lt / 1_000_000_000, "nsec": img_lt % 1_000_000_000},
                    "frame_id": format!("cycle-{k}"),
                    "format": "png",
                    "data": data,
                });
                if let Err(e) = out.message(cam, img_lt, img_lt, msg.to_string().as_bytes()) {
                    error = Some(e.to_string());
                }
            }
            if let (Some(dir), true) = (&opts.images, images_ok) {
                let f = dir.join(format!("{stem}-cycle-{k:07}.png"));
                if let Err(e) = crate::output::atomic::publish_file(&f, &png) {
                    images_ok = false;
                    report.warnings.push(format!("images stop: {e}"));
                }
            }
        }
        if lt_s >= next_flush {
            pace(next_flush);
            if corrupt_at.is_some_and(|t| lt_s >= t) {
                corrupt_at = None;
                flip.store(true, Ordering::SeqCst);
            }
            if let Err(e) = out.w.flush() {
                error = Some(e.to_string());
                return;
            }
            if let (Some(tx), Some(sample_ns)) = (&opts.on_flush, newest_sample) {
                let _ = tx.send(FlushMark {
                    sample_ns,
                    at: Instant::now(),
                });
            }
            next_flush += opts.flush_s;
        }
        if next_rotate.is_some_and(|r| lt_s >= r) {
            next_rotate = next_rotate.map(|r| r + opts.rotate_s.unwrap_or(f64::INFINITY));
            if let Err(e) = out.w.finish() {
                error = Some(e.to_string());
                return;
            }
            part = part.map(|n| n + 1);
            path = file_name(&opts.out, part);
            match open(&path, &meta, &chans, &flip) {
                Ok(o) => out = o,
                Err(e) => {
                    error = Some(e);
                    return;
                }
            }
            report.files.push(path.display().to_string());
        }
        if c >= 4 {
            return;
        }
        if c == 3 {
            report.cycles += 1;
        } else {
            newest_sample = Some(newest_sample.map_or(lt, |n| n.max(lt)));
        }
        report.messages += 1;
        if let Err(e) = out.message(c, lt, pt, d) {
            error = Some(e.to_string());
        }
    });
    if let Some(e) = error {
        return Err(format!("{}: {e}", path.display()));
    }
    out.w
        .finish()
        .map_err(|e| format!("{}: {e}", path.display()))?;
    report.wall_s = started.elapsed().as_secs_f64();
    let _ = PI;
    Ok(report)
}
