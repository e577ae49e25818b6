//! The event search on one accepted step [t0, t1] of the event loop: the
//! contact mode's crossing of δ = 0 (a sign change at the step's ends, or
//! a double crossing seen on the dense output) and the stick law's event.
//! Both return where the event is bracketed; the loop locates the contact
//! event on the new side and restarts there.

use super::runner::Runner;
use crate::model::joint_model::JointModel;
use crate::solver::roots::{bracket_root, maximize};

/// Points per free-flight step at which δ and δ̇ are sampled on the dense
/// output to catch contacts entered and left inside the step.
const FREE_SAMPLES: usize = 8;

/// This mode's contact event on the step from (t0, δ0, δ̇0) to (t1, δ1, δ̇1):
/// onset (δ up through 0) in free flight, loss (δ down through 0) in
/// contact, as (ta, δ(ta), tb, δ(tb)) bracketing it. Counts the double
/// crossings the guard catches.
pub(super) fn contact_crossing<M: JointModel<N>, const N: usize>(
    r: &mut Runner<M, N>,
    in_contact: bool,
    (t0, d0, dd0): (f64, f64, f64),
    (t1, d1, dd1): (f64, f64, f64),
) -> Option<(f64, f64, f64, f64)> {
    let mut crossing: Option<(f64, f64, f64, f64)> = None;
    if !r.model.has_joint() {
        // No joint, no contact events.
    } else if in_contact {
        if d1 < 0.0 {
            crossing = Some((t0, d0, t1, d1));
        } else if dd0 < 0.0 && dd1 > 0.0 {
            // δ turned inside the step: did it dip below zero?
            let (st, m) = r.dense_in(r.model.mode());
            let (tm, vm, n) = maximize(
                |tt| -m.penetration(tt, &st.dense(tt)).0,
                t0,
                t1,
                -d0,
                -d1,
                (t1 - t0) * 1e-9,
            );
            r.aux_evals += n as u64;
            if vm > 0.0 {
                crossing = Some((t0, d0, tm, -vm));
                r.double_crossings += 1;
            }
        }
    } else {
        // Free flight: δ and δ̇ at FREE_SAMPLES points of the dense
        // output, so that a contact entered and left inside the step
        // (a double crossing, possibly after a minimum and a maximum
        // of δ) is seen: a positive sample, or δ̇ turning from + to −
        // in a sub-interval whose maximum is positive.
        r.dense_in(r.model.mode());
        let mut prev = (t0, d0, dd0);
        for k in 1..=FREE_SAMPLES {
            let (tk, dk, ddk) = if k == FREE_SAMPLES {
                (t1, d1, dd1)
            } else {
                let tt = t0 + (t1 - t0) * k as f64 / FREE_SAMPLES as f64;
                let (d, dd) = r.model.penetration(tt, &r.st.dense(tt));
                r.aux_evals += 1;
                (tt, d, dd)
            };
            if dk > 0.0 {
                crossing = Some((prev.0, prev.1, tk, dk));
                break;
            }
            if prev.2 > 0.0 && ddk < 0.0 {
                let st = &r.st;
                let m = &r.model;
                let (tm, vm, n) = maximize(
                    |tt| m.penetration(tt, &st.dense(tt)).0,
                    prev.0,
                    tk,
                    prev.1,
                    dk,
                    (tk - prev.0) * 1e-9,
                );
                r.aux_evals += n as u64;
                if vm > 0.0 {
                    crossing = Some((prev.0, prev.1, tm, vm));
                    break;
                }
            }
            prev = (tk, dk, ddk);
        }
        if crossing.is_some() && d1 <= 0.0 {
            r.double_crossings += 1;
        }
    }
    crossing
}

/// The stick law's event on [t0, t1] (a sign change of its event function
/// from `pg` at t0 to its value at (t1, y1)), located on the dense output.
pub(super) fn process_crossing<M: JointModel<N>, const N: usize>(
    r: &mut Runner<M, N>,
    (t0, pg): (f64, Option<f64>),
    (t1, y1): (f64, &[f64; N]),
    period: f64,
) -> Option<f64> {
    let y1 = *y1;
    let mode_now = r.model.mode();
    let pg1 = r.model.process_event(mode_now, t1, &y1);
    let mut process_at: Option<f64> = None;
    if let (Some(g0), Some(g1)) = (pg, pg1)
        && g0 > 0.0
        && !(g1 > 0.0)
    {
        let (st, m) = r.dense_in(mode_now);
        let (tp, _, n) = bracket_root(
            |tt| m.process_event(mode_now, tt, &st.dense(tt)).unwrap_or(0.0),
            t0,
            g0,
            t1,
            g1,
            4.0 * f64::EPSILON * t1.abs().max(period),
            |_| false,
        );
        r.aux_evals += n as u64;
        process_at = Some(tp);
    }
    process_at
}
