//! `pinsight merge PARTIALS... --out DIR`: the shards of a sharded `yield`
//! (their `partial.json` files, or their output folders) merged into the
//! report one run over all inputs writes — the same `yield.json`,
//! `items.csv`, `pins.csv`, charts and `yield.md`, byte for byte
//! (`plant::merge`). Without `--out` it prints the Markdown report (or the
//! JSON report with `--json`).
//!
//! Exit status: 0 done, 3 done but some items were errors, 2 the merge was
//! refused (partials of different jobs, a shard missing or given twice, an
//! unreadable partial — each named).

use crate::cli::common::{outln, outp};
use crate::plant::merge::{merge, read_partial};
use crate::vision::report::write_records;
use std::path::PathBuf;
use std::process::ExitCode;

#[derive(Debug, clap::Args)]
pub struct Args {
    /// The shards' partial results: `partial.json` files or the shards' `--out` folders.
    #[arg(required = true, value_name = "PARTIAL")]
    pub partials: Vec<PathBuf>,
    /// Write the merged report files (JSON, CSV, Markdown, PNG charts) here.
    #[arg(long, value_name = "DIR")]
    pub out: Option<PathBuf>,
    /// Print the merged report as JSON instead of Markdown (without --out).
    #[arg(long)]
    pub json: bool,
}

pub fn run(args: Args) -> anyhow::Result<ExitCode> {
    let partials = args
        .partials
        .iter()
        .map(|p| read_partial(p).map(|x| (p.display().to_string(), x)))
        .collect::<Result<Vec<_>, _>>()
        .map_err(anyhow::Error::msg)?;
    let m = merge(&partials).map_err(anyhow::Error::msg)?;
    let rep = &m.report;
    match &args.out {
        Some(dir) => {
            let files =
                write_records(dir, rep, &m.items, &m.title, &[]).map_err(anyhow::Error::msg)?;
            outln!("merged {} shards: {}", m.shards, rep.summary_line())?;
            for f in files {
                outln!("wrote {f}")?;
            }
        }
        None if args.json => outln!("{}", serde_json::to_string_pretty(rep)?)?,
        None => outp!("{}", rep.markdown(&m.title, &[]))?,
    }
    Ok(if rep.errors > 0 {
        ExitCode::from(3)
    } else {
        ExitCode::SUCCESS
    })
}
