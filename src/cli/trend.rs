//! `pinsight trend LOGS_OR_DIRS... [--by rig|none] [--model linear|archard]
//! [--limit MM | --tolerance MM | -r RECIPE] [--out DIR] [--json] [--cache FILE]`:
//! the wear trend of each head and the forecast of when its clearance
//! reaches the limit ([`crate::engine::trend`]).
//!
//! The cache of calibrations (by file SHA-256) is `--cache FILE`, else
//! `DIR/trend-cache.json` with `--out`; without either nothing is kept.
//! `--out DIR` writes trend.json, history.csv, trend.md and trend.png
//! (together, atomically). `--shard k/n` calibrates one part of the sorted
//! logs; with `--out` the shard writes `partial.json` and `pinsight merge`
//! fits, limits and forecasts every shard's points (`plant::trend`).
//! Exit code 3 when a log was left out (listed with
//! its error; the others are still reported).

use crate::cli::common::outln;
use crate::engine::trend::{TrendCache, TrendOptions, run_trend};
use crate::plant::partial::{Header, Job};
use crate::plant::shard::Shard;
use crate::plant::trend::{TrendSettings, split_inputs, trend_folder};
use crate::progress::{Progress, ProgressBarGuard};
use crate::wear::WearModel;
use anyhow::anyhow;
use std::path::PathBuf;
use std::process::ExitCode;

#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum By {
    /// One trend per rig_id of the logs' metadata.
    Rig,
    /// All logs are one head.
    None,
}

#[derive(Debug, clap::Args)]
pub struct Args {
    /// Rig logs (MCAP) or folders of them.
    #[arg(required = true, value_name = "LOGS_OR_DIRS")]
    pub inputs: Vec<PathBuf>,
    /// Group the logs into heads.
    #[arg(long, value_enum, default_value = "rig")]
    pub by: By,
    /// Degradation model: linear in the head's cycles, or archard (dc/dn =
    /// k·W(c), W the sliding work per cycle the model simulates).
    #[arg(long, default_value = "linear")]
    pub model: String,
    /// The clearance limit (mm), replacing the derivation from a tolerance.
    #[arg(long, value_name = "MM", value_parser = super::common::bounds::clearance_limit_mm)]
    pub limit: Option<f64>,
    /// Depth tolerance ± (mm) the limit is derived from with the model.
    #[arg(long, value_name = "MM", conflicts_with = "recipe", value_parser = super::common::bounds::depth_tolerance_mm)]
    pub tolerance: Option<f64>,
    /// A side-view vision recipe: its height_tol_mm is the depth tolerance.
    #[arg(short = 'r', long, value_name = "RECIPE.toml")]
    pub recipe: Option<PathBuf>,
    /// The forecast interval's level (0.5–0.99).
    #[arg(long, default_value_t = 0.8, value_parser = super::common::bounds::forecast_level)]
    pub level: f64,
    /// Write trend.json, history.csv, trend.md and trend.png into this folder.
    #[arg(long, value_name = "DIR")]
    pub out: Option<PathBuf>,
    /// Print the report as JSON.
    #[arg(long)]
    pub json: bool,
    /// The calibration cache (JSON, by file SHA-256); default DIR/trend-cache.json with --out.
    #[arg(long, value_name = "FILE")]
    pub cache: Option<PathBuf>,
    /// Simulated revolutions per clearance of the calibration's coarse grid.
    #[arg(long, default_value_t = 48, value_parser = super::common::bounds::calibrate_revs)]
    pub revs: usize,
    /// Run only shard K of N (K from 0) of the sorted logs; default from the
    /// cluster's environment (docs/scale.md).
    #[arg(long, value_name = "K/N")]
    pub shard: Option<String>,
    #[command(flatten)]
    pub log_read: super::common::LogReadArgs,
}

pub fn run(args: Args) -> anyhow::Result<ExitCode> {
    let model = WearModel::parse(&args.model).map_err(anyhow::Error::msg)?;
    let tolerance_mm = match (&args.recipe, args.tolerance) {
        (Some(r), _) => {
            let rec = crate::vision::recipe::Recipe::load(r).map_err(|e| anyhow!("{e}"))?;
            Some(rec.tolerance.height_tol_mm.ok_or_else(|| {
                anyhow!(
                    "{}: no tolerance.height_tol_mm (a side-view recipe is needed for the depth tolerance)",
                    r.display()
                )
            })?)
        }
        (None, t) => t,
    };
    let mut opts = TrendOptions {
        by_rig: args.by == By::Rig,
        model,
        limit_mm: args.limit,
        tolerance_mm,
        level: args.level,
        load: args.log_read.load_options()?,
        ..TrendOptions::default()
    };
    opts.calibrate.predict.revs = args.revs.max(8);
    let cache_path = args
        .cache
        .clone()
        .or_else(|| args.out.as_ref().map(|d| d.join("trend-cache.json")));
    let mut cache = match &cache_path {
        Some(p) => TrendCache::load(p).map_err(anyhow::Error::msg)?,
        None => TrendCache::default(),
    };
    let shard = Shard::resolve(args.shard.as_deref()).map_err(anyhow::Error::msg)?;
    let part = split_inputs(shard, &args.inputs);
    if !shard.is_whole() {
        eprintln!("shard {shard}: {} log(s)", part.inputs.len());
    }
    let inputs = if shard.is_whole() {
        args.inputs.clone()
    } else {
        part.inputs.clone()
    };
    let progress = Progress::new(0);
    let report = {
        let _bar = (!args.json).then(|| ProgressBarGuard::start(progress.clone(), "trend"));
        run_trend(&inputs, &opts, &mut cache, &progress)
    };
    if let Some(dir) = &args.out {
        let settings = TrendSettings::of(&opts);
        let header = (!shard.is_whole()).then(|| {
            let text = format!(
                "{}; revs {}; load {:?}",
                serde_json::to_string(&settings).unwrap_or_default(),
                args.revs,
                opts.load
            );
            (
                Header::new(Job::Trend, shard, part.units, part.digest.clone(), &text),
                &part,
                &settings,
            )
        });
        let files = trend_folder(&report, header).map_err(anyhow::Error::msg)?;
        crate::vision::report::write_files(dir, &files, &[]).map_err(anyhow::Error::msg)?;
    }
    if let Some(p) = &cache_path
        && report.calibrated > 0
    {
        crate::output::write_file(p, &cache.to_json())?;
    }
    if args.json {
        outln!("{}", serde_json::to_string_pretty(&report)?)?;
    } else {
        outln!("{}", report.to_markdown())?;
    }
    Ok(if report.errors.is_empty() {
        ExitCode::SUCCESS
    } else {
        ExitCode::from(3)
    })
}
