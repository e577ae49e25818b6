//! `pinsight simulate` (in progress).

use std::process::ExitCode;

#[derive(Debug, clap::Args)]
pub struct Args {
    /// Preset.
    #[arg(long, default_value = "paper")]
    pub preset: String,
}

pub fn run(_args: Args) -> anyhow::Result<ExitCode> {
    anyhow::bail!("`simulate` is not implemented yet")
}

pub fn run_demo() -> anyhow::Result<ExitCode> {
    anyhow::bail!("the demo is not implemented yet")
}
