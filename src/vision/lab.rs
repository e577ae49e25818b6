//! The vision part of the methods lab: speed against pin-centre error for
//! the localisers, and how detection rate, verdict accuracy and centre
//! error degrade with noise, blur, contrast and rotation — on images from
//! the generator ([`super::synth`]) whose truth is exact.
//!
//! Entry points: [`run_lab`] (plain tables, `Serialize`) and
//! [`lab_panels`] (charts for `pinsight::plot`). [`LabMode::Quick`] runs in
//! a few seconds (for CI); [`LabMode::Full`] uses more scenes and levels.

use super::InspectOptions;
use super::gray::{GrayData, Plane};
use super::measure::{Localiser, Roi, measure_blob};
use super::recipe::Recipe;
use super::result::{PinStatus, Verdict};
use super::synth::{Damage, Rng, Scene};
use super::truth;
use crate::plot::{LineChart, Panel, Series, SeriesStyle};
use crate::progress::Progress;
use serde::Serialize;
use std::time::Instant;

/// How much work the lab does.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum LabMode {
    /// Seconds: 2 scenes per level, few levels.
    Quick,
    /// Minutes: 12 scenes per level, finer levels.
    Full,
}

/// One localiser at one noise level: centre error and cost.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct LocaliserRow {
    pub localiser: Localiser,
    pub noise_dn: f64,
    /// RMS centre error of intact pins, px.
    pub rms_px: f64,
    /// 95th percentile of the centre error, px.
    pub p95_px: f64,
    pub pins: usize,
    /// Median time of one tip measurement (region copy, threshold, labels,
    /// levels and the centre), microseconds.
    pub time_us_per_pin: f64,
}

/// One degradation level: what the whole pipeline still gets right.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct DegradeRow {
    /// "noise" (σ, DN), "blur" (σ, px), "contrast" (fraction), "rotation" (deg).
    pub factor: String,
    pub level: f64,
    pub localiser: Localiser,
    pub images: usize,
    /// Present pins found / present pins.
    pub detection_rate: f64,
    /// Images with the right verdict / images (errors count as wrong).
    pub verdict_accuracy: f64,
    /// Pins with the right status / pins, over the images inspected.
    pub status_accuracy: f64,
    /// Images that could not be inspected at all.
    pub errors: usize,
    pub rms_px: Option<f64>,
}

/// Everything the lab measured.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct VisionLab {
    pub mode: LabMode,
    pub part_number: String,
    pub speed_accuracy: Vec<LocaliserRow>,
    pub degradation: Vec<DegradeRow>,
    pub notes: Vec<String>,
}

fn lab_recipe() -> Recipe {
    // The interop 2 × 10 header (0.64 mm square tips, 2.54 mm pitch).
    let text = r#"
part_number = "LAB-2x10-2.54"
view = "top"
rows = 2
cols = 10
pitch_mm = [2.54, 2.54]
pin_mm = 0.64
pin_shape = "square"
polarity = "bright"
mm_per_px = 0.03
[tolerance]
position_mm = 0.10
tip_area = [0.6, 1.5]
"#;
    // The text is a constant and valid.
    Recipe::from_toml_str(text, "lab").unwrap_or_else(|e| panic!("{e}"))
}

/// A scene with a random pose and, on odd seeds, one defect.
fn scene(r: &Recipe, seed: u64) -> Scene {
    let mut rng = Rng::new(seed);
    let mut sc = Scene::nominal(r, r.mm_per_px.unwrap_or(0.03));
    sc.randomise(&mut rng, 4.0, 20.0, 0.8);
    sc.seed = seed;
    if seed % 2 == 1 {
        let k = (rng.uniform() * sc.pins.len() as f64) as usize % sc.pins.len();
        match seed % 6 {
            1 => sc.pins[k].present = false,
            3 => sc.pins[k].offset_mm = (0.16, -0.1),
            _ => sc.pins[k].damage = Damage::Scaled(0.66),
        }
    }
    sc
}

fn percentile(v: &mut [f64], q: f64) -> f64 {
    if v.is_empty() {
        return f64::NAN;
    }
    v.sort_by(|a, b| a.total_cmp(b));
    v[((v.len() - 1) as f64 * q).round() as usize]
}

/// Speed and centre error of each localiser on intact pins, measured on the
/// tips alone (ROI around the true centre), at each noise level.
fn speed_accuracy(
    r: &Recipe,
    noises: &[f64],
    scenes: u64,
    progress: &Progress,
) -> Vec<LocaliserRow> {
    let mut rows = Vec::new();
    let pin_px = r.pin_mm / r.mm_per_px.unwrap_or(0.03);
    for &noise in noises {
        let mut per: Vec<(Vec<f64>, Vec<f64>)> =
            vec![(Vec::new(), Vec::new()); Localiser::ALL.len()];
        for s in 0..scenes {
            if progress.is_cancelled() {
                return rows;
            }
            let mut sc = scene(r, 2 * s);
            sc.noise_dn = noise;
            let (g, t) = sc.render();
            let GrayData::U8(d) = &g.data else { continue };
            let plane = Plane {
                w: g.width as usize,
                h: g.height as usize,
                data: d.as_slice(),
            };
            for p in t.pins.iter().filter(|p| p.defect == PinStatus::Ok) {
                let (Some(x), Some(y)) = (p.x_px, p.y_px) else {
                    continue;
                };
                let half = 0.5 * pin_px;
                let roi = Roi::around(
                    x - half,
                    y - half,
                    x + half,
                    y + half,
                    0.45 * pin_px,
                    plane.w,
                    plane.h,
                );
                for (li, loc) in Localiser::ALL.iter().enumerate() {
                    let t0 = Instant::now();
                    let m = measure_blob(&plane, 1.0, roi, (x, y), *loc, 3, None);
                    let dt = t0.elapsed().as_secs_f64() * 1e6;
                    if let Some(m) = m {
                        per[li].0.push((m.x - x).hypot(m.y - y));
                        per[li].1.push(dt);
                    }
                }
            }
            progress.inc(1);
        }
        for (li, loc) in Localiser::ALL.iter().enumerate() {
            let (errs, times) = &mut per[li];
            let rms = (errs.iter().map(|e| e * e).sum::<f64>() / errs.len().max(1) as f64).sqrt();
            rows.push(LocaliserRow {
                localiser: *loc,
                noise_dn: noise,
                rms_px: rms,
                p95_px: percentile(errs, 0.95),
                pins: errs.len(),
                time_us_per_pin: percentile(times, 0.5),
            });
        }
    }
    rows
}

fn degrade(
    r: &Recipe,
    factor: &str,
    levels: &[f64],
    scenes: u64,
    localisers: &[Localiser],
    progress: &Progress,
) -> Vec<DegradeRow> {
    let mut out = Vec::new();
    for &level in levels {
        let renders: Vec<_> = (0..scenes)
            .map(|s| {
                let mut sc = scene(r, 1000 + s);
                sc.noise_dn = 2.0;
                match factor {
                    "noise" => sc.noise_dn = level,
                    "blur" => sc.blur_px = level,
                    "contrast" => sc.contrast = level,
                    _ => sc.rotation_deg = level * if s % 2 == 0 { 1.0 } else { -1.0 },
                }
                sc.render()
            })
            .collect();
        for loc in localisers {
            let opts = InspectOptions { localiser: *loc };
            let (mut found, mut present, mut vok, mut sok, mut pins, mut errors) =
                (0, 0, 0, 0, 0, 0);
            let mut sq = Vec::new();
            for (g, t) in &renders {
                present += t
                    .pins
                    .iter()
                    .filter(|p| p.defect != PinStatus::Missing)
                    .count();
                match super::inspect_gray(r, g, Default::default(), &opts) {
                    Err(_) => errors += 1,
                    Ok(ins) => {
                        let c = truth::compare(&ins, t, 15.0);
                        found += t
                            .pins
                            .iter()
                            .filter(|tp| tp.defect != PinStatus::Missing)
                            .filter(|tp| {
                                ins.pins
                                    .iter()
                                    .any(|p| p.row == tp.row && p.col == tp.col && p.x_px.is_some())
                            })
                            .count();
                        if c.verdict_ok {
                            vok += 1;
                        }
                        pins += t.pins.len();
                        sok += t.pins.len() - c.status_mismatches.len();
                        sq.extend(
                            c.centre_errors
                                .iter()
                                .filter(|e| e.2 == PinStatus::Ok)
                                .map(|e| e.3 * e.3 + e.4 * e.4),
                        );
                    }
                }
            }
            out.push(DegradeRow {
                factor: factor.to_string(),
                level,
                localiser: *loc,
                images: renders.len(),
                detection_rate: found as f64 / present.max(1) as f64,
                verdict_accuracy: vok as f64 / renders.len().max(1) as f64,
                status_accuracy: if pins > 0 {
                    sok as f64 / pins as f64
                } else {
                    0.0
                },
                errors,
                rms_px: (!sq.is_empty()).then(|| (sq.iter().sum::<f64>() / sq.len() as f64).sqrt()),
            });
        }
        progress.inc(1);
    }
    out
}

/// A degradation axis and its levels.
type Axis = (&'static str, Vec<f64>);

/// Runs the lab. Cancelling `progress` returns what was measured so far.
pub fn run_lab(mode: LabMode, progress: &Progress) -> VisionLab {
    let r = lab_recipe();
    let (scenes, noises, deg): (u64, Vec<f64>, Vec<Axis>) = match mode {
        LabMode::Quick => (
            2,
            vec![0.0, 8.0, 24.0],
            vec![
                ("noise", vec![0.0, 64.0, 128.0, 256.0]),
                ("blur", vec![0.0, 4.0, 8.0, 20.0]),
                ("contrast", vec![1.0, 0.05, 0.02, 0.01]),
                ("rotation", vec![0.0, 8.0, 20.0]),
            ],
        ),
        LabMode::Full => (
            12,
            vec![0.0, 2.0, 4.0, 8.0, 16.0, 32.0],
            vec![
                (
                    "noise",
                    vec![
                        0.0, 4.0, 8.0, 16.0, 24.0, 32.0, 48.0, 64.0, 96.0, 128.0, 192.0, 256.0,
                    ],
                ),
                (
                    "blur",
                    vec![0.0, 0.5, 1.0, 1.5, 2.0, 3.0, 4.0, 6.0, 8.0, 20.0],
                ),
                (
                    "contrast",
                    vec![1.0, 0.5, 0.25, 0.15, 0.1, 0.07, 0.05, 0.03, 0.02, 0.01],
                ),
                ("rotation", vec![0.0, 2.5, 5.0, 8.0, 11.0, 14.0, 20.0, 30.0]),
            ],
        ),
    };
    let total = noises.len() as u64 * scenes + deg.iter().map(|d| d.1.len() as u64).sum::<u64>();
    progress.set_total(total);
    let speed = speed_accuracy(&r, &noises, scenes, progress);
    let mut degradation = Vec::new();
    for (factor, levels) in &deg {
        if progress.is_cancelled() {
            break;
        }
        degradation.extend(degrade(
            &r,
            factor,
            levels,
            scenes,
            &Localiser::ALL,
            progress,
        ));
    }
    VisionLab {
        mode,
        part_number: r.part_number.clone(),
        speed_accuracy: speed,
        degradation,
        notes: vec![
            "Scenes: 2 × 10 header, 0.64 mm square tips, 0.03 mm/px, random pose (±4°, ±20 px), blur 0–0.8 px, small pin offsets; odd seeds carry one defect (missing, bent or shrunk).".into(),
            "Speed/accuracy: each localiser measures every intact tip in a region around its true centre; the time is one tip measurement (levels, threshold, labels and the centre).".into(),
            "Degradation: the whole pipeline per localiser (detection, grid fit, verdicts); noise σ in 8-bit DN (base 2 DN when another factor varies), blur σ in px, contrast as a fraction of the nominal levels, rotation in degrees (the lattice search accepts ±12°).".into(),
        ],
    }
}

/// Chart panels of the lab: error and time per localiser against noise, and
/// detection rate, verdict accuracy and error against each degradation.
pub fn lab_panels(lab: &VisionLab) -> Vec<Panel> {
    let mut panels = Vec::new();
    let by_loc = |f: &dyn Fn(&LocaliserRow) -> (f64, f64)| -> Vec<Series> {
        Localiser::ALL
            .iter()
            .map(|l| {
                Series::line(
                    l.name(),
                    lab.speed_accuracy
                        .iter()
                        .filter(|r| r.localiser == *l)
                        .map(f)
                        .collect(),
                )
                .with_style(SeriesStyle::LinePoints)
            })
            .collect()
    };
    panels.push(Panel::Line(LineChart {
        title: "Centre error against noise".into(),
        x_label: "noise σ (DN)".into(),
        y_label: "RMS error (px)".into(),
        series: by_loc(&|r| (r.noise_dn, r.rms_px.max(1e-4))),
        log_y: true,
        ..Default::default()
    }));
    panels.push(Panel::Line(LineChart {
        title: "Speed against error (each point a noise level)".into(),
        x_label: "time per tip (µs)".into(),
        y_label: "RMS error (px)".into(),
        series: by_loc(&|r| (r.time_us_per_pin, r.rms_px.max(1e-4))),
        log_y: true,
        ..Default::default()
    }));
    for factor in ["noise", "blur", "contrast", "rotation"] {
        let unit = match factor {
            "noise" => "noise σ (DN)",
            "blur" => "blur σ (px)",
            "contrast" => "contrast (fraction)",
            _ => "rotation (deg)",
        };
        let rows: Vec<&DegradeRow> = lab
            .degradation
            .iter()
            .filter(|r| r.factor == factor)
            .collect();
        if rows.is_empty() {
            continue;
        }
        let mut series = Vec::new();
        for l in Localiser::ALL {
            let pts = |f: &dyn Fn(&DegradeRow) -> f64| -> Vec<(f64, f64)> {
                rows.iter()
                    .filter(|r| r.localiser == l)
                    .map(|r| (r.level, f(r)))
                    .collect()
            };
            series.push(
                Series::line(
                    format!("verdicts, {}", l.name()),
                    pts(&|r| r.verdict_accuracy),
                )
                .with_style(SeriesStyle::LinePoints),
            );
            if l == Localiser::Coverage {
                series.push(
                    Series::line("detection rate", pts(&|r| r.detection_rate))
                        .with_style(SeriesStyle::Dashed),
                );
            }
        }
        panels.push(Panel::Line(LineChart {
            title: format!("Pipeline against {factor}"),
            x_label: unit.into(),
            y_label: "fraction right (–)".into(),
            series,
            y_range: Some((0.0, 1.05)),
            ..Default::default()
        }));
    }
    panels
}

/// Whether a verdict is a pass (helper for callers summarising the lab).
pub fn is_pass(v: Verdict) -> bool {
    v == Verdict::Pass
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn quick_lab_ranks_localisers_and_finds_breaking_points() {
        let lab = run_lab(LabMode::Quick, &Progress::hidden());
        let at = |l: Localiser, n: f64| {
            lab.speed_accuracy
                .iter()
                .find(|r| r.localiser == l && r.noise_dn == n)
                .map(|r| r.rms_px)
                .unwrap()
        };
        // Exact truth: on clean images the coverage centroid beats the
        // binary centroid (quantised by the pixel grid).
        assert!(at(Localiser::Coverage, 0.0) < at(Localiser::Centroid, 0.0));
        assert!(at(Localiser::Coverage, 0.0) < 0.05);
        // The pipeline is right on undegraded images.

        for f in ["noise", "blur", "contrast", "rotation"] {
            let first = lab
                .degradation
                .iter()
                .find(|r| r.factor == f && r.localiser == Localiser::Coverage)
                .unwrap();
            assert_eq!(first.verdict_accuracy, 1.0, "{f} at {}", first.level);
        }
        // Each axis of the quick sweep reaches a level where the pipeline
        // is no longer right: noise 256 DN, blur 20 px, contrast 1 %,
        // rotation 20° (beyond the lattice search's ±12°).
        for f in ["noise", "blur", "contrast", "rotation"] {
            let last = lab
                .degradation
                .iter()
                .rfind(|r| r.factor == f && r.localiser == Localiser::Coverage)
                .unwrap();
            assert!(
                last.verdict_accuracy < 1.0 && last.status_accuracy < 0.5,
                "{f} at {}: verdicts {}, statuses {}",
                last.level,
                last.verdict_accuracy,
                last.status_accuracy
            );
        }
        let panels = lab_panels(&lab);
        assert_eq!(panels.len(), 6);
        assert!(crate::plot::render_png(&panels, 2, 900, 900).is_ok());
    }
}
