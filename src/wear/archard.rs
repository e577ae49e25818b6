//! Archard wear of the clearance joint: the physics-informed option of the
//! wear trend (`--model archard`).
//!
//! Archard's law: the volume worn is proportional to the normal load times
//! the distance slid. Per machine cycle the joint's bearing and journal slide
//! past each other under the contact force the model simulates, so the
//! clearance grows as
//!
//! ```text
//! dc/dn = k · W(c),   W(c) = ∫_cycle F_N · |v_slip| dt   (J per cycle)
//! ```
//!
//! with F_N the normal contact force and v_slip the tangential slip speed at
//! the contact point (model.md), simulated at the logged speed with the
//! head's calibrated parameters on a ladder of clearances ([`work_ladder`]).
//! W(c) grows with c (the journal rattles harder in a larger clearance), so
//! the wear accelerates as the clearance opens. k (mm of clearance per joule
//! of sliding work) lumps the wear coefficient, the hardness and the contact
//! geometry; it is what the history fits.
//!
//! The law separates: with G(c) = ∫_{c_ref}^{c} dc′/W(c′),
//! G(c(n)) = G(c₀) + k·n is linear in the cycle count n. So the fit is the
//! same weighted straight line as the linear model ([`super::fit::fit_line`])
//! through (nᵢ, G(cᵢ)) with σ_G,i = σ_c,i / W(cᵢ) (first order), its slope
//! is k with Student's-t interval, and the forecast of the limit L is
//! Fieller's crossing of G(L) ([`super::forecast`]). The fitted clearance is
//! c(n) = G⁻¹(a + k·n), its band G⁻¹ of the line's band (G is increasing).
//!
//! W(c) between the ladder's clearances is linear in c, so G has a closed
//! form per segment (a logarithm); below the first and above the last rung
//! W is held at the end value (the report says how far the history reaches).
//! The per-cycle integral is the rectangle rule on the simulation's uniform
//! crank-angle grid: the impacts of the chaotic motion fall at random phases
//! of the grid, so its mean over revolutions is an unbiased estimate of the
//! integral (the grid need not resolve each impact); its standard error is
//! from blocks of revolutions.

use crate::model::Params;
use crate::progress::Progress;
use crate::sim::{Level, SimOptions, simulate};
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

/// The sliding work per cycle at one clearance.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct WorkPoint {
    pub clearance_mm: f64,
    /// Mean over the simulated revolutions of ∫F_N·|v_slip| dt (J per cycle).
    pub work_j: f64,
    /// Its standard error (J, from 6 blocks of revolutions).
    pub work_se_j: f64,
    /// Mean peak contact force per cycle (N), for the reader.
    pub peak_force_n: f64,
}

/// W(c) on a clearance ladder, at one speed.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct WearWork {
    pub motor_rpm: f64,
    pub revs: usize,
    pub ladder: Vec<WorkPoint>,
    pub notes: Vec<String>,
}

/// Per-revolution sliding work from curves on a uniform grid of `n` points
/// per revolution: Σ F_N·|v_slip|·Δt over each revolution.
pub fn work_per_rev(force_n: &[f64], slip_mps: &[f64], n: usize, period_s: f64) -> Vec<f64> {
    let dt = period_s / n as f64;
    force_n
        .chunks(n)
        .zip(slip_mps.chunks(n))
        .filter(|(f, v)| f.len() == n && v.len() == n)
        .map(|(f, v)| {
            f.iter()
                .zip(v)
                .map(|(f, v)| {
                    let w = f * v.abs();
                    if w.is_finite() { w } else { 0.0 }
                })
                .sum::<f64>()
                * dt
        })
        .collect()
}

/// Mean and block standard error (`blocks` contiguous blocks) of a series.
fn mean_block_se(v: &[f64], blocks: usize) -> (f64, f64) {
    let n = v.len();
    let mean = v.iter().sum::<f64>() / n.max(1) as f64;
    let b = blocks.min(n);
    if b < 2 {
        return (mean, f64::NAN);
    }
    let bm: Vec<f64> = (0..b)
        .map(|i| {
            let s = &v[i * n / b..(i + 1) * n / b];
            s.iter().sum::<f64>() / s.len() as f64
        })
        .collect();
    let m = bm.iter().sum::<f64>() / b as f64;
    let var = bm.iter().map(|x| (x - m).powi(2)).sum::<f64>() / (b - 1) as f64;
    (mean, (var / b as f64).sqrt())
}

/// Simulates `revs` revolutions (after 3 of warm-up) at each clearance of
/// `ladder_mm` (in parallel) at `motor_rpm` with `params`, and returns W(c).
pub fn work_ladder(params: &Params, motor_rpm: f64, ladder_mm: &[f64], revs: usize) -> WearWork {
    let n = 720;
    let revs = revs.max(12);
    let runs: Vec<(f64, Result<WorkPoint, String>)> = ladder_mm
        .par_iter()
        .map(|&c| {
            let mut p = params.clone();
            p.clearance = c * 1e-3;
            p.motor_rpm = motor_rpm;
            let so = SimOptions {
                level: Level::Clearance,
                warmup: 3.0,
                revs: revs as f64,
                rtol: 1e-6,
                grid_deg: Some(360.0 / n as f64),
                ..SimOptions::default()
            };
            let r = simulate(&p, &so, &Progress::hidden())
                .map_err(|e| e.to_string())
                .and_then(|r| {
                    let cu = r.curves.ok_or("no curves")?;
                    let w = work_per_rev(&cu.contact_force_n, &cu.slip_mps, n, p.period());
                    if w.len() < 2 {
                        return Err("fewer than 2 revolutions".into());
                    }
                    let (work_j, work_se_j) = mean_block_se(&w, 6);
                    let peaks: Vec<f64> = cu
                        .contact_force_n
                        .chunks(n)
                        .filter(|c| c.len() == n)
                        .map(|c| c.iter().cloned().fold(0.0, f64::max))
                        .collect();
                    Ok(WorkPoint {
                        clearance_mm: c,
                        work_j,
                        work_se_j,
                        peak_force_n: peaks.iter().sum::<f64>() / peaks.len().max(1) as f64,
                    })
                });
            (c, r)
        })
        .collect();
    let mut ladder = Vec::new();
    let mut notes = Vec::new();
    for (c, r) in runs {
        match r {
            Ok(p) if p.work_j > 0.0 => ladder.push(p),
            Ok(_) => notes.push(format!(
                "no sliding work at clearance {c} mm (no contact simulated); left out"
            )),
            Err(e) => notes.push(format!(
                "the model failed at clearance {c} mm ({e}); left out"
            )),
        }
    }
    ladder.sort_by(|a, b| a.clearance_mm.total_cmp(&b.clearance_mm));
    WearWork {
        motor_rpm,
        revs,
        ladder,
        notes,
    }
}

impl WearWork {
    /// A work curve from given points (clearance mm, J per cycle), sorted.
    pub fn from_points(motor_rpm: f64, pts: &[(f64, f64)]) -> Self {
        let mut ladder: Vec<WorkPoint> = pts
            .iter()
            .map(|&(c, w)| WorkPoint {
                clearance_mm: c,
                work_j: w,
                work_se_j: 0.0,
                peak_force_n: f64::NAN,
            })
            .collect();
        ladder.sort_by(|a, b| a.clearance_mm.total_cmp(&b.clearance_mm));
        WearWork {
            motor_rpm,
            revs: 0,
            ladder,
            notes: Vec::new(),
        }
    }

    /// Usable: at least two rungs with positive work.
    pub fn is_usable(&self) -> bool {
        self.ladder.len() >= 2 && self.ladder.iter().all(|p| p.work_j > 0.0)
    }

    /// W(c): linear between rungs, the end values held outside.
    pub fn work_at(&self, c: f64) -> f64 {
        let l = &self.ladder;
        if l.is_empty() {
            return f64::NAN;
        }
        if c <= l[0].clearance_mm {
            return l[0].work_j;
        }
        if c >= l[l.len() - 1].clearance_mm {
            return l[l.len() - 1].work_j;
        }
        let i = l
            .partition_point(|p| p.clearance_mm < c)
            .clamp(1, l.len() - 1);
        let (a, b) = (l[i - 1], l[i]);
        let w = (c - a.clearance_mm) / (b.clearance_mm - a.clearance_mm);
        a.work_j + w * (b.work_j - a.work_j)
    }

    /// G(c) = ∫_{c₀}^{c} dc′/W(c′) (mm per J per cycle), c₀ the first rung;
    /// exact for the piecewise-linear W.
    pub fn g(&self, c: f64) -> f64 {
        let l = &self.ladder;
        if l.len() < 2 {
            return f64::NAN;
        }
        let c0 = l[0].clearance_mm;
        if c <= c0 {
            return (c - c0) / l[0].work_j;
        }
        let mut g = 0.0;
        for s in l.windows(2) {
            let (a, b) = (s[0], s[1]);
            let hi = c.min(b.clearance_mm);
            if hi <= a.clearance_mm {
                break;
            }
            let slope = (b.work_j - a.work_j) / (b.clearance_mm - a.clearance_mm);
            let w_hi = a.work_j + slope * (hi - a.clearance_mm);
            g += if slope.abs() * (hi - a.clearance_mm) < 1e-12 * a.work_j {
                (hi - a.clearance_mm) / a.work_j
            } else {
                (w_hi / a.work_j).ln() / slope
            };
        }
        let last = l[l.len() - 1];
        if c > last.clearance_mm {
            g += (c - last.clearance_mm) / last.work_j;
        }
        g
    }

    /// The inverse of [`WearWork::g`] (G is strictly increasing): bisection.
    pub fn g_inv(&self, g: f64) -> f64 {
        if !g.is_finite() || self.ladder.len() < 2 {
            return f64::NAN;
        }
        let (mut lo, mut hi) = (
            self.ladder[0].clearance_mm,
            self.ladder[self.ladder.len() - 1].clearance_mm,
        );
        // Widen until the bracket holds g (W is constant outside: G linear).
        while self.g(lo) > g {
            lo -= (hi - lo).max(1e-3);
        }
        while self.g(hi) < g {
            hi += (hi - lo).max(1e-3);
        }
        for _ in 0..200 {
            let mid = 0.5 * (lo + hi);
            if self.g(mid) < g {
                lo = mid;
            } else {
                hi = mid;
            }
            if hi - lo < 1e-12 {
                break;
            }
        }
        0.5 * (lo + hi)
    }
}

/// What the Archard fit says beyond the line in G: k and the wear rate now.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ArchardFit {
    /// W(c) the fit used.
    pub work: WearWork,
    /// k (mm of clearance per J of sliding work) and its 95 % interval (the
    /// G-line's slope).
    pub k_mm_per_j: f64,
    pub k_lo95: f64,
    pub k_hi95: f64,
    /// The fitted clearance at the last log and the wear rate there,
    /// dc/dn = k·W(c) (mm per cycle), with the 95 % interval of k.
    pub clearance_now_mm: f64,
    pub rate_now: f64,
    pub rate_now_lo95: f64,
    pub rate_now_hi95: f64,
    /// The history's clearances outside the simulated ladder (W held there).
    pub notes: Vec<String>,
}

impl ArchardFit {
    /// From the line fitted to (x, G(c)) and the last abscissa.
    pub fn of(work: WearWork, fit: &super::LineFit, x_last: f64, c_min: f64, c_max: f64) -> Self {
        let c_now = work.g_inv(fit.at(x_last));
        let w_now = work.work_at(c_now);
        let mut notes = work.notes.clone();
        if let (Some(f), Some(l)) = (work.ladder.first(), work.ladder.last())
            && (c_min < f.clearance_mm || c_max > l.clearance_mm)
        {
            notes.push(format!(
                "the history's clearances ({c_min:.3}–{c_max:.3} mm) reach outside the simulated ladder ({:.3}–{:.3} mm): W held at the end value there",
                f.clearance_mm, l.clearance_mm
            ));
        }
        ArchardFit {
            k_mm_per_j: fit.slope,
            k_lo95: fit.slope_lo95,
            k_hi95: fit.slope_hi95,
            clearance_now_mm: c_now,
            rate_now: fit.slope * w_now,
            rate_now_lo95: fit.slope_lo95 * w_now,
            rate_now_hi95: fit.slope_hi95 * w_now,
            work,
            notes,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::wear::fit_line;

    /// W(c) = 2 + 4c (J, c in mm) on rungs 0.1 … 1.0: exactly linear, so
    /// G(c) = ln(W(c)/W(0.1))/4 (written out, not produced by this code).
    fn linear_work() -> WearWork {
        let pts: Vec<(f64, f64)> = (1..=10)
            .map(|i| {
                let c = i as f64 * 0.1;
                (c, 2.0 + 4.0 * c)
            })
            .collect();
        WearWork::from_points(1200.0, &pts)
    }

    #[test]
    fn g_is_the_closed_form_integral_and_g_inv_its_inverse() {
        let w = linear_work();
        for c in [0.1, 0.15, 0.33, 0.5, 0.999] {
            let want = ((2.0 + 4.0 * c) / 2.4f64).ln() / 4.0;
            assert!((w.g(c) - want).abs() < 1e-12, "c {c}: {} vs {want}", w.g(c));
            assert!((w.g_inv(want) - c).abs() < 1e-9);
        }
        // Outside the ladder W is held: G linear with slope 1/W(end).
        assert!((w.g(1.2) - (w.g(1.0) + 0.2 / 6.0)).abs() < 1e-12);
        assert!((w.g(0.05) + 0.05 / 2.4).abs() < 1e-12);
        assert!((w.g_inv(w.g(1.3)) - 1.3).abs() < 1e-9);
        assert!((w.work_at(0.25) - 3.0).abs() < 1e-12);
    }

    #[test]
    fn the_rectangle_rule_integrates_force_times_slip_per_revolution() {
        // Two revolutions of 4 points, period 0.04 s (Δt 0.01 s):
        // rev 1: F·|v| = 10·1 + 0 + 5·2 + 0 = 20 → 0.2 J; rev 2: 4·|−3| = 12 → 0.12 J.
        let f = [10.0, 0.0, 5.0, 0.0, 0.0, 4.0, 0.0, 0.0];
        let v = [1.0, 9.0, -2.0, 3.0, 1.0, -3.0, f64::NAN, 0.0];
        let w = work_per_rev(&f, &v, 4, 0.04);
        assert_eq!(w.len(), 2);
        assert!(
            (w[0] - 0.2).abs() < 1e-15 && (w[1] - 0.12).abs() < 1e-15,
            "{w:?}"
        );
    }

    /// A history made with the law itself: c(n) = G⁻¹(G(0.2) + k·n) with
    /// k = 2e-8 mm/J, W = 2 + 4c; the clearances written out from the closed
    /// form G⁻¹(g) = (2.4·e^{4g} − 2)/4, plus fixed offsets of ±0.002 mm.
    /// The fitted k's interval holds the truth and the crossing of 0.8 mm
    /// (the closed form n* = (G(0.8) − G(0.2))/k) lies in the forecast's.
    #[test]
    fn a_known_archard_law_is_recovered() {
        let w = linear_work();
        let k = 2e-8;
        let g0 = ((2.0 + 0.8) / 2.4f64).ln() / 4.0;
        let noise = [0.002, -0.002, 0.001, -0.001, 0.0, 0.002, -0.002, 0.001];
        let x: Vec<f64> = (0..8).map(|i| i as f64 * 1e6).collect();
        let c: Vec<f64> = x
            .iter()
            .zip(noise)
            .map(|(n, e)| (2.4 * (4.0 * (g0 + k * n)).exp() - 2.0) / 4.0 + e)
            .collect();
        // The clearance rises faster and faster (Archard, not linear).
        assert!(c[7] - c[6] > c[1] - c[0]);
        let g: Vec<f64> = c.iter().map(|c| w.g(*c)).collect();
        let s: Vec<f64> = c.iter().map(|c| 0.002 / w.work_at(*c)).collect();
        let f = fit_line(&x, &g, &s).unwrap();
        assert!(f.slope_lo95 <= k && k <= f.slope_hi95, "{f:?}");
        assert!((f.slope / k - 1.0).abs() < 0.05, "{}", f.slope);
        let a = ArchardFit::of(w.clone(), &f, x[7], c[0], c[7]);
        assert!((a.rate_now - f.slope * w.work_at(a.clearance_now_mm)).abs() < 1e-18);
        let true_cross = (((2.0 + 3.2) / 2.4f64).ln() / 4.0 - g0) / k;
        let fc = crate::wear::forecast(&f, w.g(0.8), x[7], 0.95, None).unwrap();
        assert!(
            fc.at_lo <= true_cross && fc.at_hi.is_some_and(|h| h >= true_cross),
            "{true_cross} not in [{}, {:?}]",
            fc.at_lo,
            fc.at_hi
        );
    }
}
