//! The end of a run of the event loop: the summary figures from the
//! runner's peaks, integrals and counts, the ideal mechanism's peaks over
//! the same window, the notes, and the states at the window's ends.

use super::runner::Runner;
use super::{Finished, RunSetup};
use crate::model::joint_model::JointModel;
use crate::model::params::Params;
use crate::sim::summary::{Q_ACC, Q_DS, Q_DV, Q_FN, Q_M12, Q_PEN, Q_PROC, Q_SMAX, Q_SMIN};
use crate::sim::{SimOptions, SimResult, Summary};
use std::time::Instant;

/// Where and how the loop ended: the run's setup, its clock, the steps it
/// took in each mode, the final time and state, and the ΔM² quadrature's
/// value where the reported window began.
pub(super) struct LoopEnd<'a, const N: usize> {
    pub p: &'a Params,
    pub opts: &'a SimOptions,
    pub how: &'a RunSetup<'a>,
    pub start: Instant,
    pub fixed_step: Option<f64>,
    pub contact_steps: u64,
    pub free_steps: u64,
    pub t: f64,
    pub y: [f64; N],
    pub q_start: f64,
}

/// The finished run: summary, curves, events, work and notes.
pub(super) fn finish<M: JointModel<N>, const N: usize>(
    mut r: Runner<'_, M, N>,
    end: LoopEnd<'_, N>,
) -> Finished<N> {
    let LoopEnd {
        p,
        opts,
        how,
        start,
        fixed_step,
        contact_steps,
        free_steps,
        t,
        y,
        q_start,
    } = end;
    let c = r.model.clearance();
    let (t_rep, t_end) = (r.t_rep, r.t_end);
    let stats = *r.st.stats();
    let tw = t_end - t_rep;
    // Without the figures nothing was tracked: every figure below reads NaN.
    let best = if opts.figures {
        r.tracker.best
    } else {
        [f64::NAN; crate::sim::summary::NQ]
    };
    let ideal_peaks = if opts.figures {
        let ideal = crate::sim::ideal_run::run(
            how.ideal,
            &SimOptions {
                level: crate::sim::Level::Ideal,
                grid_deg: None,
                ..opts.clone()
            },
        );
        (ideal.summary.peak_accel_mps2, ideal.summary.peak_torque_nm)
    } else {
        (f64::NAN, None)
    };
    let nan_unless = |x: f64| if opts.figures { x } else { f64::NAN };
    let mut notes = Vec::new();
    if r.double_crossings > 0 {
        notes.push(format!(
            "the double-crossing guard caught {} contact(s) that a step would have skipped",
            r.double_crossings
        ));
    }
    if stats.stiff_steps > 0 {
        notes.push(format!(
            "stiffness detected on {} steps: an implicit method (radau5) may be cheaper",
            stats.stiff_steps
        ));
    }
    let summary = Summary {
        preset: p.preset.clone(),
        motor_rpm: p.motor_rpm,
        clearance_mm: c * 1e3,
        material: p.material_name(),
        contact_model: p.contact_model.name().into(),
        level: how.level.into(),
        method: opts.method.name().into(),
        rtol: opts.rtol,
        atol: opts.atol,
        step_s: fixed_step,
        warmup_revs: opts.warmup,
        revs: opts.revs,
        view: opts.view().into(),
        steps: stats.steps,
        rejected_steps: stats.rejected,
        rhs_evals: stats.rhs_evals,
        aux_evals: r.aux_evals,
        jacobians: stats.jacobians,
        wall_ms: start.elapsed().as_secs_f64() * 1e3,
        n_impacts: r.n_impacts,
        peak_accel_mps2: best[Q_ACC],
        peak_contact_force_n: best[Q_FN],
        disp_dev_mean_mm: nan_unless(r.abs_s.finish(y[M::Q_S]) / tw * 1e3),
        disp_dev_max_mm: best[Q_DS] * 1e3,
        vel_dev_mean_mps: nan_unless(r.abs_v.finish(r.model.deviation(t, &y).0) / tw),
        vel_dev_max_mps: best[Q_DV],
        peak_torque_nm: Some(best[Q_M12]),
        torque_dev_rms_nm: Some(((y[M::Q_DM2] - q_start) / tw).max(0.0).sqrt()),
        stroke_min_mm: -best[Q_SMIN] * 1e3,
        stroke_max_mm: best[Q_SMAX] * 1e3,
        peak_process_force_n: Some(best[Q_PROC]),
        ideal_peak_accel_mps2: ideal_peaks.0,
        ideal_peak_torque_nm: ideal_peaks.1,
        double_crossings_caught: r.double_crossings,
        peak_penetration_um: best[Q_PEN].max(0.0) * 1e6,
        contact_steps,
        free_steps,
        motor: None,
        stick: (r.stick.events > 0 || p.process_law == crate::model::params::ProcessLaw::Stick)
            .then_some(crate::sim::summary::StickSummary {
                events: r.stick.events,
                held_phases: r.stick.phases,
                held_steps: r.stick.held_steps,
                max_steps_per_phase: r.stick.max_phase_steps,
            }),
    };
    Finished {
        result: SimResult {
            summary,
            curves: r.curves,
            events: r.events,
            stats,
            notes,
        },
        window_start: r.window_start,
        end: (t, y),
        best,
    }
}
