//! `pinsight yield`: batch yield over folders of images and rig logs.
//!
//! Inspects every image in parallel (rayon; `--jobs` sets the thread count)
//! with a progress bar, then reports yield with its 95 % Wilson interval,
//! defects per million pins, a Pareto of defect kinds, the worst pin
//! positions, yield by lot / part / rig / speed, and yield against motor
//! speed and clearance for rig-log images. With `--out DIR` it writes
//! `yield.json`, `items.csv`, `pins.csv`, `yield.md` and PNG charts there;
//! otherwise it prints the Markdown report. Images that cannot be read or
//! analysed are `error`: listed, counted beside the yield, never dropped.
//!
//! `--items` chooses the per-item outputs: the items in `yield.json`,
//! `items.csv` + `pins.csv` (the default, `json,csv`), and the Parquet
//! tables `images` and `pins` (`parquet`); `--partition-by part,lot` writes
//! the tables as hive-style partition folders (docs/scale.md).
//!
//! With `--shard k/n` and `--out`, the shard also writes `partial.json`
//! for `pinsight merge` (`plant::yields`).
//!
//! Exit status: 0 done, 3 done but some images were errors, 2 the command
//! itself failed.

use crate::cli::common::{outln, outp};
use crate::engine::vision::{YieldInput, run_yield_inputs};
use crate::plant::partial::{Header, Job};
use crate::plant::yields::{YieldOutputs, settings_text, yield_folder};
use crate::progress::{Progress, ProgressBarGuard};
use crate::vision::batch::{self, ItemStatus, RecipeBook};
use crate::vision::report::{self, GroupBy};
use crate::vision::yield_acc::YieldAcc;
use crate::vision::{InspectOptions, Localiser};
use anyhow::Context;
use std::path::PathBuf;
use std::process::ExitCode;

#[derive(Debug, clap::Args)]
pub struct Args {
    /// Folders of images, image files, or rig logs (.mcap).
    #[arg(required = true)]
    pub inputs: Vec<PathBuf>,
    /// Recipe (TOML); repeat for several part numbers.
    #[arg(long, short = 'r', required = true)]
    pub recipe: Vec<PathBuf>,
    /// Group the yield table by lot, part, rig or motor speed.
    #[arg(long, value_enum, default_value_t = GroupBy::Lot)]
    pub by: GroupBy,
    /// Write the report files (JSON, CSV, Markdown, PNG charts) here.
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// Print the report as JSON instead of Markdown (without --out).
    #[arg(long)]
    pub json: bool,
    /// Worker threads (default: all cores).
    #[arg(long, value_parser = super::common::bounds::jobs)]
    pub jobs: Option<usize>,
    /// Run only shard K of N (K from 0) of the sorted inputs; default from
    /// PINSIGHT_SHARD, JOB_COMPLETION_INDEX + PINSIGHT_SHARDS, or
    /// SLURM_ARRAY_TASK_ID + SLURM_ARRAY_TASK_COUNT (docs/scale.md).
    #[arg(long, value_name = "K/N")]
    pub shard: Option<String>,
    /// Per-item outputs with --out: any of json (the items in yield.json), csv (items.csv,
    /// pins.csv), parquet (images and pins tables, zstd), or none.
    #[arg(long, value_name = "LIST", default_value = "json,csv")]
    pub items: String,
    /// Write the Parquet tables as hive-style partition folders by these keys (part, lot,
    /// rig), e.g. part,lot; implies parquet in --items.
    #[arg(long, value_name = "KEYS")]
    pub partition_by: Option<String>,
    /// Also write every inspected image with its annotations as MCAP for Foxglove.
    #[arg(long, value_name = "FILE")]
    pub mcap: Option<PathBuf>,
}

/// The inspected images and their annotations as MCAP (inputs and results
/// in the same order).
fn write_mcap(
    file: &std::path::Path,
    inputs: &[YieldInput],
    results: &[crate::vision::batch::ItemResult],
) -> anyhow::Result<()> {
    use crate::export::mcap::inspection::{Frame, inspections_mcap};
    let frames: Vec<Frame> = inputs
        .iter()
        .zip(results)
        .map(|(i, r)| match i {
            YieldInput::Image(item) => Frame::of(Some(item), r),
            YieldInput::Failed(_) => Frame::of(None, r),
        })
        .collect();
    let bytes =
        inspections_mcap(&frames).map_err(|e| anyhow::anyhow!("{}: {e}", file.display()))?;
    crate::output::write_file(file, &bytes)?;
    Ok(())
}

/// `--items` and `--partition-by` as the folder's outputs.
pub fn outputs_of(items: &str, partition_by: Option<&str>) -> anyhow::Result<YieldOutputs> {
    let mut o = YieldOutputs::parse_items(items).map_err(anyhow::Error::msg)?;
    if let Some(k) = partition_by {
        o.parquet = Some(
            crate::export::parquet::parse_partition_keys(k)
                .map_err(|e| anyhow::anyhow!("--partition-by: {e}"))?,
        );
    }
    Ok(o)
}

pub fn run(args: Args) -> anyhow::Result<ExitCode> {
    let outputs = outputs_of(&args.items, args.partition_by.as_deref())?;
    let book = RecipeBook::load(&args.recipe);
    for e in &book.invalid {
        eprintln!("warning: {e}");
    }
    // The one yield path (engine): unreadable inputs are `error` items.
    let (items, errors) = batch::collect_items(&args.inputs);
    let shard =
        crate::plant::shard::Shard::resolve(args.shard.as_deref()).map_err(anyhow::Error::msg)?;
    let part = crate::plant::shard::split_collected_part(shard, items, errors);
    let (items, errors, orders) = (part.items, part.errors, part.orders);
    if !shard.is_whole() {
        eprintln!("shard {shard}: {} input(s)", items.len() + errors.len());
    }
    let inputs: Vec<YieldInput> = errors
        .into_iter()
        .map(|e| YieldInput::Failed(Box::new(e)))
        .chain(items.into_iter().map(YieldInput::Image))
        .collect();
    let progress = Progress::new(inputs.len() as u64);
    progress.set_message("inspecting");
    let opts = InspectOptions {
        localiser: Localiser::Coverage,
    };
    let run = {
        let _bar = ProgressBarGuard::start(progress.clone(), "yield");
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(args.jobs.unwrap_or(0))
            .build()
            .context("cannot start worker threads")?;
        pool.install(|| run_yield_inputs(&inputs, &book, &opts, args.by, &progress))
    };
    let (rep, results) = (run.report, run.results);
    if let Some(file) = &args.mcap {
        write_mcap(file, &inputs, &results)?;
    }
    let title = format!(
        "Yield report: {}",
        book.recipes
            .iter()
            .map(|r| r.part_number.as_str())
            .collect::<Vec<_>>()
            .join(", ")
    );
    match &args.out {
        Some(dir) => {
            // The folder's files; a shard adds its partial result for
            // `pinsight merge` (its aggregate and an index of its items).
            let shard_part = (!shard.is_whole()).then(|| {
                let mut aggregate = YieldAcc::new(args.by);
                for (r, &o) in results.iter().zip(&orders) {
                    aggregate.add(o, r);
                }
                let header = Header::new(
                    Job::Yield,
                    shard,
                    part.units,
                    part.digest.clone(),
                    &settings_text(&book, args.by, &outputs),
                );
                (header, aggregate)
            });
            let (files, remove) =
                yield_folder(&rep, &results, &orders, &title, &outputs, shard_part)
                    .map_err(anyhow::Error::msg)?;
            let files = report::write_files(dir, &files, &remove).map_err(anyhow::Error::msg)?;
            outln!("{}", rep.summary_line())?;
            for e in &rep.error_list {
                outln!("error: {}: {}", e.name, e.message)?;
            }
            for f in files {
                outln!("wrote {f}")?;
            }
        }
        None => {
            if args.json {
                outln!("{}", serde_json::to_string_pretty(&rep)?)?;
            } else {
                outp!("{}", rep.markdown(&title, &[]))?;
            }
        }
    }
    Ok(if results.iter().any(|r| r.status == ItemStatus::Error) {
        ExitCode::from(3)
    } else {
        ExitCode::SUCCESS
    })
}
