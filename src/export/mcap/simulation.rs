//! A simulation as MCAP: the mechanism's state at every output step and
//! the contact events, on a clock starting at the Unix epoch (a simulation
//! has no wall time; t = 0 is the start of the reported window).
//!
//! Topics (JSON):
//! - `/pinsight/sim/state` (`pinsight.SimState`): every column of the
//!   curves (`simulate --csv`) as one message per output step.
//! - `/pinsight/sim/contact` (`pinsight.ContactEvent`): each impact onset
//!   and loss of contact of the report window.
//! - `/pinsight/sim/summary` (`pinsight.SimSummary`): the run's summary
//!   figures at t = 0.

use super::McapOut;
use crate::sim::SimResult;
use crate::sim::curves::COLUMNS;

fn ns(t_s: f64) -> u64 {
    (t_s.max(0.0) * 1e9).round() as u64
}

/// Builds the MCAP of one run (curves are needed: `simulate` keeps them
/// when `--mcap` is given).
pub fn simulation_mcap(r: &SimResult) -> Result<Vec<u8>, String> {
    let mut out = McapOut::new()?;
    out.log_json(
        "/pinsight/sim/summary",
        "pinsight.SimSummary",
        &r.summary,
        0,
    )?;
    let Some(c) = &r.curves else {
        return Err("the run kept no curves to write".into());
    };
    let t0 = c.t_s.first().copied().unwrap_or(0.0);
    let cols: [&Vec<f64>; 14] = [
        &c.t_s,
        &c.crank_deg,
        &c.stroke_mm,
        &c.vel_mps,
        &c.acc_mps2,
        &c.torque_nm,
        &c.contact_force_n,
        &c.ecc_x_mm,
        &c.ecc_y_mm,
        &c.ideal_stroke_mm,
        &c.ideal_vel_mps,
        &c.ideal_acc_mps2,
        &c.ideal_torque_nm,
        &c.process_force_n,
    ];
    for i in 0..c.len() {
        let row: serde_json::Map<String, serde_json::Value> = COLUMNS
            .iter()
            .zip(cols)
            .map(|(k, v)| {
                let x = v[i];
                (
                    k.to_string(),
                    serde_json::Number::from_f64(x).map_or(serde_json::Value::Null, Into::into),
                )
            })
            .collect();
        out.log_json(
            "/pinsight/sim/state",
            "pinsight.SimState",
            &row,
            ns(c.t_s[i] - t0),
        )?;
    }
    for e in r.events.iter().filter(|e| e.in_report) {
        out.log_json(
            "/pinsight/sim/contact",
            "pinsight.ContactEvent",
            e,
            ns(e.t_s - t0),
        )?;
    }
    out.finish()
}
