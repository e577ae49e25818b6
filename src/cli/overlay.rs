//! `pinsight overlay LOG.mcap [--params FILE] [--set k=v]... [--level L]
//! [--cycles A..B] [--out DIR] [--json]`: the log's measured cycles against
//! the model's predicted ensemble (see [`crate::overlay::compare`]).
//!
//! Outputs in `--out DIR` (created):
//! - `overlay.json`: the whole [`OverlayReport`];
//! - `cycles.csv`: one row per measured cycle (residuals and figures);
//! - `run.csv`: the per-run residuals (`key,value,unit`);
//! - `figures.csv`: measured against predicted statistics of every figure;
//! - `curves.csv`: per crank angle, the ideal stroke, the measured and the
//!   predicted bands and the residual of the mean curves;
//! - `overlay_stroke.png`, `overlay_force.png`: measured vs predicted with
//!   the residual beneath.
//!
//! Without `--out` only the summary (or with `--json` the report) is printed.

use super::common::ParamArgs;
use crate::cli::common::{outln, outp};
use crate::model::Params;
use crate::model::kinematics::Geometry;
use crate::overlay::compare::{OverlayOptions, OverlayReport, model_params, overlay};
use crate::plot::{self, LineChart, Panel, Series, SeriesStyle};
use crate::progress::{Progress, ProgressBarGuard};
use crate::rig::cycles::{CycleOptions, CycleSet, analyse};
use crate::rig::{ChannelMap, LoadOptions, RigLog, load};
use crate::sim::LevelChoice;
use anyhow::{Context, anyhow, bail};
use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::process::ExitCode;

#[derive(Debug, clap::Args)]
pub struct Args {
    /// The rig log (MCAP).
    #[arg(value_name = "LOG.mcap")]
    pub log: PathBuf,
    #[command(flatten)]
    pub params: ParamArgs,
    /// Fidelity level of the prediction: clearance (default: the ensemble), ideal, kinematic, or auto.
    #[arg(long, default_value = "clearance")]
    pub level: String,
    /// Cycle indices to compare, `A..B` (B exclusive; either end may be left out).
    #[arg(long, value_name = "A..B")]
    pub cycles: Option<String>,
    /// Output directory for JSON, CSV and PNG files.
    #[arg(long, value_name = "DIR")]
    pub out: Option<PathBuf>,
    /// Print the report as JSON on stdout.
    #[arg(long)]
    pub json: bool,
    /// Channel map (TOML) for a rig that names its topics differently.
    #[arg(long, value_name = "MAP.toml")]
    pub channels: Option<PathBuf>,
    /// Override a `rig` metadata key, e.g. --meta laser_zero_mm=10.0 (repeatable).
    #[arg(long = "meta", value_name = "KEY=VALUE")]
    pub meta: Vec<String>,
    /// Simulated revolutions in the predicted ensemble (clearance level).
    #[arg(long, default_value_t = 40)]
    pub revs: usize,
    /// Revolutions simulated before the ensemble.
    #[arg(long, default_value_t = 3.0)]
    pub warmup: f64,
    /// Integrator relative tolerance of the prediction.
    #[arg(long, default_value_t = 1e-6)]
    pub rtol: f64,
    /// Relative spread of cycle speeds above which cycles are predicted per speed group (0.01 = 1 %).
    #[arg(long, default_value_t = 0.01)]
    pub speed_threshold: f64,
    /// First-order lag of the displacement sensor (µs), applied to the prediction.
    #[arg(long, default_value_t = 0.0)]
    pub laser_lag_us: f64,
    /// First-order lag of the load cell (µs), applied to the prediction.
    #[arg(long, default_value_t = 0.0)]
    pub force_lag_us: f64,
    /// Crank-angle grid points per revolution.
    #[arg(long, default_value_t = 720)]
    pub points: usize,
}

/// Parses `A..B`, `A..`, `..B` (cycle indices, B exclusive).
pub fn parse_cycle_range(s: &str) -> anyhow::Result<(u64, u64)> {
    let (a, b) = s
        .split_once("..")
        .ok_or_else(|| anyhow!("--cycles '{s}': expected A..B (e.g. 3..10)"))?;
    let num = |x: &str, d: u64| -> anyhow::Result<u64> {
        let x = x.trim();
        if x.is_empty() {
            Ok(d)
        } else {
            x.parse::<u64>()
                .map_err(|_| anyhow!("--cycles '{s}': '{x}' is not a cycle index"))
        }
    };
    let (a, b) = (num(a, 0)?, num(b, u64::MAX)?);
    if b <= a {
        bail!("--cycles '{s}': the range is empty");
    }
    Ok((a, b))
}

/// Load options from `--channels` and `--meta`.
pub fn load_options(channels: Option<&Path>, meta: &[String]) -> anyhow::Result<LoadOptions> {
    let mut opts = LoadOptions::default();
    if let Some(p) = channels {
        opts.channel_map = ChannelMap::from_file(p)?;
    }
    for kv in meta {
        let (k, v) = kv
            .split_once('=')
            .with_context(|| format!("--meta '{kv}': expected KEY=VALUE"))?;
        opts.meta_overrides
            .insert(k.trim().to_string(), v.trim().to_string());
    }
    Ok(opts)
}

/// Loads the log and delimits its cycles with the model's geometry. A log
/// that loads with no usable signal is an error naming the file.
pub fn load_and_cycles(
    path: &Path,
    opts: &LoadOptions,
    params: &ParamArgs,
    points: usize,
    show_progress: bool,
) -> anyhow::Result<(RigLog, Option<Params>, CycleSet)> {
    // The parameter file (without the --set overrides, applied after the metadata).
    let file_params = if params.params.is_some() || params.preset.is_some() {
        Some(
            ParamArgs {
                sets: Vec::new(),
                ..params.clone()
            }
            .resolve()?,
        )
    } else {
        None
    };
    let progress = Progress::new(0);
    let log = {
        let _bar = show_progress.then(|| ProgressBarGuard::start(progress.clone(), "loading"));
        load(path, opts, &progress).map_err(|e| anyhow!("{e}"))?
    };
    let geom_params = file_params.clone().unwrap_or_else(Params::paper);
    let cs = analyse(
        &log,
        &CycleOptions {
            geometry: Geometry::of(&geom_params),
            points_per_rev: points.max(8),
            ..CycleOptions::default()
        },
    );
    if log.signals.displacement.is_none() {
        bail!(
            "{}: no displacement channel ({}): the stroke cannot be compared",
            path.display(),
            log.report
                .findings
                .iter()
                .map(|f| f.message.clone())
                .collect::<Vec<_>>()
                .join("; ")
        );
    }
    Ok((log, file_params, cs))
}

pub fn run(args: Args) -> anyhow::Result<ExitCode> {
    let cycles = args.cycles.as_deref().map(parse_cycle_range).transpose()?;
    let level = match LevelChoice::parse(&args.level) {
        Some(LevelChoice::Fixed(l)) => Some(l),
        Some(LevelChoice::Auto) => None,
        None => bail!(
            "invalid --level `{}` (allowed: auto, kinematic, ideal, clearance)",
            args.level
        ),
    };
    if !(args.rtol > 0.0 && args.rtol < 1.0) {
        bail!("--rtol {} must lie in (0, 1)", args.rtol);
    }
    if !(args.laser_lag_us >= 0.0 && args.force_lag_us >= 0.0) {
        bail!("--laser-lag-us and --force-lag-us must be ≥ 0");
    }
    if !(args.speed_threshold >= 0.0) {
        bail!("--speed-threshold must be ≥ 0");
    }
    let lopts = load_options(args.channels.as_deref(), &args.meta)?;
    let (log, file_params, cs) =
        load_and_cycles(&args.log, &lopts, &args.params, args.points, !args.json)?;
    let (params, notes) = model_params(&log, file_params, &args.params.sets)
        .map_err(|e| anyhow!("{}: {e}", args.log.display()))?;
    let mut extra_notes = Vec::new();
    let level = match level {
        Some(l) => l,
        None => {
            let f = crate::sim::fidelity::assess(
                &params,
                crate::sim::fidelity::SceneResolution {
                    stroke_mm: 0.002,
                    force_n: 0.05,
                    needs_forces: true,
                },
                crate::solver::Method::Dop853,
            )?;
            extra_notes.push(format!("--level auto chose {}", f.chosen.name()));
            f.chosen
        }
    };
    let mut opts = OverlayOptions {
        speed_threshold: args.speed_threshold,
        cycles,
        ..OverlayOptions::default()
    };
    opts.predict.level = level;
    opts.predict.revs = args.revs.max(2);
    opts.predict.warmup = args.warmup;
    opts.predict.rtol = args.rtol;
    opts.predict.laser_lag_s = args.laser_lag_us * 1e-6;
    opts.predict.force_lag_s = args.force_lag_us * 1e-6;
    let progress = Progress::new(0);
    let mut report = {
        let _bar = (!args.json).then(|| ProgressBarGuard::start(progress.clone(), "overlay"));
        overlay(&log, &cs, &params, notes, &opts, &progress)?
    };
    report.notes.extend(extra_notes);
    if let Some(dir) = &args.out {
        write_outputs(dir, &report)?;
    }
    if args.json {
        outln!("{}", serde_json::to_string_pretty(&report)?)?;
    } else {
        outp!("{}", summary_text(&report, args.out.as_deref()))?;
    }
    Ok(ExitCode::SUCCESS)
}

fn f(v: f64) -> String {
    if v.is_finite() {
        format!("{v:.6}")
    } else {
        String::new()
    }
}

/// The per-cycle CSV.
pub fn cycles_csv(r: &OverlayReport) -> String {
    let mut s = String::from(
        "index,t_start_ns,motor_rpm,group,stroke_rms_err_mm,stroke_max_err_mm,stroke_err_tdc_mm,stroke_err_bdc_mm,force_rms_err_n,stroke_in_band,stroke_in_2sigma,force_in_band,force_in_2sigma,depth_mm,stroke_max_mm,stroke_min_mm,peak_force_n,disp_dev_mean_mm,disp_dev_max_mm,vel_dev_mean_mps,vel_dev_max_mps\n",
    );
    for c in &r.cycles {
        let m = &c.measured;
        let cols = [
            c.motor_rpm,
            c.group as f64,
            c.stroke_rms_err_mm,
            c.stroke_max_err_mm,
            c.stroke_err_tdc_mm,
            c.stroke_err_bdc_mm,
            c.force_rms_err_n,
            c.stroke_in_band,
            c.stroke_in_2sigma,
            c.force_in_band,
            c.force_in_2sigma,
            m.depth_mm,
            m.stroke_max_mm,
            m.stroke_min_mm,
            m.peak_force_n,
            m.disp_dev_mean_mm,
            m.disp_dev_max_mm,
            m.vel_dev_mean_mps,
            m.vel_dev_max_mps,
        ];
        let _ = write!(s, "{},{}", c.index, c.t_start_ns);
        for v in cols {
            let _ = write!(s, ",{}", f(v));
        }
        s.push('\n');
    }
    s
}

/// The per-run residuals as `key,value,unit` rows.
pub fn run_csv(r: &OverlayReport) -> String {
    let u = &r.run;
    let rows: [(&str, f64, &str); 13] = [
        ("cycles", u.cycles as f64, ""),
        ("stroke_mean_rms_mm", u.stroke_mean_rms_mm, "mm"),
        ("stroke_mean_max_mm", u.stroke_mean_max_mm, "mm"),
        ("force_mean_rms_n", u.force_mean_rms_n, "N"),
        ("force_mean_max_n", u.force_mean_max_n, "N"),
        ("stroke_rms_err_mm", u.stroke_rms_err_mm, "mm"),
        ("force_rms_err_n", u.force_rms_err_n, "N"),
        ("stroke_in_band", u.stroke_in_band, "fraction"),
        ("stroke_in_2sigma", u.stroke_in_2sigma, "fraction"),
        ("force_in_band", u.force_in_band, "fraction"),
        ("force_in_2sigma", u.force_in_2sigma, "fraction"),
        ("noise_stroke_mm", r.noise_stroke_mm, "mm"),
        ("noise_force_n", r.noise_force_n, "N"),
    ];
    let mut s = String::from("key,value,unit\n");
    for (k, v, unit) in rows {
        let _ = writeln!(s, "{k},{},{unit}", f(v));
    }
    s
}

/// Measured against predicted statistics of every figure.
pub fn figures_csv(r: &OverlayReport) -> String {
    let mut s = String::from(
        "figure,unit,measured_n,measured_mean,measured_std,measured_min,measured_max,predicted_n,predicted_mean,predicted_std,predicted_min,predicted_max,difference,z\n",
    );
    for c in &r.figures {
        let (m, p) = (&c.measured, &c.predicted);
        let _ = writeln!(
            s,
            "{},{},{},{},{},{},{},{},{},{},{},{},{},{}",
            c.figure,
            c.unit,
            m.n,
            f(m.mean),
            f(m.std),
            f(m.min),
            f(m.max),
            p.n,
            f(p.mean),
            f(p.std),
            f(p.min),
            f(p.max),
            f(c.difference),
            f(c.z)
        );
    }
    s
}

/// Per crank angle: ideal stroke, measured and predicted bands, residuals.
pub fn curves_csv(r: &OverlayReport) -> String {
    let mut s = String::from(
        "crank_deg,ideal_stroke_mm,measured_stroke_mean_mm,measured_stroke_std_mm,measured_stroke_min_mm,measured_stroke_max_mm,predicted_stroke_mean_mm,predicted_stroke_std_mm,predicted_stroke_min_mm,predicted_stroke_max_mm,residual_stroke_mm,measured_force_mean_n,measured_force_std_n,measured_force_min_n,measured_force_max_n,predicted_force_mean_n,predicted_force_std_n,predicted_force_min_n,predicted_force_max_n,residual_force_n\n",
    );
    let at = |v: &Vec<f64>, j: usize| v.get(j).copied().unwrap_or(f64::NAN);
    for (j, deg) in r.grid_deg.iter().enumerate() {
        let (ms, ps, mf, pf) = (
            &r.measured_stroke,
            &r.predicted_stroke,
            &r.measured_force,
            &r.predicted_force,
        );
        let cols = [
            *deg,
            at(&r.ideal_stroke_mm, j),
            at(&ms.mean, j),
            at(&ms.std, j),
            at(&ms.min, j),
            at(&ms.max, j),
            at(&ps.mean, j),
            at(&ps.std, j),
            at(&ps.min, j),
            at(&ps.max, j),
            at(&r.residual_stroke_mm, j),
            at(&mf.mean, j),
            at(&mf.std, j),
            at(&mf.min, j),
            at(&mf.max, j),
            at(&pf.mean, j),
            at(&pf.std, j),
            at(&pf.min, j),
            at(&pf.max, j),
            at(&r.residual_force_n, j),
        ];
        let line: Vec<String> = cols.iter().map(|v| f(*v)).collect();
        s.push_str(&line.join(","));
        s.push('\n');
    }
    s
}

/// The two panels (measured vs predicted, residual beneath) of one quantity.
/// `force` selects the force (N) instead of the stroke (mm). Plain data.
pub fn overlay_panels(r: &OverlayReport, force: bool) -> Vec<Panel> {
    let (pred, meas, resid, unit, what) = if force {
        (
            &r.predicted_force,
            &r.measured_force,
            &r.residual_force_n,
            "N",
            "force",
        )
    } else {
        (
            &r.predicted_stroke,
            &r.measured_stroke,
            &r.residual_stroke_mm,
            "mm",
            "stroke",
        )
    };
    let x = &r.grid_deg;
    let pts = |v: &[f64]| -> Vec<(f64, f64)> {
        x.iter()
            .zip(v)
            .filter(|(_, y)| y.is_finite())
            .map(|(a, b)| (*a, *b))
            .collect()
    };
    let finite_band = |lo: Vec<f64>, hi: Vec<f64>| -> (Vec<f64>, Vec<f64>, Vec<f64>) {
        let mut xs = Vec::new();
        let mut l = Vec::new();
        let mut h = Vec::new();
        for j in 0..x.len().min(lo.len()).min(hi.len()) {
            if lo[j].is_finite() && hi[j].is_finite() {
                xs.push(x[j]);
                l.push(lo[j]);
                h.push(hi[j]);
            }
        }
        (xs, l, h)
    };
    let mut bands = Vec::new();
    let (bx, bl, bh) = finite_band(pred.min.clone(), pred.max.clone());
    bands.push(plot::Band {
        label: "predicted min–max".into(),
        x: bx,
        lower: bl,
        upper: bh,
        color: Some(0),
    });
    let lo2: Vec<f64> = pred
        .mean
        .iter()
        .zip(&pred.std)
        .map(|(m, s)| m - 2.0 * s)
        .collect();
    let hi2: Vec<f64> = pred
        .mean
        .iter()
        .zip(&pred.std)
        .map(|(m, s)| m + 2.0 * s)
        .collect();
    let (bx, bl, bh) = finite_band(lo2, hi2);
    bands.push(plot::Band {
        label: "predicted mean ± 2σ".into(),
        x: bx,
        lower: bl,
        upper: bh,
        color: Some(1),
    });
    let mut series = Vec::new();
    if !force {
        series.push(
            Series::line("ideal mechanism", pts(&r.ideal_stroke_mm))
                .with_style(SeriesStyle::Dashed)
                .with_color(7),
        );
    }
    let shown = &r.sample_cycles;
    for (n, c) in shown.iter().enumerate() {
        let label = if n == 0 {
            format!(
                "measured cycles ({} of {} drawn)",
                shown.len(),
                r.run.cycles
            )
        } else {
            String::new()
        };
        let row = if force { &c.force_n } else { &c.stroke_mm };
        series.push(Series::line(label, pts(row)).with_color(3));
    }
    series.push(Series::line("measured mean", pts(&meas.mean)).with_color(2));
    series.push(Series::line("predicted mean", pts(&pred.mean)).with_color(1));
    let main = LineChart {
        title: format!(
            "{what}: measured ({} cycles) vs predicted ({}, c = {:.3} mm)",
            r.run.cycles, r.level, r.clearance_mm
        ),
        x_label: "crank angle from TDC (deg)".into(),
        y_label: format!("{what} ({unit})"),
        series,
        bands,
        x_range: Some((0.0, 360.0)),
        ..LineChart::default()
    };
    let lo: Vec<f64> = pred.std.iter().map(|s| -2.0 * s).collect();
    let hi: Vec<f64> = pred.std.iter().map(|s| 2.0 * s).collect();
    let (bx, bl, bh) = finite_band(lo, hi);
    let residual = LineChart {
        title: format!("residual of the mean {what} (measured − predicted)"),
        x_label: "crank angle from TDC (deg)".into(),
        y_label: format!("residual ({unit})"),
        series: vec![Series::line("measured mean − predicted mean", pts(resid)).with_color(2)],
        bands: vec![plot::Band {
            label: "± 2σ of the prediction".into(),
            x: bx,
            lower: bl,
            upper: bh,
            color: Some(1),
        }],
        x_range: Some((0.0, 360.0)),
        ..LineChart::default()
    };
    vec![Panel::Line(main), Panel::Line(residual)]
}

/// Writes every output file into `dir`.
pub fn write_outputs(dir: &Path, r: &OverlayReport) -> anyhow::Result<()> {
    // Staged, then committed together at the end (crate::output).
    let mut out = crate::output::Report::new_in(dir)?;
    let mut write = |name: &str, text: &str| -> anyhow::Result<()> {
        out.add(name, text.as_bytes())?;
        Ok(())
    };
    write("overlay.json", &serde_json::to_string_pretty(r)?)?;
    write("cycles.csv", &cycles_csv(r))?;
    write("run.csv", &run_csv(r))?;
    write("figures.csv", &figures_csv(r))?;
    write("curves.csv", &curves_csv(r))?;
    for (force, name) in [(false, "overlay_stroke.png"), (true, "overlay_force.png")] {
        if force && r.measured_force.mean.iter().all(|v| !v.is_finite()) {
            continue;
        }
        let panels = overlay_panels(r, force);
        let p = dir.join(name);
        let png = plot::render_png(&panels, 1, 1200, 1000)
            .map_err(|e| anyhow!("{}: {e}", p.display()))?;
        out.add(name, &png)?;
    }
    out.commit()?;
    Ok(())
}

/// The text summary.
pub fn summary_text(r: &OverlayReport, out: Option<&Path>) -> String {
    let mut s = String::new();
    let u = &r.run;
    let _ = writeln!(s, "overlay {}", r.file);
    let _ = writeln!(
        s,
        "  model: level {}, clearance {:.3} mm, standoff {:.3} mm; {} speed group(s): {}",
        r.level,
        r.clearance_mm,
        r.standoff_mm,
        r.groups.len(),
        r.groups
            .iter()
            .map(|g| format!(
                "{:.1} rpm ({} cycles, {} revs)",
                g.motor_rpm, g.cycles, g.prediction.revs
            ))
            .collect::<Vec<_>>()
            .join(", ")
    );
    let _ = writeln!(s, "  cycles compared: {}", u.cycles);
    let _ = writeln!(
        s,
        "  stroke: mean-curve residual RMS {:.4} mm (max {:.4}); per-cycle RMS {:.4} mm; inside band {:.1} %, inside ±2σ {:.1} %",
        u.stroke_mean_rms_mm,
        u.stroke_mean_max_mm,
        u.stroke_rms_err_mm,
        100.0 * u.stroke_in_band,
        100.0 * u.stroke_in_2sigma
    );
    if u.force_mean_rms_n.is_finite() {
        let _ = writeln!(
            s,
            "  force:  mean-curve residual RMS {:.3} N (max {:.3}); per-cycle RMS {:.3} N; inside band {:.1} %, inside ±2σ {:.1} %",
            u.force_mean_rms_n,
            u.force_mean_max_n,
            u.force_rms_err_n,
            100.0 * u.force_in_band,
            100.0 * u.force_in_2sigma
        );
    }
    let _ = writeln!(
        s,
        "  {:<20} {:>22} {:>22} {:>8}",
        "figure", "measured mean ± std", "predicted mean ± std", "z"
    );
    for c in &r.figures {
        let _ = writeln!(
            s,
            "  {:<20} {:>10.4} ± {:<9.4} {:>10.4} ± {:<9.4} {:>8.1}  {}",
            c.figure,
            c.measured.mean,
            c.measured.std,
            c.predicted.mean,
            c.predicted.std,
            c.z,
            c.unit
        );
    }
    for n in r.params_notes.iter().chain(&r.notes) {
        let _ = writeln!(s, "  note: {n}");
    }
    if let Some(d) = out {
        let _ = writeln!(
            s,
            "  wrote {}/{{overlay.json, cycles.csv, run.csv, figures.csv, curves.csv, overlay_stroke.png, overlay_force.png}}",
            d.display()
        );
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cycle_ranges() {
        assert_eq!(parse_cycle_range("3..10").unwrap(), (3, 10));
        assert_eq!(parse_cycle_range("..4").unwrap(), (0, 4));
        assert_eq!(parse_cycle_range("5..").unwrap(), (5, u64::MAX));
        assert!(parse_cycle_range("5").is_err());
        assert!(parse_cycle_range("5..5").is_err());
        assert!(parse_cycle_range("a..5").is_err());
    }
}
