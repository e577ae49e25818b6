//! `pinsight tui` and the no-argument default.

use std::process::ExitCode;

#[derive(Debug, clap::Args)]
pub struct Args {
    /// Logs, images, recipes and parameter files to open.
    pub paths: Vec<String>,
}

pub fn run(_args: Args) -> anyhow::Result<ExitCode> {
    anyhow::bail!("the TUI is not implemented yet")
}

/// `pinsight` with no arguments. Until the TUI exists this prints the demo
/// simulation summary.
pub fn run_default() -> anyhow::Result<ExitCode> {
    super::simulate::run_demo()
}
