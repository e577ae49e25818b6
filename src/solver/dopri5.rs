//! Dormand–Prince 5(4) (Hairer's DOPRI5): FSAL, PI step-size control
//! (Lund stabilisation, β = 0.04), stiffness detection, and the 4th-order
//! continuous extension.

use super::control::{NextStep, StiffnessMonitor, trial_step};
use super::control::{PiControl, Position};
use super::{Stats, StepError, StepperConfig, System, all_finite, wrms};

const C2: f64 = 0.2;
const C3: f64 = 0.3;
const C4: f64 = 0.8;
const C5: f64 = 8.0 / 9.0;
const A21: f64 = 0.2;
const A31: f64 = 3.0 / 40.0;
const A32: f64 = 9.0 / 40.0;
const A41: f64 = 44.0 / 45.0;
const A42: f64 = -56.0 / 15.0;
const A43: f64 = 32.0 / 9.0;
const A51: f64 = 19372.0 / 6561.0;
const A52: f64 = -25360.0 / 2187.0;
const A53: f64 = 64448.0 / 6561.0;
const A54: f64 = -212.0 / 729.0;
const A61: f64 = 9017.0 / 3168.0;
const A62: f64 = -355.0 / 33.0;
const A63: f64 = 46732.0 / 5247.0;
const A64: f64 = 49.0 / 176.0;
const A65: f64 = -5103.0 / 18656.0;
const A71: f64 = 35.0 / 384.0;
const A73: f64 = 500.0 / 1113.0;
const A74: f64 = 125.0 / 192.0;
const A75: f64 = -2187.0 / 6784.0;
const A76: f64 = 11.0 / 84.0;
const E1: f64 = 71.0 / 57600.0;
const E3: f64 = -71.0 / 16695.0;
const E4: f64 = 71.0 / 1920.0;
const E5: f64 = -17253.0 / 339200.0;
const E6: f64 = 22.0 / 525.0;
const E7: f64 = -1.0 / 40.0;
const D1: f64 = -12715105075.0 / 11282082432.0;
const D3: f64 = 87487479700.0 / 32700410799.0;
const D4: f64 = -10690763975.0 / 1880347072.0;
const D5: f64 = 701980252875.0 / 199316789632.0;
const D6: f64 = -1453857185.0 / 822651844.0;
const D7: f64 = 69997945.0 / 29380423.0;

const BETA: f64 = 0.04;
/// DOPRI5's controller: safety 0.9, ratios 0.2–10, Lund's β = 0.04.
const CONTROL: PiControl = PiControl::new(0.9, 0.2, 10.0, 0.2 - BETA * 0.75, BETA);
/// h·|λ| where DOPRI5's stability region ends on the negative real axis.
const STIFF_BOUNDARY: f64 = 3.25;

#[derive(Debug, Clone)]
pub struct Dopri5<const N: usize> {
    pub(crate) cfg: StepperConfig<N>,
    pub pos: Position<N>,
    pub next: NextStep,
    ctl: PiControl,
    rcont: [[f64; N]; 5],
    stiffness: StiffnessMonitor,
    pub stats: Stats,
}

impl<const N: usize> Dopri5<N> {
    pub fn new(cfg: StepperConfig<N>) -> Self {
        Self {
            cfg,
            pos: Position::new(),
            next: NextStep::new(cfg.h, true),
            ctl: CONTROL,
            rcont: [[0.0; N]; 5],
            stiffness: StiffnessMonitor::default(),
            stats: Stats::default(),
        }
    }

    pub fn reset<S: System<N>>(&mut self, sys: &S, t: f64, y: [f64; N], fresh_step: bool) {
        self.pos.restart(sys, t, y, &mut self.stats);
        self.ctl.restart();
        self.next.restart(fresh_step);
        self.rcont = [y, [0.0; N], [0.0; N], [0.0; N], [0.0; N]];
    }

    pub fn step<S: System<N>>(&mut self, sys: &S, t_end: f64, h_max: f64) -> Result<(), StepError> {
        let h_max = h_max.min(self.cfg.h_max);
        let ncon = self.cfg.tol.n_controlled();
        let (t, y, k1) = (self.pos.t, self.pos.y, self.pos.f);
        let (cfg, pos) = (&self.cfg, &self.pos);
        let mut h = self
            .next
            .size(cfg, &cfg.tol, sys, pos, 5, h_max, &mut self.stats);
        loop {
            let (h_try, last) = trial_step(&self.stats, self.cfg.max_steps, t, h, t_end)?;
            h = h_try;
            let mut yt = [0.0; N];
            let (mut k2, mut k3, mut k4, mut k5, mut k6, mut k7) =
                ([0.0; N], [0.0; N], [0.0; N], [0.0; N], [0.0; N], [0.0; N]);
            for i in 0..N {
                yt[i] = y[i] + h * A21 * k1[i];
            }
            sys.rhs(t + C2 * h, &yt, &mut k2);
            for i in 0..N {
                yt[i] = y[i] + h * (A31 * k1[i] + A32 * k2[i]);
            }
            sys.rhs(t + C3 * h, &yt, &mut k3);
            for i in 0..N {
                yt[i] = y[i] + h * (A41 * k1[i] + A42 * k2[i] + A43 * k3[i]);
            }
            sys.rhs(t + C4 * h, &yt, &mut k4);
            for i in 0..N {
                yt[i] = y[i] + h * (A51 * k1[i] + A52 * k2[i] + A53 * k3[i] + A54 * k4[i]);
            }
            sys.rhs(t + C5 * h, &yt, &mut k5);
            let mut ysti = [0.0; N];
            for i in 0..N {
                ysti[i] = y[i]
                    + h * (A61 * k1[i] + A62 * k2[i] + A63 * k3[i] + A64 * k4[i] + A65 * k5[i]);
            }
            let tph = if last { t_end } else { t + h };
            sys.rhs(tph, &ysti, &mut k6);
            let mut y1 = [0.0; N];
            for i in 0..N {
                y1[i] = y[i]
                    + h * (A71 * k1[i] + A73 * k3[i] + A74 * k4[i] + A75 * k5[i] + A76 * k6[i]);
            }
            sys.rhs_step_end(tph, &y1, &mut k7);
            self.stats.rhs_evals += 6;
            let mut e = [0.0; N];
            for i in 0..N {
                e[i] = h
                    * (E1 * k1[i] + E3 * k3[i] + E4 * k4[i] + E5 * k5[i] + E6 * k6[i] + E7 * k7[i]);
            }
            let w = self.cfg.tol.weights(&y, &y1);
            let err = if self.cfg.fixed {
                0.0
            } else {
                wrms(&e, &w, ncon)
            };
            if self.cfg.fixed && !all_finite(&y1) {
                return Err(StepError::NonFinite { t });
            }
            if !err.is_finite() || !all_finite(&y1) {
                // Treat as a failed step: shrink hard and retry; give up if tiny.
                self.stats.rejected += 1;
                if !all_finite(&y1) && h < 1e-300 {
                    return Err(StepError::NonFinite { t });
                }
                h = self.ctl.reject_non_finite(h, t)?;
                continue;
            }
            let (fac11, hnew) = self
                .ctl
                .propose(err, h, self.cfg.fixed.then_some(self.cfg.h));
            if err <= 1.0 {
                self.stats.steps += 1;
                // Stiffness detection (Hairer): h·|λ| from the last two stages.
                self.stiffness.observe(
                    h,
                    (&k7, &k6),
                    (&y1, &ysti),
                    STIFF_BOUNDARY,
                    &mut self.stats,
                );
                // Continuous extension.
                let mut r = [[0.0; N]; 5];
                for i in 0..N {
                    let ydiff = y1[i] - y[i];
                    let bspl = h * k1[i] - ydiff;
                    r[0][i] = y[i];
                    r[1][i] = ydiff;
                    r[2][i] = bspl;
                    r[3][i] = ydiff - h * k7[i] - bspl;
                    r[4][i] = h
                        * (D1 * k1[i]
                            + D3 * k3[i]
                            + D4 * k4[i]
                            + D5 * k5[i]
                            + D6 * k6[i]
                            + D7 * k7[i]);
                }
                self.rcont = r;
                let hnew = self.ctl.accept(err, h, hnew);
                self.pos.advance((t, y), tph, y1, k7);
                self.next.h = hnew.min(self.cfg.h_max);
                return Ok(());
            }
            self.stats.rejected += 1;
            h = self.ctl.reject(h, fac11);
        }
    }

    /// 4th-order continuous extension on [t_prev, t].
    pub fn dense(&self, t: f64) -> [f64; N] {
        let h = self.pos.t - self.pos.t_prev;
        if h <= 0.0 {
            return self.pos.y;
        }
        let s = (t - self.pos.t_prev) / h;
        let s1 = 1.0 - s;
        let r = &self.rcont;
        let mut out = [0.0; N];
        for i in 0..N {
            out[i] = r[0][i] + s * (r[1][i] + s1 * (r[2][i] + s * (r[3][i] + s1 * r[4][i])));
        }
        out
    }
}
