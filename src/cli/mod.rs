//! The `pinsight` command line. Each subcommand lives in its own file with
//! an `Args` struct (clap) and a `run` function; this file only dispatches.

use clap::{Parser, Subcommand};
use std::process::ExitCode;

pub mod batch;
pub mod calibrate;
pub mod common;
pub mod demo;
pub mod inspect;
pub mod log;
pub mod merge;
pub mod methods;
pub mod monitor;
pub mod overlay;
pub mod render;
pub mod rig_sim;
pub mod simulate;
pub mod sweep;
pub mod trend;
pub mod tui;
pub mod watch;
pub mod yield_report;

#[derive(Debug, Parser)]
#[command(
    name = "pinsight",
    version,
    about = "Pin-insertion line workstation: clearance-joint dynamics, rig logs, connector vision, yield",
    long_about = None
)]
pub struct Cli {
    #[command(subcommand)]
    pub command: Option<Command>,
}

// Parsed once at start-up; boxing the larger variants buys nothing.
#[allow(clippy::large_enum_variant)]
#[derive(Debug, Subcommand)]
pub enum Command {
    /// Simulate the mechanism (kinematic, ideal, clearance-joint or motor-driven model).
    Simulate(simulate::Args),
    /// Run the parameter study (clearance × speed × material) in parallel.
    Sweep(sweep::Args),
    /// Load a rig log (MCAP) and report what it holds.
    Log(log::Args),
    /// Compare a rig log's cycles with the model's prediction.
    Overlay(overlay::Args),
    /// Judge every cycle's force curve against a process recipe (OK/NOK with reasons) and its SPC.
    Monitor(monitor::Args),
    /// Wear trend of each head: clearance history, wear rate, limit and forecast.
    Trend(trend::Args),
    /// Fit clearance, standoff, process load and sensor offsets to a rig log.
    Calibrate(calibrate::Args),
    /// Inspect connector images against a recipe.
    Inspect(inspect::Args),
    /// Batch yield report over image folders or rig logs.
    Yield(yield_report::Args),
    /// Merge the partial results of a sharded yield into the single run's report.
    Merge(merge::Args),
    /// The methods lab: work–precision, stability, fidelity, vision localisers.
    Methods(methods::Args),
    /// Open the terminal workstation on the given files.
    Tui(tui::Args),
    /// The demo: the embedded session, or `--live` a simulated line followed live.
    Demo(demo::Args),
    /// Follow rig logs being written and folders where images arrive (headless; JSON lines).
    Watch(watch::Args),
    /// A simulated rig writing its log (and connector photographs) in real time.
    RigSim(rig_sim::Args),
    /// Render one pane headless (text, JSON, CSV or PNG).
    Render(render::Args),
    /// Run a batch script of steps and checks.
    Batch(batch::Args),
}

/// An error and its causes on one line, each cause said once: a message
/// that already quotes its cause (`…: {source}`) does not repeat it.
pub fn error_text(e: &anyhow::Error) -> String {
    let mut text = e.to_string();
    for cause in e.chain().skip(1) {
        let c = cause.to_string();
        if !text.contains(&c) {
            text.push_str(": ");
            text.push_str(&c);
        }
    }
    text
}

/// Entry point of the binary: parses arguments, runs, and turns errors into
/// a message on stderr and a non-zero exit code (never a panic trace).
pub fn main() -> ExitCode {
    // Starts the clock of PINSIGHT_MAX_WALL_S (if set).
    let _ = crate::sim::process_deadline();
    let cli = Cli::parse();
    if is_batch(cli.command.as_ref()) {
        crate::allocator::settle_for_a_batch();
    }
    let result = match cli.command {
        None => tui::run_default(),
        Some(Command::Simulate(a)) => simulate::run(a),
        Some(Command::Sweep(a)) => sweep::run(a),
        Some(Command::Log(a)) => log::run(a),
        Some(Command::Overlay(a)) => overlay::run(a),
        Some(Command::Monitor(a)) => monitor::run(a),
        Some(Command::Trend(a)) => trend::run(a),
        Some(Command::Calibrate(a)) => calibrate::run(a),
        Some(Command::Inspect(a)) => inspect::run(a),
        Some(Command::Yield(a)) => yield_report::run(a),
        Some(Command::Merge(a)) => merge::run(a),
        Some(Command::Methods(a)) => methods::run(a),
        Some(Command::Tui(a)) => tui::run(a),
        Some(Command::Watch(a)) => watch::run(a),
        Some(Command::Demo(a)) => demo::run(a),
        Some(Command::RigSim(a)) => rig_sim::run(a),
        Some(Command::Render(a)) => render::run(a),
        Some(Command::Batch(a)) => batch::run(a),
    };
    match result {
        Ok(code) => code,
        Err(e) if e.downcast_ref::<common::HelpShown>().is_some() => {
            // Help is not an error: the listing on stdout, exit 0.
            let _ = common::outln!("{e}");
            ExitCode::SUCCESS
        }
        Err(e) => {
            eprintln!("error: {}", error_text(&e));
            ExitCode::from(2)
        }
    }
}

/// Whether the command runs to completion over its inputs (the C
/// allocator is tuned for throughput, see [`crate::allocator`]); the TUI,
/// `watch`, the demo and `rig-sim` follow a line for hours instead.
fn is_batch(command: Option<&Command>) -> bool {
    !matches!(
        command,
        None | Some(Command::Tui(_))
            | Some(Command::Watch(_))
            | Some(Command::Demo(_))
            | Some(Command::RigSim(_))
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn an_error_quoting_its_cause_says_it_once() {
        let e = crate::sim::SimError::Integration {
            source: crate::solver::StepError::NonFinite { t: 0.25 },
            t: 0.25,
            crank_deg: 90.0,
            penetration_um: 0.0,
            mode: "in free flight",
        };
        let text = error_text(&anyhow::Error::new(e));
        assert_eq!(text.matches("non-finite state").count(), 1, "{text}");
        let outer = anyhow::Error::msg("inner cause").context("outer");
        assert_eq!(error_text(&outer), "outer: inner cause");
    }
}
