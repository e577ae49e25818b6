//! The overlay report's own forms: the CSV tables, the PNG charts and the
//! text summary, and writing them all into a folder; the calibration
//! report's text summary ([`calibration_text`]; its JSON is the report
//! itself, its parameter file `params_toml`). Every face that writes
//! an overlay (the command line, batch exports, examples) goes through here.
//!
//! Files written by [`write_outputs`]:
//! - `overlay.json`: the whole [`OverlayReport`];
//! - `cycles.csv`: one row per measured cycle (residuals and figures);
//! - `run.csv`: the per-run residuals (`key,value,unit`);
//! - `figures.csv`: measured against predicted statistics of every figure;
//! - `curves.csv`: per crank angle, the ideal stroke, the measured and the
//!   predicted bands and the residual of the mean curves;
//! - `overlay_stroke.png`, `overlay_force.png`: measured vs predicted with
//!   the residual beneath.

use super::calibrate::CalibrationReport;
use super::compare::OverlayReport;
use crate::plot::{self, LineChart, Panel, Series, SeriesStyle};
use anyhow::anyhow;
use std::fmt::Write as _;
use std::path::Path;

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

/// Writes every output file into `dir`: staged, then committed together at
/// the end (`crate::output`), so a folder holds the old complete report or
/// the new one, never a mix.
pub fn write_outputs(dir: &Path, r: &OverlayReport) -> anyhow::Result<()> {
    let mut out = crate::output::Report::new_in(dir)?;
    let mut write = |name: &str, text: &str| -> anyhow::Result<()> {
        out.add(name, text.as_bytes())?;
        Ok(())
    };
    // Without the prediction's wall-clock time: a re-run writes the same bytes.
    let json =
        crate::output::json::to_vec_pretty_without(r, crate::output::json::NOT_REPRODUCIBLE)?;
    write("overlay.json", &String::from_utf8(json)?)?;
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

/// The calibration report's text summary (what `pinsight calibrate`
/// prints): each estimate with its σ and U95, the F_ins table, the residual
/// before and after, the notes.
pub fn calibration_text(r: &CalibrationReport) -> String {
    let mut s = String::new();
    let _ = writeln!(
        s,
        "calibrate {}: {} cycles at {:.1} rpm",
        r.file, r.cycles, r.motor_rpm
    );
    let _ = writeln!(
        s,
        "  {:<14} {:>10} {:>12} {:>10} {:>10}  unit",
        "estimate", "nominal", "value", "σ", "U95"
    );
    for e in &r.estimates {
        let _ = writeln!(
            s,
            "  {:<14} {:>10} {:>12.5} {:>10.5} {:>10.5}  {}",
            e.name,
            e.nominal.map_or("-".to_string(), |v| format!("{v:.4}")),
            e.value,
            e.sigma,
            e.u95,
            e.unit
        );
    }
    if !r.f_ins_table.is_empty() {
        let _ = writeln!(s, "  F_ins table (depth mm → N ± σ):");
        for (d, f, sg) in &r.f_ins_table {
            let _ = writeln!(s, "    {d:>6.3} → {f:>8.3} ± {sg:.3}");
        }
    }
    let _ = writeln!(
        s,
        "  residual before: stroke spread {:.4} mm, stroke mean {:.4} mm, force {:.3} N",
        r.before.stroke_spread_rms_mm, r.before.stroke_mean_rms_mm, r.before.force_rms_n
    );
    let _ = writeln!(
        s,
        "  residual after:  stroke spread {:.4} mm, stroke mean {:.4} mm, force {:.3} N",
        r.after.stroke_spread_rms_mm, r.after.stroke_mean_rms_mm, r.after.force_rms_n
    );
    for n in &r.notes {
        let _ = writeln!(s, "  note: {n}");
    }
    s
}
