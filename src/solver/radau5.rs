//! Radau IIA of order 5 (three-stage implicit collocation), after Hairer &
//! Wanner's RADAU5: simplified Newton iterations with a finite-difference
//! Jacobian, the embedded error estimate filtered through
//! (γ₀⁻¹/h · I − J)⁻¹, Gustafsson's predictive step-size control, and the
//! collocation polynomial as dense output.
//!
//! Difference from RADAU5: the 3N×3N Newton matrix I − h A⊗J is factorised
//! as it stands (N is 7 here) instead of through the eigen-decomposition of
//! A into one real and one complex N×N system — simpler, and the same
//! iterates.

use super::control::Position;
use super::control::{NextStep, derivative_at_end, trial_step};
use super::{Scale, Stats, StepError, StepperConfig, System, Tolerance, all_finite, wrms};

const SQ6: f64 = 2.449_489_742_783_178;
const C1: f64 = (4.0 - SQ6) / 10.0;
const C2: f64 = (4.0 + SQ6) / 10.0;
const A: [[f64; 3]; 3] = [
    [
        (88.0 - 7.0 * SQ6) / 360.0,
        (296.0 - 169.0 * SQ6) / 1800.0,
        (-2.0 + 3.0 * SQ6) / 225.0,
    ],
    [
        (296.0 + 169.0 * SQ6) / 1800.0,
        (88.0 + 7.0 * SQ6) / 360.0,
        (-2.0 - 3.0 * SQ6) / 225.0,
    ],
    [(16.0 - SQ6) / 36.0, (16.0 + SQ6) / 36.0, 1.0 / 9.0],
];
const CS: [f64; 3] = [C1, C2, 1.0];
const DD1: f64 = -(13.0 + 7.0 * SQ6) / 3.0;
const DD2: f64 = (-13.0 + 7.0 * SQ6) / 3.0;
const DD3: f64 = -1.0 / 3.0;
const NIT: u32 = 7;
const SAFE: f64 = 0.9;
const FACL: f64 = 5.0;
const FACR: f64 = 1.0 / 8.0;
const THET: f64 = 0.001;

/// The real eigenvalue of A⁻¹, 1/γ₀.
fn u1() -> f64 {
    let x = (6.0 + 81f64.cbrt() - 9f64.cbrt()) / 30.0;
    1.0 / x
}

/// Dense LU decomposition with partial pivoting.
#[derive(Debug, Clone, Default)]
struct Lu {
    n: usize,
    a: Vec<f64>,
    piv: Vec<usize>,
}

impl Lu {
    /// Factorises the n×n row-major matrix `m`; None when singular.
    fn factor(n: usize, mut a: Vec<f64>) -> Option<Self> {
        let mut piv = vec![0; n];
        for k in 0..n {
            let mut p = k;
            let mut best = a[k * n + k].abs();
            for i in k + 1..n {
                let v = a[i * n + k].abs();
                if v > best {
                    best = v;
                    p = i;
                }
            }
            if !(best > 0.0) || !best.is_finite() {
                return None;
            }
            piv[k] = p;
            if p != k {
                for j in 0..n {
                    a.swap(k * n + j, p * n + j);
                }
            }
            let d = a[k * n + k];
            for i in k + 1..n {
                let f = a[i * n + k] / d;
                a[i * n + k] = f;
                if f != 0.0 {
                    for j in k + 1..n {
                        a[i * n + j] -= f * a[k * n + j];
                    }
                }
            }
        }
        Some(Self { n, a, piv })
    }

    fn solve(&self, b: &mut [f64]) {
        let n = self.n;
        // Whole rows (multipliers included) were swapped while factorising:
        // apply every interchange first, then substitute forwards.
        for k in 0..n {
            let p = self.piv[k];
            if p != k {
                b.swap(k, p);
            }
        }
        for k in 0..n {
            for i in k + 1..n {
                b[i] -= self.a[i * n + k] * b[k];
            }
        }
        for k in (0..n).rev() {
            let mut s = b[k];
            for j in k + 1..n {
                s -= self.a[k * n + j] * b[j];
            }
            b[k] = s / self.a[k * n + k];
        }
    }
}

#[derive(Debug, Clone)]
pub struct Radau5<const N: usize> {
    pub(crate) cfg: StepperConfig<N>,
    /// The tolerances as RADAU5 uses them internally (rtol' = 0.1 rtol^(2/3)).
    tol: Tolerance<N>,
    fnewt: f64,
    pub pos: Position<N>,
    /// Stage increments of the last accepted step (dense output).
    z: [[f64; N]; 3],
    pub next: NextStep,
    h_used: f64,
    jac: Vec<f64>,
    jac_fresh: bool,
    jac_valid: bool,
    lu_full: Option<Lu>,
    lu_err: Option<Lu>,
    lu_h: f64,
    theta_last: f64,
    first: bool,
    rejected_last: bool,
    hacc: f64,
    erracc: f64,
    faccon: f64,
    pub stats: Stats,
}

impl<const N: usize> Radau5<N> {
    pub fn new(cfg: StepperConfig<N>) -> Self {
        let mut tol = cfg.tol;
        let rtol = tol.rtol.max(1e-14);
        let quot_tol = 0.1 * rtol.powf(2.0 / 3.0);
        for i in 0..N {
            tol.atol[i] = quot_tol * tol.atol[i] / rtol;
        }
        tol.rtol = quot_tol;
        let fnewt = (10.0 * f64::EPSILON / quot_tol).max(0.03f64.min(quot_tol.sqrt()));
        Self {
            cfg,
            tol,
            fnewt,
            pos: Position::new(),
            z: [[0.0; N]; 3],
            next: NextStep::new(cfg.h, true),
            h_used: 0.0,
            jac: vec![0.0; N * N],
            jac_fresh: false,
            jac_valid: false,
            lu_full: None,
            lu_err: None,
            lu_h: 0.0,
            theta_last: 1.0,
            first: true,
            rejected_last: false,
            hacc: 0.0,
            erracc: 1e-2,
            faccon: 1.0,
            stats: Stats::default(),
        }
    }

    pub fn reset<S: System<N>>(&mut self, sys: &S, t: f64, y: [f64; N], fresh_step: bool) {
        self.pos.restart(sys, t, y, &mut self.stats);
        self.z = [[0.0; N]; 3];
        self.h_used = 0.0;
        self.jac_valid = false;
        self.lu_full = None;
        self.lu_err = None;
        self.first = true;
        self.rejected_last = false;
        self.faccon = 1.0;
        self.next.restart(fresh_step);
    }

    fn compute_jacobian<S: System<N>>(&mut self, sys: &S) {
        let (t, y, f0) = (self.pos.t, self.pos.y, self.pos.f);
        for j in 0..N {
            if matches!(self.cfg.tol.scale[j], Scale::Ignore) {
                // Quadrature components: nothing depends on them.
                for i in 0..N {
                    self.jac[i * N + j] = 0.0;
                }
                continue;
            }
            let delt = (f64::EPSILON * 1e-5f64.max(y[j].abs())).sqrt();
            let mut yp = y;
            yp[j] += delt;
            let mut fp = [0.0; N];
            sys.rhs(t, &yp, &mut fp);
            self.stats.rhs_evals += 1;
            for i in 0..N {
                self.jac[i * N + j] = (fp[i] - f0[i]) / delt;
            }
        }
        self.stats.jacobians += 1;
        self.jac_valid = true;
        self.jac_fresh = true;
    }

    fn factorise(&mut self, h: f64) -> bool {
        let n3 = 3 * N;
        let mut m = vec![0.0; n3 * n3];
        for bi in 0..3 {
            for bj in 0..3 {
                let a = h * A[bi][bj];
                for i in 0..N {
                    for j in 0..N {
                        let mut v = -a * self.jac[i * N + j];
                        if bi == bj && i == j {
                            v += 1.0;
                        }
                        m[(bi * N + i) * n3 + bj * N + j] = v;
                    }
                }
            }
        }
        let fac1 = u1() / h;
        let mut e = vec![0.0; N * N];
        for i in 0..N {
            for j in 0..N {
                e[i * N + j] = -self.jac[i * N + j] + if i == j { fac1 } else { 0.0 };
            }
        }
        self.stats.lu_decompositions += 2;
        self.lu_full = Lu::factor(n3, m);
        self.lu_err = Lu::factor(N, e);
        self.lu_h = h;
        self.lu_full.is_some() && self.lu_err.is_some()
    }

    pub fn step<S: System<N>>(&mut self, sys: &S, t_end: f64, h_max: f64) -> Result<(), StepError> {
        let h_max = h_max.min(self.cfg.h_max);
        let ncon = self.tol.n_controlled();
        let (t, y, f0) = (self.pos.t, self.pos.y, self.pos.f);
        let (cfg, pos) = (&self.cfg, &self.pos);
        let mut h = self
            .next
            .size(cfg, &self.tol, sys, pos, 3, h_max, &mut self.stats);
        let mut newton_fails = 0u32;
        loop {
            let (h_try, last) = trial_step(&self.stats, self.cfg.max_steps, t, h, t_end)?;
            h = h_try;
            if !self.jac_valid {
                self.compute_jacobian(sys);
            }
            if (self.lu_full.is_none() || self.lu_h != h) && !self.factorise(h) {
                self.stats.newton_failures += 1;
                newton_fails += 1;
                if newton_fails > 10 {
                    return Err(StepError::NewtonFailure { t, h });
                }
                h *= 0.5;
                continue;
            }
            // Starting values: extrapolate the last collocation polynomial.
            let mut z = [[0.0; N]; 3];
            if !self.first && self.h_used > 0.0 {
                for s in 0..3 {
                    let tt = t + CS[s] * h;
                    let u = self.dense(tt);
                    for i in 0..N {
                        z[s][i] = u[i] - y[i];
                    }
                }
            }
            let w = self.tol.weights(&y, &y);
            // Simplified Newton iterations.
            let mut converged = false;
            let mut dyno_old: f64 = 0.0;
            let mut theta = self.theta_last;
            let mut faccon = self.faccon.max(f64::EPSILON).powf(0.8);
            let mut iters = 0;
            let mut diverged = false;
            let nit = if self.cfg.fixed { 40 } else { NIT };
            while iters < nit {
                iters += 1;
                let mut fz = [[0.0; N]; 3];
                for s in 0..3 {
                    let mut ys = y;
                    for i in 0..N {
                        ys[i] += z[s][i];
                    }
                    sys.rhs(t + CS[s] * h, &ys, &mut fz[s]);
                }
                self.stats.rhs_evals += 3;
                let mut rhs = vec![0.0; 3 * N];
                for s in 0..3 {
                    for i in 0..N {
                        let hf = h * (A[s][0] * fz[0][i] + A[s][1] * fz[1][i] + A[s][2] * fz[2][i]);
                        rhs[s * N + i] = hf - z[s][i];
                    }
                }
                if !rhs.iter().all(|v| v.is_finite()) {
                    diverged = true;
                    break;
                }
                if let Some(lu) = &self.lu_full {
                    lu.solve(&mut rhs);
                }
                let mut dyno = 0.0;
                for s in 0..3 {
                    for i in 0..N {
                        z[s][i] += rhs[s * N + i];
                        dyno += (rhs[s * N + i] * w[i]).powi(2);
                    }
                }
                dyno = (dyno / (3 * ncon) as f64).sqrt();
                if iters > 1 {
                    theta = dyno / dyno_old.max(1e-300);
                    if theta >= 0.99 {
                        diverged = true;
                        break;
                    }
                    faccon = theta / (1.0 - theta);
                    // Predict whether the iteration can converge in the iterations left.
                    let left = (nit - iters) as i32;
                    if theta.powi(left) / (1.0 - theta) * dyno > self.fnewt
                        && left > 0
                        && theta > 0.9
                    {
                        diverged = true;
                        break;
                    }
                }
                dyno_old = dyno.max(f64::EPSILON);
                if faccon * dyno <= self.fnewt {
                    converged = true;
                    break;
                }
            }
            if !converged || diverged {
                self.stats.newton_failures += 1;
                self.stats.rejected += 1;
                newton_fails += 1;
                if newton_fails > 20 || (self.cfg.fixed && !self.jac_fresh) && newton_fails > 1 {
                    return Err(StepError::NewtonFailure { t, h });
                }
                if !self.cfg.fixed {
                    h *= 0.5;
                }
                self.faccon = 1.0;
                if !self.jac_fresh {
                    self.jac_valid = false;
                }
                continue;
            }
            self.faccon = faccon;
            self.theta_last = theta;
            // Error estimate.
            let hee = [DD1 / h, DD2 / h, DD3 / h];
            let mut f2 = [0.0; N];
            let mut cont = [0.0; N];
            for i in 0..N {
                f2[i] = hee[0] * z[0][i] + hee[1] * z[1][i] + hee[2] * z[2][i];
                cont[i] = f2[i] + f0[i];
            }
            if let Some(lu) = &self.lu_err {
                lu.solve(&mut cont);
            }
            let mut ynew = y;
            for i in 0..N {
                ynew[i] += z[2][i];
            }
            let wn = self.tol.weights(&y, &ynew);
            let mut err = if self.cfg.fixed {
                0.0
            } else {
                wrms(&cont, &wn, ncon).max(1e-10)
            };
            if !self.cfg.fixed && err >= 1.0 && (self.first || self.rejected_last) {
                let mut yc = y;
                for i in 0..N {
                    yc[i] += cont[i];
                }
                let mut f1 = [0.0; N];
                sys.rhs(t, &yc, &mut f1);
                self.stats.rhs_evals += 1;
                for i in 0..N {
                    cont[i] = f1[i] + f2[i];
                }
                if let Some(lu) = &self.lu_err {
                    lu.solve(&mut cont);
                }
                err = wrms(&cont, &wn, ncon).max(1e-10);
            }
            if !err.is_finite() || !all_finite(&ynew) {
                if self.cfg.fixed {
                    return Err(StepError::NonFinite { t });
                }
                self.stats.rejected += 1;
                h *= 0.25;
                continue;
            }
            let fac = SAFE.min(SAFE * (1.0 + 2.0 * NIT as f64) / (iters as f64 + 2.0 * NIT as f64));
            let mut quot = FACR.max(FACL.min(err.powf(0.25) / fac));
            let mut hnew = if self.cfg.fixed { self.cfg.h } else { h / quot };
            if err < 1.0 {
                // Gustafsson's predictive controller.
                if !self.first && self.hacc > 0.0 && !self.cfg.fixed {
                    let facgus = (self.hacc / h) * (err * err / self.erracc).powf(0.25) / SAFE;
                    let facgus = FACR.max(FACL.min(facgus));
                    quot = quot.max(facgus);
                    hnew = h / quot;
                }
                self.hacc = h;
                self.erracc = err.max(1e-2);
                let tph = if last { t_end } else { t + h };
                let fnew = derivative_at_end(sys, tph, &ynew, &mut self.stats)?;
                self.stats.steps += 1;
                if self.rejected_last {
                    hnew = hnew.min(h);
                }
                self.first = false;
                self.rejected_last = false;
                self.z = z;
                self.pos.advance((t, y), tph, ynew, fnew);
                self.h_used = h;
                // Keep the Jacobian when Newton converged fast, and the LU when h barely changes.
                self.jac_fresh = false;
                if theta > THET {
                    self.jac_valid = false;
                    self.lu_full = None;
                }
                let ratio = hnew / h;
                if self.jac_valid && (1.0..=1.2).contains(&ratio) && !self.cfg.fixed {
                    hnew = h;
                }
                self.next.h = hnew.min(self.cfg.h_max);
                return Ok(());
            }
            self.rejected_last = true;
            self.stats.rejected += 1;
            h = if self.first { h * 0.1 } else { hnew };
        }
    }

    /// The collocation polynomial of the last accepted step (valid on
    /// [t_prev, t]; used beyond it only to start the next step's Newton iteration).
    pub fn dense(&self, t: f64) -> [f64; N] {
        let h = self.h_used;
        if h <= 0.0 {
            return self.pos.y;
        }
        let s = (t - self.pos.t_prev) / h;
        // Lagrange basis on the nodes 0, c1, c2, 1 with p(0) = 0.
        let l1 = s * (s - C2) * (s - 1.0) / (C1 * (C1 - C2) * (C1 - 1.0));
        let l2 = s * (s - C1) * (s - 1.0) / (C2 * (C2 - C1) * (C2 - 1.0));
        let l3 = s * (s - C1) * (s - C2) / ((1.0 - C1) * (1.0 - C2));
        let mut out = self.pos.y_prev;
        for i in 0..N {
            out[i] += l1 * self.z[0][i] + l2 * self.z[1][i] + l3 * self.z[2][i];
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lu_solves() {
        let a = vec![0.0, 2.0, 1.0, 1.0, 1.0, 1.0, 4.0, 1.0, 0.0];
        let lu = Lu::factor(3, a.clone()).unwrap();
        let x = [1.0, -2.0, 3.0];
        let mut b = vec![0.0; 3];
        for i in 0..3 {
            for j in 0..3 {
                b[i] += a[i * 3 + j] * x[j];
            }
        }
        lu.solve(&mut b);
        for i in 0..3 {
            assert!((b[i] - x[i]).abs() < 1e-14);
        }
        assert!(Lu::factor(2, vec![1.0, 2.0, 2.0, 4.0]).is_none());
    }

    #[test]
    fn radau_constants() {
        // Row sums of A are the nodes.
        for (s, row) in A.iter().enumerate() {
            assert!((row.iter().sum::<f64>() - CS[s]).abs() < 1e-15);
        }
        assert!((u1() - 3.637_834_252_744_496).abs() < 1e-12);
    }
}
