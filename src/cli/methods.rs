//! `pinsight methods [dynamics|vision]`: the methods lab.

use crate::cli::common::outln;
use crate::methods::Effort;
use crate::methods::dynamics::{DynamicsLab, run_dynamics_lab, scenes_from_toml};
use crate::output::Report;
use crate::plot::render_png;
use crate::progress::{Progress, ProgressBarGuard};
use crate::vision::lab::{LabMode, VisionLab, lab_panels, run_lab};
use anyhow::{Context, anyhow, bail};
use std::io::Write;
use std::path::{Path, PathBuf};
use std::process::ExitCode;

#[derive(Debug, clap::Args)]
pub struct Args {
    /// Which lab: dynamics or vision.
    #[arg(default_value = "dynamics")]
    pub lab: String,
    /// A TOML file of scenes ([[scene]] with name, preset, set = ["k=v", …]) for the dynamics lab.
    #[arg(long, value_name = "FILE")]
    pub scenes: Option<PathBuf>,
    /// Full study (minutes) instead of the quick one (seconds).
    #[arg(long)]
    pub full: bool,
    /// Output directory for the tables (JSON, CSV) and charts (PNG).
    #[arg(long, default_value = "pinsight-methods")]
    pub out: PathBuf,
    /// Print the JSON on stdout.
    #[arg(long)]
    pub json: bool,
}

pub fn run(args: Args) -> anyhow::Result<ExitCode> {
    let effort = if args.full {
        Effort::Full
    } else {
        Effort::Quick
    };
    match args.lab.as_str() {
        "dynamics" => run_dynamics(&args, effort),
        "vision" => run_vision(&args),
        other => Err(anyhow!("unknown lab `{other}` (allowed: dynamics, vision)")),
    }
}

fn run_dynamics(args: &Args, effort: Effort) -> anyhow::Result<ExitCode> {
    let custom = match &args.scenes {
        Some(path) => {
            let text = crate::input::read_text(path)
                .with_context(|| format!("reading {}", path.display()))?;
            Some(
                scenes_from_toml(&text)
                    .map_err(|e| anyhow!("scenes file {}: {e}", path.display()))?,
            )
        }
        None => None,
    };
    // Staged: the tables and charts replace an older set only when all
    // are written.
    let mut report = Report::new_in(&args.out)?;
    let progress = Progress::new(1);
    let lab = {
        let _bar = ProgressBarGuard::start(progress.clone(), "methods");
        run_dynamics_lab(effort, custom, &progress)
    };
    let json = serde_json::to_string_pretty(&lab)?;
    report.add("dynamics.json", json.as_bytes())?;
    write_tables(&mut report, &lab)?;
    for (name, panels, cols, w, h) in [
        (
            "work_precision.png",
            lab.work_precision_panels(),
            2,
            1500,
            1200,
        ),
        ("stability.png", lab.stability_panels(), 1, 1100, 750),
        ("long_run.png", lab.long_run_panels(), 2, 1500, 600),
        ("step_budget.png", lab.budget_panels(), 1, 1400, 600),
    ] {
        report.add(name, &render_png(&panels, cols, w, h)?)?;
    }
    report.commit()?;
    if args.json {
        outln!("{json}")?;
    } else {
        print_summary(&mut crate::cli::common::stdout(), &lab, &args.out)?;
    }
    Ok(ExitCode::SUCCESS)
}

fn run_vision(args: &Args) -> anyhow::Result<ExitCode> {
    if args.scenes.is_some() {
        bail!(
            "--scenes applies to the dynamics lab only (the vision lab generates its own exact-truth images)"
        );
    }
    let mode = if args.full {
        LabMode::Full
    } else {
        LabMode::Quick
    };
    let mut report = Report::new_in(&args.out)?;
    let progress = Progress::new(1);
    let lab = {
        let _bar = ProgressBarGuard::start(progress.clone(), "vision lab");
        run_lab(mode, &progress)
    };
    let json = serde_json::to_string_pretty(&lab)?;
    report.add("vision.json", json.as_bytes())?;
    write_vision_tables(&mut report, &lab)?;
    report.add(
        "vision_lab.png",
        &render_png(&lab_panels(&lab), 2, 1500, 1500)?,
    )?;
    report.commit()?;
    if args.json {
        outln!("{json}")?;
    } else {
        print_vision_summary(&mut crate::cli::common::stdout(), &lab, &args.out)?;
    }
    Ok(ExitCode::SUCCESS)
}

fn write_vision_tables(report: &mut Report, lab: &VisionLab) -> anyhow::Result<()> {
    let mut w = String::from("localiser,noise_dn,rms_px,p95_px,pins,time_us_per_pin\n");
    for r in &lab.speed_accuracy {
        w.push_str(&format!(
            "\"{}\",{},{},{},{},{}\n",
            r.localiser.name(),
            r.noise_dn,
            csv_f(r.rms_px),
            csv_f(r.p95_px),
            r.pins,
            csv_f(r.time_us_per_pin)
        ));
    }
    report.add("vision_speed_accuracy.csv", w.as_bytes())?;
    let mut w = String::from(
        "factor,level,localiser,images,detection_rate,verdict_accuracy,status_accuracy,errors,rms_px\n",
    );
    for r in &lab.degradation {
        w.push_str(&format!(
            "{},{},\"{}\",{},{},{},{},{},{}\n",
            r.factor,
            r.level,
            r.localiser.name(),
            r.images,
            csv_f(r.detection_rate),
            csv_f(r.verdict_accuracy),
            csv_f(r.status_accuracy),
            r.errors,
            r.rms_px.map(csv_f).unwrap_or_default()
        ));
    }
    report.add("vision_degradation.csv", w.as_bytes())?;
    Ok(())
}

fn print_vision_summary<W: Write>(out: &mut W, lab: &VisionLab, dir: &Path) -> std::io::Result<()> {
    writeln!(
        out,
        "pinsight methods vision ({:?}) — part {}",
        lab.mode, lab.part_number
    )?;
    writeln!(out, "speed against pin-centre error (exact truth):")?;
    writeln!(
        out,
        "  {:<30} {:>8} {:>9} {:>9} {:>6} {:>10}",
        "localiser", "noise DN", "RMS px", "p95 px", "pins", "µs/pin"
    )?;
    for r in &lab.speed_accuracy {
        writeln!(
            out,
            "  {:<30} {:>8} {:>9.4} {:>9.4} {:>6} {:>10.2}",
            r.localiser.name(),
            r.noise_dn,
            r.rms_px,
            r.p95_px,
            r.pins,
            r.time_us_per_pin
        )?;
    }
    writeln!(
        out,
        "where the pipeline breaks (verdict accuracy, detection rate):"
    )?;
    for r in &lab.degradation {
        writeln!(
            out,
            "  {:<9} {:>6} {:<30} verdicts {:>5.1} %  detected {:>5.1} %  pin statuses {:>5.1} %{}",
            r.factor,
            r.level,
            r.localiser.name(),
            100.0 * r.verdict_accuracy,
            100.0 * r.detection_rate,
            100.0 * r.status_accuracy,
            if r.errors > 0 {
                format!("  ({} images not inspected)", r.errors)
            } else {
                String::new()
            }
        )?;
    }
    for n in &lab.notes {
        writeln!(out, "note: {n}")?;
    }
    writeln!(out, "tables and charts in {}", dir.display())?;
    Ok(())
}

fn csv_f(x: f64) -> String {
    if x.is_finite() {
        format!("{x}")
    } else {
        String::new()
    }
}

fn write_tables(report: &mut Report, lab: &DynamicsLab) -> anyhow::Result<()> {
    let mut w = String::from(
        "scene,method,setting_kind,setting,wall_ms,rhs_evals,aux_evals,steps,rejected,impacts,impact_count_error,stroke_err_mm,event_time_err_s,peak_force_rel_err,failed\n",
    );
    for p in &lab.work_precision {
        w.push_str(&format!(
            "\"{}\",{},{},{},{},{},{},{},{},{},{},{},{},{},\"{}\"\n",
            p.scene,
            p.method,
            p.setting_kind,
            p.setting,
            csv_f(p.wall_ms),
            p.rhs_evals,
            p.aux_evals,
            p.steps,
            p.rejected,
            p.impacts,
            p.impact_count_error,
            csv_f(p.stroke_err_mm),
            csv_f(p.event_time_err_s),
            csv_f(p.peak_force_rel_err),
            p.failed.as_deref().unwrap_or("").replace('"', "'")
        ));
    }
    report.add("work_precision.csv", w.as_bytes())?;
    let mut w = String::from(
        "variant,method,omega_contact,predicted_stable_step_s,measured_stable_step_s,measured_accurate_step_s,failure_beyond\n",
    );
    for r in &lab.stability {
        w.push_str(&format!(
            "\"{}\",{},{},{},{},{},{}\n",
            r.variant,
            r.method,
            r.omega_contact,
            r.predicted_stable_step_s,
            r.measured_stable_step_s.map(csv_f).unwrap_or_default(),
            r.measured_accurate_step_s.map(csv_f).unwrap_or_default(),
            r.failure_beyond
                .map(|o| format!("{o:?}"))
                .unwrap_or_default()
        ));
    }
    report.add("stability.csv", w.as_bytes())?;
    let mut w =
        String::from("scene,solver,rtol,rhs_evals,wall_ms,error,error_kind,impacts,failed\n");
    for p in &lab.outside_reference {
        w.push_str(&format!(
            "\"{}\",\"{}\",{},{},{},{},\"{}\",{},\"{}\"\n",
            p.scene,
            p.solver,
            p.rtol,
            p.rhs_evals,
            csv_f(p.wall_ms),
            csv_f(p.error),
            p.error_kind,
            p.impacts.map(|i| i.to_string()).unwrap_or_default(),
            p.failed.as_deref().unwrap_or("").replace('"', "'")
        ));
    }
    report.add("outside_reference.csv", w.as_bytes())?;
    let mut w = String::from(
        "rtol,horizon_revs,tolerance_horizon_revs,wall_ms,rhs_evals,as_good_as_tightest",
    );
    for f in DynamicsLab::long_run_figures() {
        w.push_str(&format!(",{f}_mean,{f}_std"));
    }
    w.push('\n');
    for r in &lab.long_run.rows {
        w.push_str(&format!(
            "{},{},{},{},{},{}",
            r.rtol,
            r.horizon_revs.map(csv_f).unwrap_or_default(),
            r.tolerance_horizon_revs.map(csv_f).unwrap_or_default(),
            r.wall_ms,
            r.rhs_evals,
            r.as_good_as_tightest
        ));
        for (_, m, s) in &r.figures {
            w.push_str(&format!(",{},{}", csv_f(*m), csv_f(*s)));
        }
        w.push('\n');
    }
    report.add("long_run.csv", w.as_bytes())?;
    let mut w = String::from("clearance_mm,motor_rpm,chosen,stroke_diff_mm,force_diff_n,reason\n");
    for c in &lab.fidelity {
        w.push_str(&format!(
            "{},{},{},{},{},\"{}\"\n",
            c.clearance_mm,
            c.motor_rpm,
            c.chosen.name(),
            c.stroke_diff_mm.map(csv_f).unwrap_or_default(),
            c.force_diff_n.map(csv_f).unwrap_or_default(),
            c.reason.replace('"', "'")
        ));
    }
    report.add("fidelity.csv", w.as_bytes())?;
    Ok(())
}

fn print_summary<W: Write>(out: &mut W, lab: &DynamicsLab, dir: &Path) -> std::io::Result<()> {
    writeln!(
        out,
        "pinsight methods dynamics ({:?}) — {:.1} s",
        lab.effort,
        lab.wall_ms / 1e3
    )?;
    writeln!(
        out,
        "work–precision (deterministic window, reference dop853 rtol 1e-13):"
    )?;
    writeln!(
        out,
        "  {:<36} {:<7} {:>9} {:>8} {:>8} {:>11} {:>11} {:>10}",
        "scene", "method", "setting", "evals", "wall ms", "stroke err", "event err", "impacts±"
    )?;
    for p in &lab.work_precision {
        match &p.failed {
            None => writeln!(
                out,
                "  {:<36} {:<7} {:>9.0e} {:>8} {:>8.2} {:>11.2e} {:>11.2e} {:>10}",
                p.scene,
                p.method,
                p.setting,
                p.rhs_evals + p.aux_evals,
                p.wall_ms,
                p.stroke_err_mm,
                p.event_time_err_s,
                p.impact_count_error
            )?,
            Some(e) => writeln!(
                out,
                "  {:<36} {:<7} {:>9.0e} failed: {e}",
                p.scene, p.method, p.setting
            )?,
        }
    }
    writeln!(
        out,
        "imaginary-axis stability limits h·ω: {:?}",
        lab.imaginary_axis_limits
    )?;
    writeln!(
        out,
        "fixed-step limits (predicted = limit / contact frequency):"
    )?;
    for r in &lab.stability {
        writeln!(
            out,
            "  {:<26} {:<7} ω {:>9.3e} rad/s  predicted {:>9.3e} s  stable {:>10}  accurate {:>10}  beyond: {}",
            r.variant,
            r.method,
            r.omega_contact,
            r.predicted_stable_step_s,
            r.measured_stable_step_s
                .map(|h| format!("{h:.3e}"))
                .unwrap_or("–".into()),
            r.measured_accurate_step_s
                .map(|h| format!("{h:.3e}"))
                .unwrap_or("–".into()),
            r.failure_beyond
                .map(|o| format!("{o:?}"))
                .unwrap_or("–".into())
        )?;
    }
    writeln!(
        out,
        "long run ({}, {} realisations × {} revolutions):",
        lab.long_run.scene, lab.long_run.realisations, lab.long_run.revs
    )?;
    for r in &lab.long_run.rows {
        let f = r
            .figures
            .first()
            .map(|f| format!("mean |Δs| {:.5} ± {:.5} mm", f.1, f.2))
            .unwrap_or_default();
        writeln!(
            out,
            "  rtol {:.0e}: horizon {} revs (vs tightest tolerance: {}), {f}, {} evals, {}",
            r.rtol,
            r.horizon_revs
                .map(|h| format!("{h:.2}"))
                .unwrap_or("–".into()),
            r.tolerance_horizon_revs
                .map(|h| format!("{h:.2}"))
                .unwrap_or("> span".into()),
            r.rhs_evals,
            if r.as_good_as_tightest {
                "as good as the tightest"
            } else {
                "differs from the tightest"
            }
        )?;
    }
    if let Some(t) = lab.long_run.recommended_rtol {
        writeln!(
            out,
            "  → cheapest tolerance with the tightest's statistics: {t:.0e}"
        )?;
    }
    writeln!(
        out,
        "outside reference (ode_solvers 0.6.2, same right-hand side):"
    )?;
    for p in &lab.outside_reference {
        match &p.failed {
            None => writeln!(
                out,
                "  {:<20} {:<40} rtol {:>7.0e} evals {:>7} error {:>10.3e}{}",
                p.scene,
                p.solver,
                p.rtol,
                p.rhs_evals,
                p.error,
                p.impacts
                    .map(|i| format!(" impacts {i}"))
                    .unwrap_or_default()
            )?,
            Some(e) => writeln!(
                out,
                "  {:<20} {:<40} rtol {:>7.0e} failed: {e}",
                p.scene, p.solver, p.rtol
            )?,
        }
    }
    writeln!(out, "failure modes:")?;
    for f in &lab.failures {
        writeln!(out, "  {} ({}): {}", f.what, f.method, f.outcome)?;
    }
    writeln!(out, "fidelity (paper preset, alloy steel):")?;
    for c in &lab.fidelity {
        writeln!(
            out,
            "  c {} mm, {} rpm → {}: {}",
            c.clearance_mm,
            c.motor_rpm,
            c.chosen.name(),
            c.reason
        )?;
    }
    writeln!(out, "tables and charts in {}", dir.display())?;
    Ok(())
}
