//! Fitting the process load and the load cell's lag from the force cycles
//! (bottom dead centre excluded), with a jackknife spread.

use super::*;
use crate::model::Params;
use crate::model::table::Table;

/// Measured data of one cycle for the force fit.
pub(super) struct ForceCycle {
    /// Stroke (mm, phase-corrected, laser zero corrected), force (N), velocity (m/s).
    pub(super) s: Vec<f64>,
    pub(super) f: Vec<f64>,
    pub(super) v: Vec<f64>,
    pub(super) dt: f64,
    /// Where the samples start to matter for a given standoff (see
    /// [`ForceCycle::new`]), so that the objective, evaluated thousands of
    /// times per calibration, skips the approach to the part.
    reach: Reach,
}

/// Prefix maxima of the stroke: the first sample past a level is the first
/// at which the running maximum passes it (subtraction is monotone, so the
/// same comparison on the maximum finds the same sample).
struct Reach {
    /// Running maximum of the finite strokes.
    any: Vec<f64>,
    /// Running maximum of the finite strokes at which the pin bar moves
    /// down (v > 0): the samples the insertion regressors can see.
    down: Vec<f64>,
    /// The first sample moving up or at rest (v ≤ 0, both finite): from
    /// there a withdrawal load may act, whatever the depth.
    first_up: usize,
    /// The samples whose measured force is finite and above 0.5 N, in
    /// order: the only ones of the approach that enter the fit (a scan of
    /// the whole approach per evaluation cost more than the fit itself).
    loud: Vec<usize>,
}

impl ForceCycle {
    pub(super) fn new(s: Vec<f64>, f: Vec<f64>, v: Vec<f64>, dt: f64) -> Self {
        let (mut any, mut down) = (f64::NEG_INFINITY, f64::NEG_INFINITY);
        let (mut any_at, mut down_at) = (Vec::with_capacity(s.len()), Vec::with_capacity(s.len()));
        let mut first_up = s.len();
        for (j, (&sj, &vj)) in s.iter().zip(&v).enumerate() {
            if sj.is_finite() {
                any = any.max(sj);
                if vj.is_finite() {
                    if vj > 0.0 {
                        down = down.max(sj);
                    } else {
                        first_up = first_up.min(j);
                    }
                }
            }
            any_at.push(any);
            down_at.push(down);
        }
        let loud = (0..f.len())
            .filter(|&j| f[j].is_finite() && f[j].abs() > 0.5)
            .collect();
        let reach = Reach {
            any: any_at,
            down: down_at,
            first_up,
            loud,
        };
        ForceCycle { s, f, v, dt, reach }
    }
}

/// Grid points within this many degrees of bottom dead centre are left out of
/// the force fit (the filter still runs through them): the load drops there
/// within a fraction of a degree (c_d(v) as the pin bar stops), so on a
/// 0.5° grid the exact drop time cannot be represented and a few points would
/// dominate the residual.
pub(super) const BDC_EXCLUDE_DEG: f64 = 4.0;

/// The force fit uses the downstroke only up to the first grid point where,
/// in or near the part (depth > −0.5 mm), the pin bar slows below this speed
/// (m/s). With a clearance the pin bar dwells near bottom dead centre while
/// the journal crosses the clearance; the process law then switches on the
/// sign of a velocity of ~1 mm/s (c_d), far below what a differentiated laser
/// signal resolves (~0.02 m/s), so those samples cannot be modelled from the
/// measurement and would dominate the residual.
pub(super) const FIT_MIN_SPEED: f64 = 0.1;

/// The force objective for (standoff, τ): table values by linear least
/// squares; returns (sum of squares, values, samples).
// The fit's inputs are plain numbers of one objective evaluation; a struct
// for them would only be unpacked again.
#[allow(clippy::too_many_arguments)]
pub(super) fn force_fit(
    cycles: &[&ForceCycle],
    knots_mm: &[f64],
    fixed: Option<&[f64]>,
    f_wd: &Table,
    standoff_mm: f64,
    tau: f64,
    v0: f64,
    v1: f64,
) -> (f64, Vec<f64>, usize) {
    let k = knots_mm.len();
    let cd = |v: f64| crate::model::contact::smoothing(v, v0, v1);
    // Hat basis on the knots; beyond the last knot the last value holds.
    let basis = |d: f64, out: &mut [f64]| {
        out.iter_mut().for_each(|x| *x = 0.0);
        if d <= 0.0 {
            return;
        }
        if d >= knots_mm[k - 1] {
            out[k - 1] = 1.0;
            return;
        }
        // The first knot above d, by a scan from the start: d moves
        // through the knots in order along a stroke, so the scan's
        // branches are predicted where a binary search's are not (the
        // same index as `partition_point`).
        let i = knots_mm.iter().position(|&x| x > d).unwrap_or(k).max(1);
        let w = (d - knots_mm[i - 1]) / (knots_mm[i] - knots_mm[i - 1]);
        out[i - 1] = 1.0 - w;
        out[i] = w;
    };
    let mut ata = vec![0.0; k * k];
    let mut atb = vec![0.0; k];
    // The regressors of the fitted samples, k per sample (flat), their
    // measured forces and withdrawal terms: kept for the sum of squares once
    // the values are solved. The buffers are the thread's, reused: a
    // calibration evaluates this objective some 3 000 times, and fresh
    // buffers sized for every sample up to the dead centre (a third of a
    // megabyte for 30 cycles) cost more than the arithmetic.
    let mut scratch = FIT_SCRATCH.take();
    let Scratch {
        cols,
        ys,
        fixed_part,
    } = &mut scratch;
    cols.clear();
    ys.clear();
    fixed_part.clear();
    // The normal equations' upper triangle, accumulated as the rows come
    // (the same sums in the same order as a pass over the stored rows).
    let solve = fixed.is_none();
    let mut accumulate = |r: &[f64], y: f64, fw: f64| {
        if solve {
            let e = y - fw;
            for (i, ((ri, bi), row)) in r
                .iter()
                .zip(atb.iter_mut())
                .zip(ata.chunks_exact_mut(k))
                .enumerate()
            {
                *bi += ri * e;
                for (a, &rj) in row[i..].iter_mut().zip(&r[i..]) {
                    *a += ri * rj;
                }
            }
        }
    };
    let zeros = vec![0.0; k];
    let mut b = vec![0.0; k];
    let mut prev = vec![0.0; k];
    for c in cycles {
        let (ea, b0, b1) = crate::overlay::predict::ramp_lag_coefficients(c.dt, tau);
        let n = c.s.len();
        let half = n / 2;
        let excl = (BDC_EXCLUDE_DEG / 360.0 * n as f64).round() as usize;
        // No sample before the stroke first comes within 0.5 mm of the
        // standoff can stop the fit.
        let near = c.reach.any[..half].partition_point(|&m| !(m - standoff_mm > -0.5));
        let stop = (near..half)
            .find(|&j| {
                c.s[j].is_finite()
                    && c.s[j] - standoff_mm > -0.5
                    && c.v[j].is_finite()
                    && c.v[j] < FIT_MIN_SPEED
            })
            .unwrap_or(half);
        // The approach: until a downward sample passes the standoff (and,
        // with a withdrawal load, until the pin bar first moves up) every
        // regressor and the withdrawal term are exactly zero, and so is the
        // filter's state; only the measured force of those samples is
        // fitted (against zero), as the full loop below would.
        let mut quiet = c.reach.down[..stop].partition_point(|&m| !(m - standoff_mm > 0.0));
        if !f_wd.is_zero() {
            quiet = quiet.min(c.reach.first_up);
        }
        let loud = &c.reach.loud;
        for &j in &loud[..loud.partition_point(|&j| j < quiet)] {
            let y = c.f[j];
            if j.abs_diff(half) > excl {
                cols.extend_from_slice(&zeros);
                ys.push(y);
                fixed_part.push(0.0);
                accumulate(&zeros, y, 0.0);
            }
        }
        let mut state = vec![0.0; k];
        let mut state_wd = 0.0;
        let mut prev_wd = 0.0;
        prev.iter_mut().for_each(|x| *x = 0.0);
        // Nothing after `stop` is fitted, and the filter only looks back.
        for j in quiet..stop {
            let (s, v) = (c.s[j], c.v[j]);
            let d = if s.is_finite() {
                s - standoff_mm
            } else {
                f64::NAN
            };
            let mut wd = 0.0;
            if d.is_finite() && v.is_finite() {
                if v > 0.0 {
                    basis(d, &mut b);
                    let g = cd(v);
                    b.iter_mut().for_each(|x| *x *= g);
                } else {
                    b.iter_mut().for_each(|x| *x = 0.0);
                    wd = -f_wd.eval(d * 1e-3) * cd(-v);
                }
            } else {
                b.iter_mut().for_each(|x| *x = 0.0);
            }
            for ((st, &p), &bi) in state.iter_mut().zip(prev.iter()).zip(b.iter()) {
                *st = ea * *st + b0 * p + b1 * bi;
            }
            state_wd = ea * state_wd + b0 * prev_wd + b1 * wd;
            // `b` is written whole at the next sample.
            std::mem::swap(&mut prev, &mut b);
            prev_wd = wd;
            let y = c.f[j];
            // Samples that carry information: force expected or measured, away from BDC.
            let near_bdc = j.abs_diff(n / 2) <= excl;
            if !near_bdc && y.is_finite() && (state.iter().any(|x| x.abs() > 1e-9) || y.abs() > 0.5)
            {
                cols.extend_from_slice(&state);
                ys.push(y);
                fixed_part.push(state_wd);
                accumulate(&state, y, state_wd);
            }
        }
    }
    let vals: Vec<f64> = match fixed {
        Some(v) => v.to_vec(),
        None => {
            // The upper triangle only (the products are the same either
            // way round), mirrored here.
            for i in 0..k {
                for j in 0..i {
                    ata[i * k + j] = ata[j * k + i];
                }
            }
            // F_ins at zero depth is 0 by the definition of the standoff (the
            // pin meets the part: no load yet). Left free, that value and the
            // standoff trade off along the onset ramp (a + b·(s − standoff)).
            if knots_mm[0] <= 0.0 {
                for i in 0..k {
                    ata[i] = 0.0;
                    ata[i * k] = 0.0;
                }
                ata[0] = 1.0;
                atb[0] = 0.0;
            }
            let m = nalgebra::DMatrix::from_row_slice(k, k, &ata)
                + nalgebra::DMatrix::identity(k, k) * 1e-9;
            let rhs = nalgebra::DVector::from_vec(atb.clone());
            match m.lu().solve(&rhs) {
                Some(x) => x.iter().copied().collect(),
                None => vec![0.0; k],
            }
        }
    };
    let mut ss = 0.0;
    for ((r, &y), &fw) in cols.chunks_exact(k).zip(ys.iter()).zip(fixed_part.iter()) {
        let pred: f64 = r.iter().zip(&vals).map(|(a, b)| a * b).sum::<f64>() + fw;
        ss += (y - pred).powi(2);
    }
    let count = ys.len();
    FIT_SCRATCH.set(scratch);
    (ss, vals, count)
}

/// The force objective's row buffers ([`force_fit`]), one set per thread.
#[derive(Default)]
struct Scratch {
    cols: Vec<f64>,
    ys: Vec<f64>,
    fixed_part: Vec<f64>,
}

thread_local! {
    static FIT_SCRATCH: std::cell::Cell<Scratch> = std::cell::Cell::new(Scratch::default());
}

/// The force fit's fixed inputs and its two searches: the calibration's
/// stages, jackknife and propagation call these instead of spelling the
/// spans each time.
#[derive(Clone, Copy)]
pub(super) struct ForceSearch<'a> {
    pub knots: &'a [f64],
    /// F_ins at the knots when it is not fitted.
    pub fixed: Option<&'a [f64]>,
    pub p: &'a Params,
}

impl ForceSearch<'_> {
    /// Around the nominal standoff: ±2 mm, τ 0–400 µs.
    pub fn wide(&self, cycles: &[&ForceCycle], nominal_so: f64) -> (f64, f64, Vec<f64>) {
        fit_force(
            cycles,
            self.knots,
            self.fixed,
            self.p,
            (nominal_so, 200e-6),
            (2.0, 200e-6),
        )
    }

    /// Around a fit (standoff, τ): ±0.3 mm, ±60 µs.
    pub fn narrow(&self, cycles: &[&ForceCycle], around: (f64, f64)) -> (f64, f64, Vec<f64>) {
        fit_force(cycles, self.knots, self.fixed, self.p, around, (0.3, 60e-6))
    }
}

/// Standoff and τ minimising the force objective (nested Brent searches:
/// the best standoff for each τ inside, τ outside).
pub(super) fn fit_force(
    cycles: &[&ForceCycle],
    knots: &[f64],
    fixed: Option<&[f64]>,
    p: &Params,
    around: (f64, f64),
    spans: (f64, f64),
) -> (f64, f64, Vec<f64>) {
    use crate::solver::roots::brent_min;
    let (s0, t0) = around;
    // The standoff of the best τ so far, kept so that the best τ's inner
    // search is not run again (Brent returns its best point, and keeps the
    // newer of equal ones, as `<=` does here).
    let mut best = (f64::INFINITY, s0);
    let (tau, _, _) = brent_min(
        (t0 - spans.1).max(0.0),
        t0 + spans.1,
        FORCE_TOL_TAU_S,
        |tau| {
            let (so, ss, _) = brent_min(s0 - spans.0, s0 + spans.0, FORCE_TOL_STANDOFF_MM, |so| {
                force_fit(cycles, knots, fixed, &p.f_wd, so, tau, p.v0, p.v1).0
            });
            if ss <= best.0 {
                best = (ss, so);
            }
            ss
        },
    );
    let so = best.1;
    let (_, vals, _) = force_fit(cycles, knots, fixed, &p.f_wd, so, tau, p.v0, p.v1);
    (so, tau, vals)
}

/// Jackknife standard error of estimates from delete-one-block fits.
pub(super) fn jackknife(values: &[f64]) -> f64 {
    let b = values.len();
    if b < 2 {
        return f64::NAN;
    }
    let m = values.iter().sum::<f64>() / b as f64;
    ((b as f64 - 1.0) / b as f64 * values.iter().map(|x| (x - m).powi(2)).sum::<f64>()).sqrt()
}
