//! Calibration: what a log can identify, fitted against the model by least
//! squares on quantities that are not chaotic.
//!
//! 1. Clearance, laser zero and phase — from the stroke. Over the k measured
//!    cycles, per crank angle: the mean stroke M(φ) and its spread across
//!    cycles S(φ). The model's ensemble at clearance c gives the same two
//!    curves (the spread grows with c: the journal rattles in the
//!    clearance). Objective: Σ_φ (S − √(S_c² + σ_n²))²/var + Σ_φ (M + Δz −
//!    M_c + ψ·M_c′)²/var, with the laser-zero correction Δz and a phase ψ
//!    (the laser's lag as a crank angle) solved linearly for each c.
//!    - S is the standard deviation of k cycles in a row, which is biased
//!      low for small k (and more so because consecutive revolutions of the
//!      chaotic motion are correlated); S_c is therefore the same statistic:
//!      the mean over windows of k consecutive simulated revolutions of each
//!      window's σ ([`stroke_fit::curves_windowed`]). σ_n is the laser noise
//!      as it is in the cycles (linear interpolation onto the grid keeps 2/3
//!      of its variance).
//!    - The model is run on a coarse grid of clearances (short ensembles, in
//!      parallel; a scout round of a quarter length first, then the nodes
//!      near its estimate at full length, [`stroke_fit::scout_near`]) to
//!      find c0, then on a fine grid c0 × (0.76 … 1.32) with
//!      long ensembles (5 revolutions per measured cycle, 120–800), again
//!      around the estimate if it left the fine grid. Short ensembles alone
//!      move the minimum by several per cent from one realisation to the
//!      next: that, not a flaw of the statistic, was most of the error seen
//!      on logs of another generator (+4.5 % at 0.5 mm).
//!    - Across the fine nodes the curves are smoothed per crank angle by a
//!      weighted quadratic in c ([`stroke_fit::smooth_grid`]): each node is
//!      one chaotic run with a few per cent of sampling noise, which moved
//!      the fit node by node and made the objective kinked, so that the
//!      minimum stuck at nodes and a jackknife over blocks of the runs saw
//!      no variation. Elsewhere the curves are interpolated linearly; c is
//!      the best node, a 64-point scan between its neighbours, then a
//!      golden-section search.
//!    - The measured curves' sampling variances in the objective are those
//!      of the predicted spread at a first estimate, then held fixed
//!      ([`stroke_fit::Weights`]); with the measured spread itself as the
//!      weight the fit read −1.5 to −2 % low at 12 cycles.
//!    - With a force channel the stroke fit runs in two stages: the part's
//!      load acts on the pin bar from the standoff on and changes the
//!      journal's rattle near BDC, so the fine grid is simulated with the
//!      standoff and F_ins a force fit found after the coarse grid
//!      (predictions at the nominal standoff read 3–11 % low on logs whose
//!      standoff was 0.1–0.3 mm short).
//!    - Cost: the ensembles run DOPRI5 at rtol 1e-4 (statistics, not
//!      trajectories; [`ENSEMBLE_RTOL`], [`ENSEMBLE_METHOD`]) and the force fit's searches (Brent's method)
//!      stop far under a fiftieth of the estimates' σ
//!      ([`FORCE_TOL_STANDOFF_MM`]).
//! 2. Standoff, F_ins table and the load cell's lag — from the force against
//!    the (phase-corrected) measured stroke: the load cell reads
//!    Lag_τ[F_ins(s − standoff)·c_d(v)] on the way down (and the fixed
//!    F_wd on the way up). For a given (standoff, τ) the table values at the
//!    nominal table's depths enter linearly (solved by least squares);
//!    standoff and τ by nested Brent searches.
//! 3. Uncertainties. The clearance (and Δz, ψ): σ² = σ_log² + σ_model²,
//!    where σ_log, the sampling spread of an ensemble of k measured cycles,
//!    is the larger of (a) a parametric bootstrap — the interior fine
//!    nodes' revolutions cut into logs of k cycles, noise added, each fitted
//!    like the log against the grid rebuilt without it — and (b) the
//!    delete-one-block jackknife over blocks of the measured cycles; and
//!    σ_model, the prediction's own sampling noise, is the jackknife over
//!    blocks of simulated revolutions. The jackknife over the log's 8 blocks
//!    alone was too narrow (the chaotic motion is correlated over many
//!    revolutions: 10-revolution windows differ by ±15 % in spread). The
//!    clearance's U95 = t₉₅(ν)·σ with ν from Welch–Satterthwaite (the parts
//!    come from 8 blocks and 12–24 simulated logs; 2σ would cover less than
//!    95 %). The other estimates report U = 2σ. Coverage over a sweep of
//!    synthetic logs: docs/rig-logs.md, "Calibration: bias and coverage"
//!    ([`coverage`], `examples/calib_coverage.rs`).
//!
//! The sensor zeros: the laser zero mark is refined here (Δz); the force
//! tare and the angle offset come from the cycle analysis and are reported
//! as they are.

pub mod coverage;
pub mod flywheel;
mod force_fit;
mod stroke_fit;
mod types;

use force_fit::*;
use stroke_fit::*;
pub use types::*;

use super::compare::OverlayError;
use super::predict::{PredictOptions, Prediction, noise_sigma, predict, velocity};
use crate::model::Params;
use crate::model::table::Table;
use crate::progress::Progress;
use crate::rig::RigLog;
use crate::rig::cycles::{CycleSet, ValueSource};
use rayon::prelude::*;
use std::f64::consts::TAU;

/// Calibrates `base` (the nominal parameters) against a log.
pub fn calibrate(
    log: &RigLog,
    cs: &CycleSet,
    base: &Params,
    opts: &CalibrateOptions,
    progress: &Progress,
) -> Result<CalibrationReport, OverlayError> {
    let file = log.file.clone();
    let n = cs.points_per_rev;
    let mut notes = Vec::new();
    let cycles: Vec<&crate::rig::Cycle> = cs.usable().filter(|c| !c.stroke_mm.is_empty()).collect();
    if cycles.len() < 4 {
        return Err(OverlayError::NoData {
            file,
            message: format!(
                "calibration needs at least 4 usable cycles with a displacement signal, {} found",
                cycles.len()
            ),
        });
    }
    let gear = cs.crank.gear_ratio;
    let motor_rpm = cycles.iter().map(|c| c.crank_rpm).sum::<f64>() / cycles.len() as f64 * gear;
    let noise = log
        .signals
        .displacement
        .as_ref()
        .map_or(0.0, |s| noise_sigma(&s.values))
        // The cycles are the samples interpolated linearly onto the grid: at
        // a point a fraction w between two samples the noise variance is
        // ((1 − w)² + w²)·σ², 2/3·σ² on average over w.
        * (2.0f64 / 3.0).sqrt();

    // 1. Predictions on the clearance grid (in parallel).
    let k_meas = cycles.len();
    let nominal_c = base.clearance * 1e3;
    let mut grid_c: Vec<f64> = opts.clearance_grid_mm.clone();
    grid_c.push(nominal_c);
    grid_c.retain(|c| c.is_finite() && *c > 0.0);
    grid_c.sort_by(|a, b| a.total_cmp(b));
    grid_c.dedup_by(|a, b| (*a - *b).abs() < 1e-9);
    let popts = PredictOptions {
        points_per_rev: n,
        ..opts.predict.clone()
    };
    let refine_revs =
        (opts.refine_cycles_factor * k_meas).clamp(opts.refine_revs.0, opts.refine_revs.1);
    progress.set_total(grid_c.len() as u64 + 2 * opts.refine_factors.len() as u64 + 3);
    // The model at each clearance of `cs` (in parallel); a node the model
    // fails at is left out of `place`, with a note.
    let run_grid = |p0: &Params,
                    cs: &[f64],
                    revs: usize,
                    place: &str,
                    notes: &mut Vec<String>|
     -> Vec<(f64, Prediction)> {
        let runs: Vec<(f64, Result<Prediction, crate::sim::SimError>)> = cs
            .par_iter()
            .map(|&c| {
                let mut p = p0.clone();
                p.clearance = c * 1e-3;
                let o = PredictOptions {
                    revs,
                    ..popts.clone()
                };
                let r = predict(&p, motor_rpm, &o, &Progress::hidden());
                progress.inc(1);
                (c, r)
            })
            .collect();
        let mut ok = Vec::new();
        for (c, r) in runs {
            match r {
                Ok(p) => ok.push((c, p)),
                Err(e) => notes.push(format!(
                    "the model failed at clearance {c:.4} mm ({e}); left out of {place}"
                )),
            }
        }
        ok
    };
    let nb = opts.blocks.max(2);
    // The measured spread is the σ of k_meas cycles in a row: the prediction's
    // spread is the same statistic over windows of k_meas revolutions.
    let curves_pred = |preds: &[(f64, Prediction)], drop: Option<usize>| -> Vec<(f64, Curves)> {
        preds
            .iter()
            .map(|(c, p)| {
                let r = p.stroke_revs.len();
                let rows: Vec<&[f64]> = p
                    .stroke_revs
                    .iter()
                    .enumerate()
                    .filter(|(i, _)| drop.is_none_or(|b| i * nb / r != b))
                    .map(|(_, v)| v.as_slice())
                    .collect();
                (*c, curves_windowed(&rows, n, k_meas))
            })
            .collect()
    };
    let meas_curves = |drop: Option<usize>| -> Curves {
        let k = cycles.len();
        let rows: Vec<&[f64]> = cycles
            .iter()
            .enumerate()
            .filter(|(i, _)| drop.is_none_or(|b| i * nb / k != b))
            .map(|(_, c)| c.stroke_mm.as_slice())
            .collect();
        curves_of(&rows, n)
    };
    let full_meas = meas_curves(None);
    // The coarse grid in two rounds. A scout round runs every node for a
    // fraction of the revolutions ([`SCOUT_FRACTION`]), enough to place the
    // minimum within a few nodes; then only the nodes near
    // the scout's estimate run at full length ([`scout_near`]), and only
    // they stay in the grid. The far nodes only showed that the minimum is
    // not there; kept at a quarter length, their noise let a jackknife
    // replicate now and then jump to one of them (U95 of 0.001 mm became
    // 0.71 mm on one sweep log). The near ones are the same runs a
    // one-round grid makes, so the fine grid, its neighbours and the
    // jackknife see the same curves: the coarse grid costs about half.
    let scout_revs = (popts.revs / SCOUT_FRACTION).max(8).min(popts.revs);
    let mut preds_ok = run_grid(base, &grid_c, scout_revs, "the grid", &mut notes);
    if preds_ok.len() < 3 {
        return Err(OverlayError::NoData {
            file,
            message: "the model ran at fewer than 3 clearances".into(),
        });
    }
    if scout_revs < popts.revs {
        let c_scout = fit_clearance(&full_meas, &curves_pred(&preds_ok, None), noise, None).0;
        let near = scout_near(
            &preds_ok.iter().map(|x| x.0).collect::<Vec<_>>(),
            c_scout,
            &opts.refine_factors,
        );
        progress.set_total(
            grid_c.len() as u64 + near.len() as u64 + 2 * opts.refine_factors.len() as u64 + 3,
        );
        let full = run_grid(
            base,
            &near,
            popts.revs,
            "the coarse grid's second round",
            &mut notes,
        );
        if full.len() >= 3 {
            preds_ok = full;
        } else {
            notes.push(format!(
                "the coarse grid's second round ran at {} clearance(s): the scout runs of {scout_revs} revolutions kept",
                full.len()
            ));
        }
    }
    // The force fit's inputs (section 2), needed between the stroke fit's
    // two stages: the measured stroke advanced by the laser phase ψ
    // (interpolated on the grid) and corrected by Δz, with its velocity.
    let omega_deg = |c: &crate::rig::Cycle| TAU * c.crank_rpm / 60.0;
    let make_fcycles = |dz: f64, psi: f64| -> Vec<ForceCycle> {
        cycles
            .iter()
            .filter(|c| !c.force_n.is_empty())
            .map(|c| {
                let k = psi / (TAU / n as f64);
                let s: Vec<f64> = (0..n)
                    .map(|j| {
                        let x = j as f64 + k;
                        let i0 = x.floor();
                        let w = x - i0;
                        let a = c.stroke_mm[(i0 as i64).rem_euclid(n as i64) as usize];
                        let b = c.stroke_mm[((i0 as i64) + 1).rem_euclid(n as i64) as usize];
                        a + w * (b - a) + dz
                    })
                    .collect();
                let v = velocity(&s, omega_deg(c));
                ForceCycle::new(s, c.force_n.clone(), v, c.duration_s / n as f64)
            })
            .collect()
    };
    let nominal_so = base.standoff * 1e3;
    let knots: Vec<f64> = {
        let k: Vec<f64> = base.f_ins.to_mm().iter().map(|p| p.0).collect();
        if k.len() >= 2 {
            k
        } else {
            vec![0.0, 0.2, 0.5, 1.0, 2.0]
        }
    };
    let nominal_vals: Vec<f64> = knots.iter().map(|&d| base.f_ins.eval(d * 1e-3)).collect();
    let fixed = if opts.fit_f_ins {
        None
    } else {
        Some(nominal_vals.as_slice())
    };
    let search = ForceSearch {
        knots: &knots,
        fixed,
        p: base,
    };
    // Coarse grid → c0; then long ensembles on a fine grid around c0 (the
    // coarse ensembles are short: their sampling noise moves the minimum by
    // several per cent from one realisation to the next), again around the
    // estimate when it falls outside the first fine grid.
    let coarse = preds_ok;
    let coarse_fit = fit_clearance(&full_meas, &curves_pred(&coarse, None), noise, None);
    let run_stage = |p0: &Params, centre: f64, revs: usize, notes: &mut Vec<String>| {
        let mut centre = centre;
        let mut preds_ok = coarse.clone();
        let mut fine_c: Vec<f64> = Vec::new();
        // The fine nodes the curves are smoothed over: the last pass's range.
        let mut smooth_c: Vec<f64> = Vec::new();
        let mut pass = 0;
        loop {
            let new_c: Vec<f64> = opts
                .refine_factors
                .iter()
                .map(|f| centre * f)
                .filter(|c| *c > 1e-3 && !fine_c.iter().any(|x| (x - c).abs() < 1e-9))
                .collect();
            if new_c.len() >= 2 {
                let (lo, hi) = (new_c[0], new_c[new_c.len() - 1]);
                let fine = run_grid(p0, &new_c, revs, "the fine grid", notes);
                preds_ok.retain(|(c, _)| {
                    *c < lo * 0.999
                        || *c > hi * 1.001
                        || fine_c.iter().any(|x| (x - c).abs() < 1e-12)
                });
                fine_c.extend(fine.iter().map(|x| x.0));
                preds_ok.extend(fine);
                preds_ok.sort_by(|a, b| a.0.total_cmp(&b.0));
                smooth_c = fine_c
                    .iter()
                    .copied()
                    .filter(|c| *c >= lo * 0.999 && *c <= hi * 1.001)
                    .collect();
            }
            let full_raw = curves_pred(&preds_ok, None);
            let full_pred = smooth_grid(&full_raw, &smooth_c);
            let fit = fit_clearance(&full_meas, &full_pred, noise, None);
            pass += 1;
            let (lo, hi) = fine_c
                .iter()
                .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), c| {
                    (a.min(*c), b.max(*c))
                });
            if pass >= 2 || (fit.0 >= lo * 1.03 && fit.0 <= hi * 0.97) {
                return (preds_ok, fine_c, smooth_c, full_raw, full_pred, fit);
            }
            centre = fit.0;
        }
    };
    // With a force channel the fine grid is simulated with the fitted
    // standoff and F_ins, not the nominal ones: the part's load acts on the
    // pin bar from the standoff on and changes the journal's rattle near
    // BDC, so predictions made with the nominal standoff and F_ins read the
    // clearance wrong when the rig's differ (measured over the coverage
    // sweep: error/truth correlated +0.31 with standoff − nominal; 5 of the
    // 6 logs outside U95 had a standoff 0.1–0.27 mm short of the nominal,
    // reading 3–11 % low). The force fit needs Δz and ψ, which the coarse
    // grid's fit gives well enough: the force fit is repeated on the final
    // Δz and ψ below. (Until this stop a first stage of fine runs of half
    // length located c, Δz and ψ for it: a fifth of the model time, and
    // no better; docs/rig-logs.md.)
    let has_force = cycles.iter().any(|c| !c.force_n.is_empty());
    let mut stage_params = base.clone();
    if has_force {
        let (c1, dz1, psi1) = coarse_fit;
        let fc = make_fcycles(dz1, psi1);
        let refs: Vec<&ForceCycle> = fc.iter().collect();
        let (so, _, vals) = search.wide(&refs, nominal_so);
        // A first force fit that jumps by more than 1 mm from the nominal
        // standoff is taken as failed (seen once in 78 sweep logs: 12.77 mm
        // against a true 14.09, the final fit then found the truth): the
        // fine grid then runs with the nominal parameters.
        let plausible = so.is_finite() && (so - nominal_so).abs() <= 1.0;
        if plausible {
            stage_params.standoff = so * 1e-3;
        }
        if opts.fit_f_ins && plausible {
            let pts: Vec<(f64, f64)> = knots
                .iter()
                .zip(&vals)
                .map(|(d, f)| (*d, f.max(0.0)))
                .collect();
            if let Ok(t) = Table::from_mm(&pts) {
                stage_params.f_ins = t;
            }
        }
        notes.push(if plausible {
            format!(
                "stroke fit in two stages: {c1:.4} mm on the coarse grid with the nominal standoff {nominal_so:.3} mm, then the fine grid simulated with the fitted standoff {so:.3} mm and F_ins"
            )
        } else {
            format!(
                "stroke fit in two stages: the force fit after the coarse grid gave a standoff of {so:.3} mm, more than 1 mm from the nominal {nominal_so:.3} mm; the fine grid simulated with the nominal parameters"
            )
        });
    }
    let stage = run_stage(&stage_params, coarse_fit.0, refine_revs, &mut notes);
    let (preds_ok, fine_c, smooth_c, full_raw, full_pred, fit) = stage;
    // The measured curves' variances fixed at the predicted spread there
    // (not the measured one: see `Weights`), and the fit repeated with them.
    let weights = Weights::of(&interp_curves(&full_pred, fit.0), noise, k_meas);
    let fit = fit_clearance(&full_meas, &full_pred, noise, Some(&weights));
    let w = Some(&weights);
    let grid_c: Vec<f64> = preds_ok.iter().map(|x| x.0).collect();
    let (c_fit, dz, psi) = fit;
    let profile: Vec<(f64, f64)> = full_pred
        .iter()
        .map(|(c, cu)| (*c, stroke_objective(&full_meas, cu, noise, w).0))
        .collect();
    // Jackknife: blocks of measured cycles, blocks of simulated revolutions.
    let jk_meas: Vec<(f64, f64, f64)> = (0..nb.min(cycles.len()))
        .into_par_iter()
        .map(|b| fit_clearance(&meas_curves(Some(b)), &full_pred, noise, w))
        .collect();
    let jk_pred: Vec<(f64, f64, f64)> = (0..nb)
        .into_par_iter()
        .map(|b| {
            let g = smooth_grid(&curves_pred(&preds_ok, Some(b)), &smooth_c);
            fit_clearance(&full_meas, &g, noise, w)
        })
        .collect();
    // The measured ensemble's own sampling spread, from the model: windows of
    // k_meas consecutive revolutions simulated at the fitted clearance (with
    // the measured noise added), each fitted like the log. The cycles of the
    // chaotic motion are correlated over several revolutions, so the
    // delete-a-block jackknife over the log's few blocks underestimates it.
    let fine_nodes: Vec<(usize, &[Vec<f64>])> = preds_ok
        .iter()
        .enumerate()
        .filter(|(i, (_, p))| {
            let is_fine = |j: usize| {
                preds_ok
                    .get(j)
                    .is_some_and(|(c, _)| fine_c.iter().any(|f| (f - c).abs() < 1e-12))
            };
            // Interior fine nodes only: a log of a node at the fine grid's
            // edge would be fitted against a short, noisy coarse neighbour.
            *i > 0
                && is_fine(*i - 1)
                && is_fine(*i)
                && is_fine(*i + 1)
                && p.stroke_revs.len() >= 2 * k_meas
        })
        .map(|(i, (_, p))| (i, p.stroke_revs.as_slice()))
        .collect();
    let boot = bootstrap(&full_raw, &fine_nodes, k_meas, noise, c_fit, &smooth_c, w);
    progress.inc(1);
    let combine = |f: fn(&(f64, f64, f64)) -> f64| {
        let a = jackknife(&jk_meas.iter().map(f).collect::<Vec<_>>());
        let a_boot = sample_sd(&boot.iter().map(f).collect::<Vec<_>>());
        let a = if a_boot.is_finite() { a.max(a_boot) } else { a };
        let b = jackknife(&jk_pred.iter().map(f).collect::<Vec<_>>());
        (a * a + b * b).sqrt()
    };
    let sc = combine(|x| x.0);
    // Coverage factor for the clearance: Student's t at 95 % for the
    // Welch–Satterthwaite degrees of freedom of σ_c (its two parts are
    // estimated from a few blocks or simulated logs, so 2σ would cover less
    // than 95 %).
    let k95 = {
        let jm = jackknife(&jk_meas.iter().map(|x| x.0).collect::<Vec<_>>());
        let bm = sample_sd(&boot.iter().map(|x| x.0).collect::<Vec<_>>());
        let (a, nu_a) = if bm.is_finite() && bm >= jm {
            (bm, boot.len().saturating_sub(1).max(1) as f64)
        } else {
            (jm, jk_meas.len().saturating_sub(1).max(1) as f64)
        };
        let b = jackknife(&jk_pred.iter().map(|x| x.0).collect::<Vec<_>>());
        let nu_b = jk_pred.len().saturating_sub(1).max(1) as f64;
        let b4 = if b.is_finite() { b.powi(4) / nu_b } else { 0.0 };
        let nu = sc.powi(4) / (a.powi(4) / nu_a + b4);
        t95(nu)
    };
    let sdz = combine(|x| x.1);
    let spsi = combine(|x| x.2);
    if boot.len() >= 2 {
        let m = boot.iter().map(|x| x.0).sum::<f64>() / boot.len() as f64;
        notes.push(format!(
            "clearance σ {:.4} mm: {} simulated logs of {k_meas} cycles fitted with errors {m:+.4} ± {:.4} mm; jackknife over the log's blocks {:.4} mm, over the prediction's {:.4} mm",
            sc,
            boot.len(),
            sample_sd(&boot.iter().map(|x| x.0).collect::<Vec<_>>()),
            jackknife(&jk_meas.iter().map(|x| x.0).collect::<Vec<_>>()),
            jackknife(&jk_pred.iter().map(|x| x.0).collect::<Vec<_>>()),
        ));
    }
    let edge = grid_c.first().is_some_and(|&lo| c_fit <= lo * 1.001)
        || grid_c.last().is_some_and(|&hi| c_fit >= hi * 0.999);
    if edge {
        notes.push(format!("the clearance estimate {c_fit:.3} mm is at the edge of the simulated grid ({:.3}–{:.3} mm): treat it as a bound", grid_c[0], grid_c[grid_c.len() - 1]));
    }
    let before_curves = interp_curves(&full_pred, nominal_c);
    let (_, _, _, b_spread, _) = stroke_objective(&full_meas, &before_curves, noise, w);
    // Before: the cycle analysis's zeros (no Δz, no phase).
    let b_mean = {
        let r: Vec<f64> = full_meas
            .mean
            .iter()
            .zip(&before_curves.mean)
            .map(|(a, b)| a - b)
            .filter(|x| x.is_finite())
            .collect();
        (r.iter().map(|x| x * x).sum::<f64>() / r.len().max(1) as f64).sqrt()
    };
    let (_, _, _, a_spread, a_mean) =
        stroke_objective(&full_meas, &interp_curves(&full_pred, c_fit), noise, w);

    // 2. Force: standoff, F_ins, load-cell lag (against the stroke corrected
    // by the final Δz and ψ; `make_fcycles` above).
    let fcycles = make_fcycles(dz, psi);
    let mut estimates = Vec::new();
    let meta_or = |m: Option<f64>| m;
    let mut fitted = base.clone();
    fitted.clearance = c_fit * 1e-3;
    let mut table_out = Vec::new();
    let (mut before_force, mut after_force) = (f64::NAN, f64::NAN);
    if fcycles.is_empty() {
        notes.push("no force channel: standoff and F_ins cannot be identified; the nominal values are kept".into());
    } else {
        let all: Vec<&ForceCycle> = fcycles.iter().collect();
        let (so, tau, vals) = search.wide(&all, nominal_so);
        let nb_f = nb.min(all.len());
        let jk: Vec<(f64, f64, Vec<f64>)> = (0..nb_f)
            .into_par_iter()
            .map(|b| {
                let sub: Vec<&ForceCycle> = all
                    .iter()
                    .enumerate()
                    .filter(|(i, _)| i * nb_f / all.len() != b)
                    .map(|(_, c)| *c)
                    .collect();
                search.narrow(&sub, (so, tau))
            })
            .collect();
        progress.inc(1);
        let s_so_jk = jackknife(&jk.iter().map(|x| x.0).collect::<Vec<_>>());
        let s_tau_jk = jackknife(&jk.iter().map(|x| x.1).collect::<Vec<_>>());
        // The force is fitted against the stroke corrected by Δz and ψ: their
        // uncertainties carry into the standoff (1:1 for Δz) and the lag.
        // Propagated by refitting with each moved by its σ (first order).
        let moved: Vec<(f64, f64)> = [(dz + sdz, psi), (dz, psi + spsi)]
            .into_par_iter()
            .map(|(d, ps)| {
                if !(d.is_finite() && ps.is_finite()) {
                    return (f64::NAN, f64::NAN);
                }
                let fc = make_fcycles(d, ps);
                let refs: Vec<&ForceCycle> = fc.iter().collect();
                let (so2, tau2, _) = search.narrow(&refs, (so, tau));
                (so2 - so, tau2 - tau)
            })
            .collect();
        let prop = |f: fn(&(f64, f64)) -> f64| -> f64 {
            moved
                .iter()
                .map(f)
                .filter(|x| x.is_finite())
                .map(|x| x * x)
                .sum::<f64>()
        };
        let s_so = (s_so_jk * s_so_jk + prop(|x| x.0)).sqrt();
        let s_tau = (s_tau_jk * s_tau_jk + prop(|x| x.1)).sqrt();
        notes.push(format!(
            "standoff σ {:.4} mm = jackknife {:.4} mm ⊕ laser zero/phase propagated {:.4} mm",
            s_so,
            s_so_jk,
            prop(|x| x.0).sqrt()
        ));
        let (ss_b, _, nb_s) = force_fit(
            &all,
            &knots,
            Some(&nominal_vals),
            &base.f_wd,
            nominal_so,
            0.0,
            base.v0,
            base.v1,
        );
        let (ss_a, _, na_s) = force_fit(
            &all,
            &knots,
            Some(&vals),
            &base.f_wd,
            so,
            tau,
            base.v0,
            base.v1,
        );
        before_force = (ss_b / nb_s.max(1) as f64).sqrt();
        after_force = (ss_a / na_s.max(1) as f64).sqrt();
        estimates.push(Estimate {
            name: "standoff".into(),
            unit: "mm".into(),
            nominal: Some(nominal_so),
            value: so,
            sigma: s_so,
            u95: 2.0 * s_so,
            method: "force against the measured stroke: onset of F_ins(s − standoff), with the load cell's lag".into(),
        });
        estimates.push(Estimate {
            name: "force_lag".into(),
            unit: "us".into(),
            nominal: None,
            value: tau * 1e6,
            sigma: s_tau * 1e6,
            u95: 2.0 * s_tau * 1e6,
            method: "first-order lag of the load cell fitted with the standoff".into(),
        });
        fitted.standoff = so * 1e-3;
        if opts.fit_f_ins {
            let pts: Vec<(f64, f64)> = knots
                .iter()
                .zip(&vals)
                .map(|(d, f)| (*d, f.max(0.0)))
                .collect();
            match Table::from_mm(&pts) {
                Ok(t) => fitted.f_ins = t,
                Err(e) => notes.push(format!("fitted F_ins table rejected ({e}); nominal kept")),
            }
            for (i, (&d, &f)) in knots.iter().zip(&vals).enumerate() {
                let s = jackknife(&jk.iter().map(|x| x.2[i]).collect::<Vec<_>>());
                table_out.push((d, f, s));
            }
        }
    }

    // 3. Estimates of the stroke fit.
    let lz = &cs.offsets.laser_zero_mm;
    estimates.insert(
        0,
        Estimate {
            name: "clearance".into(),
            unit: "mm".into(),
            nominal: Some(nominal_c),
            value: c_fit,
            sigma: sc,
            u95: k95 * sc,
            method: "spread and mean of the stroke across cycles against the model's ensembles"
                .into(),
        },
    );
    estimates.insert(
        1,
        Estimate {
            name: "laser_zero".into(),
            unit: "mm".into(),
            nominal: meta_or(log.meta.laser_zero_mm),
            value: lz.applied + dz,
            sigma: sdz,
            u95: 2.0 * sdz,
            method: format!(
                "mean stroke against the model's mean stroke at the fitted clearance (the cycle analysis had {:.4} mm, {})",
                lz.applied,
                match lz.source {
                    ValueSource::Metadata => "from the metadata",
                    ValueSource::Override => "a session override",
                    _ => "an ideal-mechanism estimate",
                }
            ),
        },
    );
    let omega = TAU * motor_rpm / gear / 60.0;
    estimates.insert(
        2,
        Estimate {
            name: "laser_lag".into(),
            unit: "us".into(),
            nominal: None,
            value: psi / omega * 1e6,
            sigma: spsi / omega * 1e6,
            u95: 2.0 * spsi / omega * 1e6,
            method: "phase of the mean stroke against the model (the laser's lag; with an uncalibrated encoder it also holds the angle offset's error)".into(),
        },
    );
    let o = &cs.offsets;
    if let Some(e) = o.force_tare_n.estimate {
        estimates.push(Estimate {
            name: "force_tare".into(),
            unit: "N".into(),
            nominal: log.meta.force_tare_n,
            value: e,
            sigma: o.force_tare_n.sigma.unwrap_or(f64::NAN),
            u95: 2.0 * o.force_tare_n.sigma.unwrap_or(f64::NAN),
            method: "off-part load-cell reading (cycle analysis)".into(),
        });
    }
    if let Some(e) = o.angle_offset_rad.estimate {
        estimates.push(Estimate {
            name: "angle_offset".into(),
            unit: "rad".into(),
            nominal: log.meta.angle_offset_rad,
            value: e,
            sigma: o.angle_offset_rad.sigma.unwrap_or(f64::NAN),
            u95: 2.0 * o.angle_offset_rad.sigma.unwrap_or(f64::NAN),
            method: o.angle_offset_rad.note.clone(),
        });
    }
    progress.inc(1);

    let mut toml = format!(
        "# pinsight calibrate {file}\n# motor {motor_rpm:.1} rpm, {} cycles. Estimates (value ± U95):\n",
        cycles.len()
    );
    for e in &estimates {
        toml.push_str(&format!(
            "#   {} = {:.5} ± {:.5} {}\n",
            e.name, e.value, e.u95, e.unit
        ));
    }
    toml.push_str(&format!(
        "# Sensor settings for `pinsight overlay`: --meta laser_zero_mm={:.4} --laser-lag-us {:.1}{}\n",
        lz.applied + dz,
        psi / omega * 1e6,
        estimates.iter().find(|e| e.name == "force_lag").map_or(String::new(), |e| format!(" --force-lag-us {:.1}", e.value))
    ));
    toml.push_str(&fitted.to_toml());
    Ok(CalibrationReport {
        file,
        motor_rpm,
        cycles: cycles.len(),
        estimates,
        f_ins_table: table_out,
        before: Residuals {
            stroke_spread_rms_mm: b_spread,
            stroke_mean_rms_mm: b_mean,
            force_rms_n: before_force,
        },
        after: Residuals {
            stroke_spread_rms_mm: a_spread,
            stroke_mean_rms_mm: a_mean,
            force_rms_n: after_force,
        },
        clearance_profile: profile,
        params: fitted,
        params_toml: toml,
        notes,
    })
}

#[cfg(test)]
mod tests;
