//! The monitor's verdicts as MCAP, beside the logs' own messages: one
//! `pinsight.CycleVerdict` per cycle on `/pinsight/monitor/cycle` at the
//! cycle's start (status `ok` / `nok` / `not_evaluated`, the failed objects
//! with their reasons, the process values), so Foxglove's State Transitions
//! panel shows OK/NOK along the force and displacement plots.

use super::McapOut;
use crate::process::run::MonitorRun;
use std::path::PathBuf;

/// Builds the MCAP of a monitor run; `logs` are re-mapped to copy their messages.
pub fn monitor_mcap(run: &MonitorRun, logs: &[PathBuf]) -> Result<Vec<u8>, String> {
    let mut out = McapOut::new()?;
    for p in logs {
        // A log that could not be read is already an error in the run.
        if let Ok(src) = crate::rig::mcap_read::Source::open(p) {
            out.copy_messages(src.bytes(), "")?;
        }
    }
    for l in &run.logs {
        let Ok(r) = &l.report else { continue };
        for c in &r.cycles {
            let t = u64::try_from(c.t_start_ns).unwrap_or(0);
            out.log_json("/pinsight/monitor/cycle", "pinsight.CycleVerdict", c, t)?;
        }
    }
    out.finish()
}
