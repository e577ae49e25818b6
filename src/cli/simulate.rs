//! `pinsight simulate`: one run, an ensemble, or the demo summary.

use super::common::ParamArgs;
use crate::cli::common::outln;
use crate::model::params::Params;
use crate::panes::fmt_opt;
use crate::progress::{Progress, ProgressBarGuard};
use crate::sim::ensemble::{EnsembleResult, run_ensemble};
use crate::sim::fidelity::{FidelityReport, SceneResolution, assess};
use crate::sim::{Level, LevelChoice, SimOptions, SimResult, simulate};
use anyhow::{Context, anyhow};
use serde_json::{Value, json};
use std::io::Write;
use std::path::PathBuf;
use std::process::ExitCode;

#[derive(Debug, clap::Args)]
pub struct Args {
    #[command(flatten)]
    pub params: ParamArgs,
    /// Fidelity level: auto (cheapest sufficient), kinematic, ideal, clearance or motor.
    #[arg(long, default_value = "clearance")]
    pub level: String,
    #[command(flatten)]
    pub solver: super::common::SolverArgs,
    /// Fixed step in seconds (RK4: default period/20000; adaptive methods: turns error control off).
    #[arg(long, value_parser = super::common::bounds::step_s)]
    pub step: Option<f64>,
    /// Warm-up revolutions before the reported window (fractional allowed).
    #[arg(long, default_value_t = 2.0, value_parser = super::common::bounds::warmup)]
    pub warmup: f64,
    /// Reported revolutions (fractional allowed). `--warmup 0 --revs 0.5` is the deterministic window.
    #[arg(long, default_value_t = 3.0, value_parser = super::common::bounds::revs)]
    pub revs: f64,
    /// Run N realisations from start offsets k·1 nm and report statistics of every figure.
    #[arg(long, value_name = "N", value_parser = super::common::bounds::ensemble)]
    pub ensemble: Option<usize>,
    /// Also estimate the prediction horizon (two realisations 1 nm apart).
    #[arg(long)]
    pub horizon: bool,
    /// Write the reported revolutions on a 0.5° crank-angle grid as CSV.
    #[arg(long, value_name = "FILE")]
    pub csv: Option<PathBuf>,
    /// Crank-angle spacing of the CSV grid in degrees.
    #[arg(long, default_value_t = 0.5, value_parser = super::common::bounds::grid_deg)]
    pub grid_deg: f64,
    /// Stroke resolution of the scene for `--level auto`, mm.
    #[arg(long, default_value_t = 0.002, value_parser = super::common::bounds::resolution)]
    pub resolution_mm: f64,
    /// Force resolution of the scene for `--level auto`, N.
    #[arg(long, default_value_t = 0.05, value_parser = super::common::bounds::resolution)]
    pub force_resolution_n: f64,
    /// Crank-speed resolution of the scene for `--level auto`: the smallest
    /// first harmonic of the speed per cycle the spindle channel resolves, %.
    #[arg(long, default_value_t = 0.05, value_parser = super::common::bounds::resolution)]
    pub speed_resolution_pct: f64,
    /// Print one JSON object instead of the text summary.
    #[arg(long)]
    pub json: bool,
    /// Also write the run (state at every grid step, contact events, summary) as MCAP for Foxglove.
    #[arg(long, value_name = "FILE")]
    pub mcap: Option<PathBuf>,
}

pub fn run(args: Args) -> anyhow::Result<ExitCode> {
    let p = args.params.resolve()?;
    let method = args.solver.method()?;
    let choice = LevelChoice::parse(&args.level).ok_or_else(|| {
        anyhow!(
            "invalid --level `{}` (allowed: auto, kinematic, ideal, clearance, motor)",
            args.level
        )
    })?;
    let fidelity = match choice {
        LevelChoice::Auto => Some(assess(
            &p,
            SceneResolution {
                stroke_mm: args.resolution_mm,
                force_n: args.force_resolution_n,
                needs_forces: true,
                speed_pct: args.speed_resolution_pct,
            },
            method,
        )?),
        LevelChoice::Fixed(_) => None,
    };
    let level = match (&fidelity, choice) {
        (Some(f), _) => f.chosen,
        (None, LevelChoice::Fixed(l)) => l,
        (None, LevelChoice::Auto) => Level::Clearance,
    };
    let opts = SimOptions {
        level,
        method,
        rtol: args.solver.rtol,
        atol: args.solver.atol,
        step: args.step,
        warmup: args.warmup,
        revs: args.revs,
        grid_deg: (args.csv.is_some() || args.mcap.is_some()).then_some(args.grid_deg),
        record_events: true,
        ..SimOptions::default()
    };
    opts.validate()?;
    let progress = Progress::new(1000);
    let _bar = (!args.json).then(|| ProgressBarGuard::start(progress.clone(), "simulate"));
    let result = simulate(&p, &opts, &progress)?;
    let ensemble = match args.ensemble {
        Some(n) if n > 1 && matches!(level, Level::Clearance | Level::Motor) => {
            Some(run_ensemble(&p, &opts, n, 1e-9, args.horizon, &progress)?)
        }
        _ => None,
    };
    let horizon = match (
        &ensemble,
        args.horizon && matches!(level, Level::Clearance | Level::Motor),
    ) {
        (Some(e), _) => e.horizon,
        (None, true) => Some(crate::sim::ensemble::prediction_horizon(&p, &opts, 1e-9)?),
        _ => None,
    };
    drop(_bar);
    if let (Some(path), Some(curves)) = (&args.csv, &result.curves) {
        let mut buf = Vec::new();
        curves
            .write_csv(&mut buf)
            .with_context(|| format!("writing {}", path.display()))?;
        crate::output::write_file(path, &buf)?;
    }
    if let Some(path) = &args.mcap {
        let bytes = crate::export::mcap::simulation::simulation_mcap(&result)
            .map_err(|e| anyhow!("{}: {e}", path.display()))?;
        crate::output::write_file(path, &bytes)?;
    }
    if args.json {
        let v = to_json(
            &p,
            &result,
            ensemble.as_ref(),
            horizon.as_ref(),
            fidelity.as_ref(),
        );
        outln!("{}", serde_json::to_string_pretty(&v)?)?;
    } else {
        let mut out = crate::cli::common::stdout();
        write_text(
            &mut out,
            &p,
            &opts,
            &result,
            ensemble.as_ref(),
            horizon.as_ref(),
            fidelity.as_ref(),
        )?;
        if let Some(path) = &args.csv {
            writeln!(
                out,
                "curves: {} ({} rows)",
                path.display(),
                result.curves.as_ref().map_or(0, |c| c.len())
            )?;
        }
    }
    Ok(ExitCode::SUCCESS)
}

/// The `--json` object: every summary field at the top level (ensemble
/// means when an ensemble ran), plus notes, events count, ensemble block,
/// horizon and the fidelity report.
pub fn to_json(
    p: &Params,
    r: &SimResult,
    ensemble: Option<&EnsembleResult>,
    horizon: Option<&crate::sim::ensemble::Horizon>,
    fidelity: Option<&FidelityReport>,
) -> Value {
    let mut v = serde_json::to_value(&r.summary).unwrap_or(Value::Null);
    if let Value::Object(m) = &mut v {
        m.insert("offset_mm".into(), json!(p.offset * 1e3));
        m.insert("notes".into(), json!(r.notes));
        if let Some(e) = ensemble {
            for f in &e.figures {
                if f.figure == "impacts_per_rev" {
                    continue;
                }
                m.insert(f.figure.clone(), json!(f.stats.mean));
            }
            m.insert(
                "n_impacts".into(),
                json!(e.stats("impacts_per_rev").map(|s| s.mean * r.summary.revs)),
            );
            m.insert("steps".into(), json!(e.steps));
            m.insert("rhs_evals".into(), json!(e.rhs_evals));
            m.insert("wall_ms".into(), json!(e.wall_ms));
            m.insert(
                "view".into(),
                json!(format!("ensemble mean of {} realisations", e.realisations)),
            );
            m.insert(
                "ensemble".into(),
                json!({
                    "realisations": e.realisations,
                    "perturbation_m": e.perturbation_m,
                    "figures": e.figures,
                }),
            );
        }
        if let Some(h) = horizon {
            m.insert("horizon".into(), json!(h));
        }
        if let Some(f) = fidelity {
            m.insert("fidelity".into(), json!(f));
        }
    }
    v
}

#[allow(clippy::too_many_arguments)]
fn write_text<W: Write>(
    out: &mut W,
    p: &Params,
    opts: &SimOptions,
    r: &SimResult,
    ensemble: Option<&EnsembleResult>,
    horizon: Option<&crate::sim::ensemble::Horizon>,
    fidelity: Option<&FidelityReport>,
) -> std::io::Result<()> {
    let s = &r.summary;
    writeln!(
        out,
        "pinsight simulate — preset {}, level {} ({}), {} rpm, clearance {:.3} mm, {}, {} (ce {})",
        s.preset,
        s.level,
        if s.level == "clearance" || s.level == "motor" {
            format!("{} rtol {:.0e}", s.method, s.rtol)
        } else {
            "closed form".into()
        },
        p.motor_rpm,
        s.clearance_mm,
        s.material,
        s.contact_model,
        p.restitution
    )?;
    if let Some(f) = fidelity {
        writeln!(out, "level auto → {}: {}", f.chosen.name(), f.reason)?;
    }
    writeln!(
        out,
        "window: {} warm-up + {} reported revolutions — {}",
        crate::fmt::plain(opts.warmup),
        crate::fmt::plain(opts.revs),
        s.view
    )?;
    if s.view == "single realisation" {
        writeln!(
            out,
            "  the clearance motion is chaotic: this is one trajectory; compare statistics (--ensemble N), not values"
        )?;
    }
    let row = |out: &mut W, name: &str, v: String, ideal: String| {
        writeln!(out, "  {name:<30} {v:>16} {ideal:>16}")
    };
    writeln!(out, "  {:<30} {:>16} {:>16}", "figure", "value", "ideal")?;
    row(out, "impacts", s.n_impacts.to_string(), "0".into())?;
    row(
        out,
        "peak |acceleration| (m/s²)",
        format!("{:.3}", s.peak_accel_mps2),
        format!("{:.3}", s.ideal_peak_accel_mps2),
    )?;
    row(
        out,
        "peak contact force (N)",
        format!("{:.3}", s.peak_contact_force_n),
        "–".into(),
    )?;
    row(
        out,
        "mean |Δs| (mm)",
        format!("{:.6}", s.disp_dev_mean_mm),
        "0".into(),
    )?;
    row(
        out,
        "max |Δs| (mm)",
        format!("{:.6}", s.disp_dev_max_mm),
        "0".into(),
    )?;
    row(
        out,
        "mean |Δv| (m/s)",
        format!("{:.6}", s.vel_dev_mean_mps),
        "0".into(),
    )?;
    row(
        out,
        "max |Δv| (m/s)",
        format!("{:.6}", s.vel_dev_max_mps),
        "0".into(),
    )?;
    row(
        out,
        "peak |M12| (N·m)",
        fmt_opt(s.peak_torque_nm, 4),
        fmt_opt(s.ideal_peak_torque_nm, 4),
    )?;
    row(
        out,
        "RMS ΔM12 (N·m)",
        fmt_opt(s.torque_dev_rms_nm, 4),
        "0".into(),
    )?;
    row(
        out,
        "stroke min / max (mm)",
        format!("{:.4} / {:.4}", s.stroke_min_mm, s.stroke_max_mm),
        "".into(),
    )?;
    row(
        out,
        "peak load-cell force (N)",
        fmt_opt(s.peak_process_force_n, 3),
        "".into(),
    )?;
    if let Some(m) = &s.motor {
        write_motor(out, m)?;
    }
    writeln!(
        out,
        "work: {} steps ({} rejected), {} rhs + {} aux evaluations, {:.2} ms",
        s.steps, s.rejected_steps, s.rhs_evals, s.aux_evals, s.wall_ms
    )?;
    if let Some(e) = ensemble {
        writeln!(
            out,
            "ensemble: {} realisations (start offsets k·{:.0e} m), {:.1} ms",
            e.realisations, e.perturbation_m, e.wall_ms
        )?;
        writeln!(
            out,
            "  {:<24} {:>14} {:>12} {:>14} {:>14}",
            "figure", "mean", "std", "min", "max"
        )?;
        for f in &e.figures {
            let st = f.stats;
            writeln!(
                out,
                "  {:<24} {:>14.6} {:>12.4e} {:>14.6} {:>14.6}",
                f.figure, st.mean, st.std, st.min, st.max
            )?;
        }
    }
    if let Some(h) = horizon {
        match h.revs {
            Some(n) => writeln!(
                out,
                "prediction horizon: {n:.2} revolutions (realisations {:.0e} m apart differ by {:.4} mm at rtol {:.0e})",
                h.perturbation_m, h.threshold_mm, h.rtol
            )?,
            None => writeln!(
                out,
                "prediction horizon: > {} revolutions (no separation by {:.4} mm)",
                h.span_revs, h.threshold_mm
            )?,
        }
    }
    for n in &r.notes {
        writeln!(out, "note: {n}")?;
    }
    Ok(())
}

/// The motor level's figures: speed and ripple, the motor's duty, and
/// where its work went.
fn write_motor<W: Write>(
    out: &mut W,
    m: &crate::sim::motor_run::MotorSummary,
) -> std::io::Result<()> {
    let opt = |v: Option<f64>, d: usize| v.map_or("–".to_string(), |x| format!("{x:.d$}"));
    writeln!(
        out,
        "motor ({} curve, speed control {}): drive inertia {:.3e} kg m² at the crank{}",
        m.curve,
        m.control,
        m.drive_inertia_kgm2,
        m.no_load_rpm
            .map(|n| format!(", no-load speed {n:.1} rev/min"))
            .unwrap_or_default()
    )?;
    writeln!(
        out,
        "  crank speed {:.2} rev/min mean ({:.2} … {:.2}; operating point {:.2})",
        m.mean_crank_rpm, m.min_crank_rpm, m.max_crank_rpm, m.operating_crank_rpm
    )?;
    writeln!(
        out,
        "  speed ripple {:.3} % peak-to-peak, first harmonic {} % (peak at {}° after TDC)",
        m.ripple_p2p_pct,
        opt(m.ripple_h1_pct, 3),
        opt(m.ripple_h1_phase_deg, 0)
    )?;
    writeln!(
        out,
        "  motor torque peak {:.4} N·m, RMS {:.4} N·m (curve at the mean speed {:.4} N·m), mean power {:.3} W",
        m.peak_motor_torque_nm,
        m.rms_motor_torque_nm,
        m.curve_torque_at_mean_nm,
        m.mean_motor_power_w
    )?;
    let e = &m.energy;
    writeln!(
        out,
        "  energy (J): motor {:.6} = process {:.6} + guide {:.6} + impacts/joint {:.6} + gear {:.6} + Δkinetic {:.6} + Δpotential {:.6} + Δelastic {:.2e} (residual {:.1e})",
        e.motor_work_j,
        e.process_work_j,
        e.guide_friction_j,
        e.impact_and_joint_friction_j,
        e.gear_loss_j,
        e.kinetic_change_j,
        e.potential_change_j,
        e.elastic_change_j,
        e.residual_j
    )
}

/// `pinsight` with no arguments (no TTY): the demo summary — the paper
/// preset over the default protocol, with its prediction horizon.
pub fn run_demo() -> anyhow::Result<ExitCode> {
    let p = Params::paper();
    let opts = SimOptions {
        record_events: true,
        ..SimOptions::default()
    };
    let r = simulate(&p, &opts, &Progress::hidden())?;
    let h = crate::sim::ensemble::prediction_horizon(&p, &opts, 1e-9)?;
    let mut out = crate::cli::common::stdout();
    writeln!(
        out,
        "pinsight demo (embedded): the `paper` pin-insertion head at 1200 rpm"
    )?;
    write_text(&mut out, &p, &opts, &r, None, Some(&h), None)?;
    writeln!(
        out,
        "\nrun `pinsight --help` for the commands (simulate, sweep, log, overlay, inspect, yield, …)"
    )?;
    Ok(ExitCode::SUCCESS)
}
