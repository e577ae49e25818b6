//! `pinsight sweep`: the paper's study (clearance × speed × material).
//!
//! `--shard k/n` runs case `i` of the grid when `i mod n = k`; the shard
//! also writes `partial.json`, and `pinsight merge` gives the single run's
//! study (`plant::sweep`).

use super::common::{ParamArgs, parse_list_f64};
use crate::cli::common::outln;
use crate::plant::partial::Job;
use crate::plant::shard::{Shard, split_list};
use crate::plant::sweep::{case_units, sweep_folder};
use crate::progress::{Progress, ProgressBarGuard};
use crate::sim::sweep::{SweepGrid, run_sweep_cases};
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
    /// Run only shard K of N (K from 0) of the grid's cases; default from the
    /// cluster's environment (docs/scale.md).
    #[arg(long, value_name = "K/N")]
    pub shard: Option<String>,
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
    let shard = Shard::resolve(args.shard.as_deref()).map_err(anyhow::Error::msg)?;
    let part = split_list(shard, case_units(&grid), Clone::clone);
    let keep: std::collections::BTreeSet<usize> = part.orders.iter().map(|&o| o as usize).collect();
    if !shard.is_whole() {
        eprintln!("shard {shard}: {} of {} cases", keep.len(), grid.len());
    }
    let progress = Progress::new(keep.len() as u64);
    let result = {
        let _bar = ProgressBarGuard::start(progress.clone(), "sweep");
        run_sweep_cases(&base, &grid, &opts, &|i| keep.contains(&i), &progress)
    };
    // Every result we have, then the charts; staged and committed together
    // (an older report is replaced only when all are complete).
    let header = (!shard.is_whole()).then(|| {
        let settings = format!(
            "base {}; grid {}; {:?}; charts {}",
            serde_json::to_string(&base).unwrap_or_default(),
            serde_json::to_string(&grid).unwrap_or_default(),
            opts,
            !args.no_charts
        );
        (
            part.header(Job::Sweep, shard, &settings),
            part.orders.as_slice(),
        )
    });
    let files = sweep_folder(&result, !args.no_charts, header)?;
    let written = crate::vision::report::write_files(&args.out, &files, &[])
        .map_err(anyhow::Error::msg)
        .with_context(|| format!("writing the sweep into {}", args.out.display()))?;
    let csv_path = args.out.join("sweep.csv");
    let json_path = args.out.join("sweep.json");
    let json = String::from_utf8_lossy(&files[1].1).into_owned();
    let charts: Vec<PathBuf> = written
        .iter()
        .filter(|f| f.ends_with(".png"))
        .map(PathBuf::from)
        .collect();
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
