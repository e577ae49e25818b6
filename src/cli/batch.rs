//! `pinsight batch SCRIPT.toml`: run a script of load / set / run / export
//! / check steps (format in [`crate::batch::script`] and docs/tui.md).
//! Prints a summary of every step and check; exits 1 when a check fails or
//! a step errs, 2 when the script cannot be read.

use crate::cli::common::outp;
use std::path::PathBuf;
use std::process::ExitCode;

#[derive(Debug, clap::Args)]
pub struct Args {
    /// The script (TOML with [[step]] tables).
    pub script: PathBuf,
    /// Folder the export steps write into.
    #[arg(long, default_value = ".")]
    pub out: PathBuf,
    /// Also write the report as JSON to this file.
    #[arg(long, value_name = "FILE")]
    pub json: Option<PathBuf>,
}

pub fn run(args: Args) -> anyhow::Result<ExitCode> {
    let report =
        crate::batch::script::run_file(&args.script, &args.out).map_err(|e| anyhow::anyhow!(e))?;
    outp!("{}", report.table())?;
    if let Some(p) = &args.json {
        std::fs::write(p, serde_json::to_string_pretty(&report)?)
            .map_err(|e| anyhow::anyhow!("cannot write {}: {e}", p.display()))?;
    }
    Ok(if report.success() {
        ExitCode::SUCCESS
    } else {
        ExitCode::from(1)
    })
}
