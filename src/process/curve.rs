//! One cycle's process curve: force against stroke (one branch) or against
//! crank angle, read off the cycle's crank-angle grid, and the derived
//! process values.

use super::recipe::{Axis, Branch, Quantity};
use crate::rig::cycles::{Cycle, CycleSet};

/// Half-width of the windows around the dead centres for the impact-noise index, degrees.
pub const NOISE_HALF_WIDTH_DEG: f64 = 15.0;

/// The force where the points (x, force), in angle order, first pass `x`
/// (linear between neighbours).
fn first_crossing(p: &[(f64, f64)], x: f64) -> Option<f64> {
    p.windows(2).find_map(|w| {
        let ((x0, f0), (x1, f1)) = (w[0], w[1]);
        let between = (x0 <= x && x <= x1) || (x1 <= x && x <= x0);
        if !between {
            return None;
        }
        if x1 == x0 {
            return Some(f0);
        }
        Some(f0 + (f1 - f0) * (x - x0) / (x1 - x0))
    })
}

/// A cycle on the set's grid.
pub struct CycleCurve<'a> {
    pub angle: &'a [f64],
    pub stroke: &'a [f64],
    pub force: &'a [f64],
    pub ideal: &'a [f64],
    pub standoff_mm: f64,
    pub cycle: &'a Cycle,
}

impl<'a> CycleCurve<'a> {
    pub fn new(cs: &'a CycleSet, c: &'a Cycle) -> Self {
        CycleCurve {
            angle: &cs.grid_deg,
            stroke: &c.stroke_mm,
            force: &c.force_n,
            ideal: &cs.ideal_stroke_mm,
            standoff_mm: cs.standoff_mm,
            cycle: c,
        }
    }

    pub fn has_force(&self) -> bool {
        self.force.iter().any(|f| f.is_finite())
    }

    fn on_branch(&self, j: usize, axis: Axis, branch: Branch) -> bool {
        match axis {
            Axis::Angle => true,
            Axis::Stroke => {
                let a = self.angle[j];
                match branch {
                    Branch::Down => a <= 180.0,
                    Branch::Up => a >= 180.0,
                }
            }
        }
    }

    /// The curve's points (x, force) in angle order, finite ones only.
    pub fn points(&self, axis: Axis, branch: Branch) -> Vec<(f64, f64)> {
        let n = self
            .angle
            .len()
            .min(self.stroke.len())
            .min(self.force.len());
        (0..n)
            .filter(|&j| self.on_branch(j, axis, branch))
            .filter_map(|j| {
                let x = match axis {
                    Axis::Angle => self.angle[j],
                    Axis::Stroke => self.stroke[j],
                };
                (x.is_finite() && self.force[j].is_finite()).then_some((x, self.force[j]))
            })
            .collect()
    }

    /// The force where the curve first passes abscissa `x` (linear between
    /// grid points): on the angle axis at that angle, on the stroke axis the
    /// first crossing of that stroke on the branch.
    pub fn force_at(&self, axis: Axis, branch: Branch, x: f64) -> Option<f64> {
        first_crossing(&self.points(axis, branch), x)
    }

    /// [`CycleCurve::force_at`] at many abscissae, with the curve's points
    /// built once: one walk along the curve when both the points and `xs`
    /// ascend (the crank-angle axis, a clean stroke branch), the first
    /// crossing for each x otherwise. Same answers as `force_at`.
    pub fn forces_at(&self, axis: Axis, branch: Branch, xs: &[f64]) -> Vec<Option<f64>> {
        let p = self.points(axis, branch);
        fn ascending(mut v: impl Iterator<Item = f64>) -> bool {
            let mut prev = f64::NEG_INFINITY;
            v.all(|x| {
                let ok = x > prev;
                prev = x;
                ok
            })
        }
        if !(ascending(p.iter().map(|q| q.0)) && ascending(xs.iter().copied())) {
            return xs.iter().map(|&x| first_crossing(&p, x)).collect();
        }
        // Strictly ascending points: the segment holding x is the first
        // whose right end reaches it, and it moves only forwards.
        let mut j = 0;
        xs.iter()
            .map(|&x| {
                while j + 1 < p.len() && p[j + 1].0 < x {
                    j += 1;
                }
                if j + 1 >= p.len() || x < p[j].0 {
                    return None;
                }
                let ((x0, f0), (x1, f1)) = (p[j], p[j + 1]);
                Some(f0 + (f1 - f0) * (x - x0) / (x1 - x0))
            })
            .collect()
    }

    /// A derived process value (None: the data it needs is missing).
    pub fn value(&self, q: Quantity, at_depth_mm: Option<f64>) -> Option<f64> {
        let c = self.cycle;
        let fin = |x: f64| x.is_finite().then_some(x);
        match q {
            Quantity::PeakForceN => self.has_force().then_some(c.peak_force_n).and_then(fin),
            Quantity::DepthMm => fin(c.depth_mm),
            Quantity::DepthAtPeakMm => {
                let j = (0..self.force.len().min(self.stroke.len()))
                    .filter(|&j| self.force[j].is_finite() && self.stroke[j].is_finite())
                    .max_by(|&a, &b| self.force[a].total_cmp(&self.force[b]))?;
                fin(self.stroke[j] - self.standoff_mm)
            }
            Quantity::ForceAtDepthN => {
                self.force_at(Axis::Stroke, Branch::Down, self.standoff_mm + at_depth_mm?)
            }
            Quantity::BdcStrokeErrMm => fin(c.stroke_err_bdc_mm),
            Quantity::TdcStrokeErrMm => fin(c.stroke_err_tdc_mm),
            Quantity::ImpactNoiseUm => self.impact_noise_um(),
        }
    }

    /// RMS of the second difference of (stroke − ideal stroke) within
    /// ±[`NOISE_HALF_WIDTH_DEG`] of TDC and BDC, µm: the joint's impacts
    /// near the dead centres as high-pass energy (the ideal mechanism's own
    /// curvature removed).
    fn impact_noise_um(&self) -> Option<f64> {
        let n = self
            .angle
            .len()
            .min(self.stroke.len())
            .min(self.ideal.len());
        let dev: Vec<f64> = (0..n).map(|j| self.stroke[j] - self.ideal[j]).collect();
        let near = |a: f64| {
            let d_tdc = a.min(360.0 - a);
            let d_bdc = (a - 180.0).abs();
            d_tdc <= NOISE_HALF_WIDTH_DEG || d_bdc <= NOISE_HALF_WIDTH_DEG
        };
        let mut acc = 0.0;
        let mut k = 0usize;
        for j in 1..n.saturating_sub(1) {
            if !near(self.angle[j]) {
                continue;
            }
            let d2 = dev[j - 1] - 2.0 * dev[j] + dev[j + 1];
            if d2.is_finite() {
                acc += d2 * d2;
                k += 1;
            }
        }
        (k > 0).then(|| (acc / k as f64).sqrt() * 1e3)
    }
}
