//! `pinsight merge PARTIALS... --out DIR`: the shards of a sharded job
//! (their `partial.json` files, or their output folders) merged into the
//! report one run over all inputs writes — for `yield` the same
//! `yield.json`, `items.csv`, `pins.csv`, Parquet tables, charts and
//! `yield.md`, byte for byte (`plant::merge`). Without `--out` it prints
//! the report (or its JSON with `--json`).
//!
//! Exit status: what a single run of the job gives (0 done; 3 some items
//! were errors; 1 for `monitor` when a cycle is NOK), 2 the merge was
//! refused (partials of different jobs, recipes or pinsight versions, a
//! shard missing or given twice, overlapping shards, an unreadable or
//! changed file — each named) and nothing was written.

use crate::cli::common::{outln, outp};
use crate::plant::merge::merge_paths;
use std::path::PathBuf;
use std::process::ExitCode;

#[derive(Debug, clap::Args)]
pub struct Args {
    /// The shards' partial results: `partial.json` files or the shards' `--out` folders.
    #[arg(required = true, value_name = "PARTIAL")]
    pub partials: Vec<PathBuf>,
    /// Write the merged report's files here.
    #[arg(long, value_name = "DIR")]
    pub out: Option<PathBuf>,
    /// Print the merged report as JSON instead of text (without --out).
    #[arg(long)]
    pub json: bool,
}

pub fn run(args: Args) -> anyhow::Result<ExitCode> {
    let m = merge_paths(&args.partials).map_err(anyhow::Error::msg)?;
    match &args.out {
        Some(dir) => {
            let files = crate::vision::report::write_files(dir, &m.files, &m.remove)
                .map_err(anyhow::Error::msg)?;
            outln!(
                "merged {} shards of {}: {}",
                m.shards,
                m.job.name(),
                m.summary
            )?;
            for f in files {
                outln!("wrote {f}")?;
            }
        }
        None if args.json => outln!("{}", m.json)?,
        None => outp!("{}", m.text)?,
    }
    Ok(ExitCode::from(m.exit))
}
