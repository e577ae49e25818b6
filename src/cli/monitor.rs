//! `pinsight monitor LOG... --process R.toml [--learn N] [--json | --csv |
//! --out DIR] [--dfq FILE] [--mcap FILE]`: every cycle's force curve judged against the
//! process recipe's evaluation objects (OK / NOK with reasons / not
//! evaluated), and the SPC of the value checks (see [`crate::process`]).
//!
//! `-r RECIPE` (vision recipes) joins each connector's photograph in the
//! log with its cycle's verdict: the confusion of process NOK against
//! vision fail, and the connectors where they disagree.
//!
//! `--band` adds the model's predicted band to each connector's story (an
//! overlay prediction per log: the fraction of the cycle's stroke and force
//! inside the band, the stroke residual at BDC).
//!
//! `--out DIR` writes monitor.json, cycles.csv, spc.csv (process values and
//! pin positions, overall, by lot, by speed), connectors.csv (with `-r`)
//! and a control chart PNG per characteristic (`chart-<name>.png`).
//!
//! `--parquet` adds `cycles.parquet` (one row per cycle: verdict, reasons,
//! process values, the model band's residuals; docs/scale.md), and
//! `--partition-by part,lot` writes it as hive-style partition folders.
//!
//! `--shard k/n` runs one part of the sorted logs (docs/scale.md); with
//! `--out` the shard writes `partial.json` for `pinsight merge`, which
//! gives the single run's folder (`plant::monitor`).
//!
//! `--learn N` first learns the recipe's envelopes from the first N good
//! cycles and writes the recipe back (atomically), then monitors with it.
//!
//! Exit code: 0 when every cycle is OK; 1 when a cycle is NOK or could not
//! be evaluated (a cycle without force data is never OK); 3 when a log
//! could not be monitored (the others are still reported).

use crate::cli::common::{outln, outp};
use crate::engine::process::{learn_from_logs, monitor_logs};
use crate::plant::monitor::{MonitorOutputs, exit_status, monitor_folder};
use crate::plant::partial::Job;
use crate::plant::shard::{Shard, split_list};
use crate::process::ProcessRecipe;
use crate::process::report::{cycles_csv, summary_text};
use crate::progress::{Progress, ProgressBarGuard};
use crate::vision::batch::RecipeBook;
use anyhow::anyhow;
use std::path::PathBuf;
use std::process::ExitCode;

#[derive(Debug, clap::Args)]
pub struct Args {
    /// Rig logs (MCAP).
    #[arg(required = true, value_name = "LOG.mcap")]
    pub logs: Vec<PathBuf>,
    /// The process recipe (TOML: windows, thresholds, envelopes, value checks).
    #[arg(long, value_name = "RECIPE.toml")]
    pub process: PathBuf,
    /// Vision recipes (files or folders): inspect each connector's photograph in the log
    /// and join it with its cycle's verdict (the connector's whole story).
    #[arg(short = 'r', long = "recipe", value_name = "RECIPE.toml")]
    pub recipes: Vec<PathBuf>,
    /// Join the model's predicted band for each cycle to its connector's story (runs the
    /// overlay prediction per log).
    #[arg(long, requires = "recipes")]
    pub band: bool,
    /// Learn the recipe's envelopes from the first N good cycles and save them into the recipe.
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u32).range(2..=100_000))]
    pub learn: Option<u32>,
    /// Print the run as JSON.
    #[arg(long, conflicts_with = "csv")]
    pub json: bool,
    /// Print one CSV row per cycle.
    #[arg(long)]
    pub csv: bool,
    /// Write monitor.json, cycles.csv, spc.csv, connectors.csv and control chart PNGs into this folder.
    #[arg(long, value_name = "DIR")]
    pub out: Option<PathBuf>,
    /// Also write the process values as a Q-DAS ASCII transfer file (AQDEF .dfq) for SPC packages.
    #[arg(long, value_name = "FILE.dfq")]
    pub dfq: Option<PathBuf>,
    /// Also write the verdicts as MCAP for Foxglove (with the log's own messages).
    #[arg(long, value_name = "FILE")]
    pub mcap: Option<PathBuf>,
    /// With --out: also write cycles.parquet (one row per cycle, zstd).
    #[arg(long)]
    pub parquet: bool,
    /// Write the Parquet table as hive-style partition folders by these keys (part, lot),
    /// e.g. part,lot; implies --parquet.
    #[arg(long, value_name = "KEYS")]
    pub partition_by: Option<String>,
    /// Run only shard K of N (K from 0) of the sorted logs; default from the
    /// cluster's environment (docs/scale.md).
    #[arg(long, value_name = "K/N")]
    pub shard: Option<String>,
    #[command(flatten)]
    pub log_read: super::common::LogReadArgs,
}

/// `--parquet` and `--partition-by` as the folder's outputs.
fn outputs_of(args: &Args) -> anyhow::Result<MonitorOutputs> {
    let keys = match &args.partition_by {
        Some(k) => {
            let keys = crate::export::parquet::parse_partition_keys(k)
                .map_err(|e| anyhow!("--partition-by: {e}"))?;
            if keys.contains(&crate::export::parquet::PartitionKey::Rig) {
                return Err(anyhow!(
                    "--partition-by: the cycles table has no rig column (part, lot)"
                ));
            }
            Some(keys)
        }
        None => args.parquet.then(Vec::new),
    };
    Ok(MonitorOutputs { parquet: keys })
}

pub fn run(args: Args) -> anyhow::Result<ExitCode> {
    let outputs = outputs_of(&args)?;
    let shard = Shard::resolve(args.shard.as_deref()).map_err(anyhow::Error::msg)?;
    if !shard.is_whole() && args.learn.is_some() {
        return Err(anyhow!(
            "--learn with --shard: each shard would learn from its own logs; learn once \
             (pinsight monitor LOG --learn N), then run the shards with the learned recipe"
        ));
    }
    let mut recipe = ProcessRecipe::load(&args.process).map_err(|e| anyhow!("{e}"))?;
    let opts = args.log_read.load_options()?;
    let part = split_list(shard, args.logs.clone(), |p| p.display().to_string());
    if !shard.is_whole() {
        eprintln!("shard {shard}: {} log(s)", part.kept.len());
    }
    let progress = Progress::new(0);
    let quiet = args.json || args.csv;
    let _bar = (!quiet).then(|| ProgressBarGuard::start(progress.clone(), "monitor"));
    let mut learned = None;
    if let Some(n) = args.learn {
        let (r, note) = learn_from_logs(&recipe, &args.logs, &opts, n as usize, &progress)
            .map_err(anyhow::Error::msg)?;
        crate::output::write_file(&args.process, r.to_toml().as_bytes())?;
        recipe = r;
        learned = Some(format!("{note}; saved to {}", args.process.display()));
    }
    let book = (!args.recipes.is_empty()).then(|| RecipeBook::load(&args.recipes));
    let mut run = monitor_logs(
        &recipe,
        &part.kept,
        &opts,
        book.as_ref(),
        args.band,
        &progress,
    );
    run.learned = learned;
    drop(_bar);
    if let Some(dir) = &args.out {
        let header = (!shard.is_whole()).then(|| {
            let settings = format!(
                "process recipe {}; vision recipes {}; band {}; load {:?}; outputs {}",
                serde_json::to_string(&recipe).unwrap_or_default(),
                book.as_ref()
                    .map(|b| serde_json::to_string(&b.recipes).unwrap_or_default())
                    .unwrap_or_default(),
                args.band,
                opts,
                serde_json::to_string(&outputs).unwrap_or_default(),
            );
            (
                part.header(Job::Monitor, shard, &settings),
                part.orders.as_slice(),
            )
        });
        let (files, remove) =
            monitor_folder(&run, &recipe, &outputs, header).map_err(anyhow::Error::msg)?;
        crate::vision::report::write_files(dir, &files, &remove).map_err(anyhow::Error::msg)?;
    }
    if let Some(file) = &args.dfq {
        crate::output::write_file(file, &crate::process::qdas::dfq(&run))?;
    }
    if let Some(file) = &args.mcap {
        let bytes = crate::export::mcap::monitor::monitor_mcap(&run, &part.kept)
            .map_err(|e| anyhow!("{}: {e}", file.display()))?;
        crate::output::write_file(file, &bytes)?;
    }
    if args.json {
        outln!("{}", serde_json::to_string_pretty(&run)?)?;
    } else if args.csv {
        outp!("{}", cycles_csv(&run))?;
    } else {
        outp!("{}", summary_text(&run))?;
    }
    Ok(ExitCode::from(exit_status(&run)))
}
