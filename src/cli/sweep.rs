//! `pinsight sweep`: the paper's study (clearance × speed × material).

use super::common::{ParamArgs, parse_list_f64};
use crate::cli::common::outln;
use crate::plot::render_png;
use crate::progress::{Progress, ProgressBarGuard};
use crate::sim::ensemble::{FIGURES, figure};
use crate::sim::sweep::{Factor, SweepGrid, SweepResult, run_sweep};
use crate::sim::{Level, SimOptions};
use anyhow::{Context, anyhow};
use std::io::Write;
use std::path::PathBuf;
use std::process::ExitCode;

#[derive(Debug, clap::Args)]
pub struct Args {
    #[command(flatten)]
    pub params: ParamArgs,
    /// Clearances in mm, comma-separated (default 0.1,0.3,0.5,0.8).
    #[arg(long)]
    pub clearances: Option<String>,
    /// Motor speeds in rpm, comma-separated (default 1000,1200,1500,1800,2000).
    #[arg(long)]
    pub speeds: Option<String>,
    /// Materials, comma-separated (default: all five).
    #[arg(long)]
    pub materials: Option<String>,
    /// A TOML grid file (clearances_mm, speeds_rpm, materials); command-line lists override it.
    #[arg(long, value_name = "FILE")]
    pub grid: Option<PathBuf>,
    #[command(flatten)]
    pub solver: super::common::SolverArgs,
    #[arg(long, default_value_t = 2.0, value_parser = super::common::bounds::warmup)]
    pub warmup: f64,
    #[arg(long, default_value_t = 3.0, value_parser = super::common::bounds::revs)]
    pub revs: f64,
    /// Output directory for sweep.csv, sweep.json and the PNG charts.
    #[arg(long, default_value = "pinsight-sweep")]
    pub out: PathBuf,
    /// Skip the PNG charts.
    #[arg(long)]
    pub no_charts: bool,
    /// Print the JSON table on stdout as well.
    #[arg(long)]
    pub json: bool,
}

pub fn run(args: Args) -> anyhow::Result<ExitCode> {
    let base = args.params.resolve()?;
    let mut grid = match &args.grid {
        Some(path) => {
            let text = crate::input::read_text(path)
                .with_context(|| format!("reading grid file {}", path.display()))?;
            SweepGrid::from_toml_str(&text)
                .map_err(|e| anyhow!("grid file {}: {e}", path.display()))?
        }
        None => SweepGrid::default(),
    };
    if let Some(s) = &args.clearances {
        grid.clearances_mm = parse_list_f64(s, "--clearances")?;
    }
    if let Some(s) = &args.speeds {
        grid.speeds_rpm = parse_list_f64(s, "--speeds")?;
    }
    if let Some(s) = &args.materials {
        grid.materials = s
            .split(',')
            .map(|x| x.trim().to_string())
            .filter(|x| !x.is_empty())
            .collect();
    }
    grid.validate().map_err(|e| anyhow!("sweep grid: {e}"))?;
    let method = args.solver.method()?;
    let opts = SimOptions {
        level: Level::Clearance,
        method,
        rtol: args.solver.rtol,
        atol: args.solver.atol,
        warmup: args.warmup,
        revs: args.revs,
        ..SimOptions::default()
    };
    opts.validate()?;
    // The report is staged and replaces an older one only when complete.
    let mut report = crate::output::Report::new_in(&args.out)?;
    let progress = Progress::new(grid.len() as u64);
    let result = {
        let _bar = ProgressBarGuard::start(progress.clone(), "sweep");
        run_sweep(&base, &grid, &opts, &progress)
    };
    // Write every result we have, then the charts.
    let csv_path = args.out.join("sweep.csv");
    let mut csv = Vec::new();
    write_csv(&mut csv, &result).with_context(|| format!("writing {}", csv_path.display()))?;
    report.add("sweep.csv", &csv)?;
    let json_path = args.out.join("sweep.json");
    let json = serde_json::to_string_pretty(&result)?;
    report.add("sweep.json", json.as_bytes())?;
    let mut charts = Vec::new();
    if !args.no_charts {
        for f in Factor::ALL {
            let name = format!("curves_{}.png", f.name());
            let png = render_png(&result.curve_panels(f), 2, 1600, 1100)?;
            charts.push(report.add(&name, &png)?);
            let name = format!("bars_{}.png", f.name());
            let png = render_png(&result.bar_panels(f), 2, 1400, 550)?;
            charts.push(report.add(&name, &png)?);
        }
    }
    report.commit()?;
    if args.json {
        outln!("{json}")?;
    } else {
        let mut out = crate::cli::common::stdout();
        writeln!(
            out,
            "pinsight sweep — preset {}, {} cases ({} clearances × {} speeds × {} materials), {} rtol {:.0e}, {} + {} revolutions",
            result.preset,
            result.cases.len(),
            grid.clearances_mm.len(),
            grid.speeds_rpm.len(),
            grid.materials.len(),
            result.method,
            result.rtol,
            crate::fmt::plain(result.warmup_revs),
            crate::fmt::plain(result.revs)
        )?;
        writeln!(
            out,
            "nominal: c = {} mm, {} rpm, {}; wall {:.0} ms; {} failed",
            crate::fmt::plain(result.nominal.clearance_mm),
            crate::fmt::plain(result.nominal.motor_rpm),
            result.nominal.material,
            result.wall_ms,
            result.failed
        )?;
        writeln!(
            out,
            "{:>8} {:>7} {:<17} {:>8} {:>11} {:>11} {:>10}",
            "c_mm", "rpm", "material", "impacts", "mean|Δs|mm", "mean|Δv|m/s", "peak M Nm"
        )?;
        for c in &result.cases {
            match (&c.summary, &c.error) {
                (Some(s), _) => writeln!(
                    out,
                    "{:>8} {:>7} {:<17} {:>8} {:>11.5} {:>11.5} {:>10.4}",
                    crate::fmt::plain(c.clearance_mm),
                    crate::fmt::plain(c.motor_rpm),
                    c.material,
                    s.n_impacts,
                    s.disp_dev_mean_mm,
                    s.vel_dev_mean_mps,
                    s.peak_torque_nm.unwrap_or(f64::NAN)
                )?,
                (None, Some(e)) => writeln!(
                    out,
                    "{:>8} {:>7} {:<17} error: {e}",
                    crate::fmt::plain(c.clearance_mm),
                    crate::fmt::plain(c.motor_rpm),
                    c.material
                )?,
                (None, None) => {}
            }
        }
        writeln!(
            out,
            "wrote {} and {}",
            csv_path.display(),
            json_path.display()
        )?;
        for c in &charts {
            writeln!(out, "chart: {}", c.display())?;
        }
    }
    Ok(if result.failed > 0 {
        ExitCode::from(1)
    } else {
        ExitCode::SUCCESS
    })
}

/// A grid value in a CSV cell: as written, but in exponent form far from 1
/// (a refused 1e-300 is not 300 zeros).
fn csv_num(x: f64) -> String {
    if x != 0.0 && !(1e-4..1e16).contains(&x.abs()) {
        format!("{x:e}")
    } else {
        format!("{x}")
    }
}

fn write_csv(f: &mut Vec<u8>, r: &SweepResult) -> anyhow::Result<()> {
    write!(f, "clearance_mm,motor_rpm,material,status")?;
    for name in FIGURES {
        write!(f, ",{name}")?;
    }
    writeln!(f, ",n_impacts,steps,rejected_steps,rhs_evals,wall_ms,error")?;
    for c in &r.cases {
        write!(
            f,
            "{},{},{},{}",
            csv_num(c.clearance_mm),
            csv_num(c.motor_rpm),
            c.material,
            if c.error.is_some() { "error" } else { "ok" }
        )?;
        for name in FIGURES {
            match &c.summary {
                Some(s) => {
                    let v = figure(s, name);
                    if v.is_finite() {
                        write!(f, ",{v}")?
                    } else {
                        write!(f, ",")?
                    }
                }
                None => write!(f, ",")?,
            }
        }
        match &c.summary {
            Some(s) => write!(
                f,
                ",{},{},{},{},{:.3}",
                s.n_impacts, s.steps, s.rejected_steps, s.rhs_evals, s.wall_ms
            )?,
            None => write!(f, ",,,,,")?,
        }
        let err = c.error.as_deref().unwrap_or("").replace(['"', '\n'], " ");
        writeln!(f, ",\"{err}\"")?;
    }
    Ok(())
}
