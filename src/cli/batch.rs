//! `pinsight batch SCRIPT.toml`: run a script of load / set / run / export
//! / check steps (format in [`crate::batch::script`] and docs/tui.md).
//! Prints a summary of every step and check; exits 1 when a check fails or
//! a step errs, 2 when the script cannot be read, 130 when Ctrl-C stopped
//! it (between steps; the summary lists the files written, each complete).

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
    // Ctrl-C stops between steps; the summary then says what was written.
    let progress = crate::progress::Progress::hidden();
    if let Err(e) = progress.cancel_on_ctrl_c() {
        eprintln!("warning: Ctrl-C will stop at once (cannot catch it: {e})");
    }
    let report = crate::batch::script::run_file_cancellable(&args.script, &args.out, &progress)
        .map_err(|e| anyhow::anyhow!(e))?;
    outp!("{}", report.table())?;
    if let Some(p) = &args.json {
        crate::output::write_file(p, serde_json::to_string_pretty(&report)?.as_bytes())?;
    }
    Ok(if report.interrupted {
        ExitCode::from(130)
    } else if report.success() {
        ExitCode::SUCCESS
    } else {
        ExitCode::from(1)
    })
}
