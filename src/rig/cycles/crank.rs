//! The crank angle: unwrapped from the logged angle, its crossings of an
//! angle, and the encoder resolution read from the logged values.

use crate::rig::signals::Signal;
use std::f64::consts::{PI, TAU};

/// Wraps an angle to (−π, π].
pub fn wrap_pi(a: f64) -> f64 {
    let w = (a + PI).rem_euclid(TAU) - PI;
    if w <= -PI { w + TAU } else { w }
}

/// The unwrapped crank angle θ2(t) (offset applied).
#[derive(Debug, Clone)]
pub struct Crank {
    pub t_ns: Vec<i64>,
    /// Unwrapped θ2, rad.
    pub theta: Vec<f64>,
    /// Median sample interval (ns).
    pub dt_ns: i64,
    /// Median crank speed (rad/s).
    pub omega: f64,
}

impl Crank {
    /// Unwraps a logged angle signal (wrapped or not). Returns None with fewer than 3 samples.
    pub fn unwrap(angle: &Signal) -> Option<(Crank, bool)> {
        let n = angle.len();
        if n < 3 {
            return None;
        }
        let t = &angle.t_ns;
        let a = &angle.values;
        let stride = (n / 20_000).max(1);
        let mut rates: Vec<f64> = (1..n)
            .step_by(stride)
            .filter(|&i| t[i] > t[i - 1])
            .map(|i| wrap_pi(a[i] - a[i - 1]) / ((t[i] - t[i - 1]) as f64 * 1e-9))
            .collect();
        let mut dts: Vec<i64> = (1..n).step_by(stride).map(|i| t[i] - t[i - 1]).collect();
        if rates.is_empty() {
            return None;
        }
        let mid = rates.len() / 2;
        let omega = *rates.select_nth_unstable_by(mid, |x, y| x.total_cmp(y)).1;
        let mid = dts.len() / 2;
        let dt_ns = *dts.select_nth_unstable(mid).1;
        let mut theta = Vec::with_capacity(n);
        theta.push(a[0]);
        let mut wrapped = false;
        for i in 1..n {
            let d = a[i] - a[i - 1];
            let expected = omega * (t[i] - t[i - 1]) as f64 * 1e-9;
            let k = ((expected - d) / TAU).round();
            if k != 0.0 {
                wrapped = true;
            }
            theta.push(theta[i - 1] + d + k * TAU);
        }
        Some((
            Crank {
                t_ns: t.clone(),
                theta,
                dt_ns,
                omega,
            },
            wrapped,
        ))
    }

    /// θ2 at time t (linear interpolation; None outside the samples or across
    /// a spindle hole longer than 5 nominal intervals).
    pub fn at(&self, t: i64) -> Option<f64> {
        let mut h = 0;
        self.at_from(t, &mut h)
    }

    /// [`Crank::at`] for increasing times: `hint` remembers where the last
    /// query ended so a sweep costs O(n) instead of O(n log n).
    pub fn at_from(&self, t: i64, hint: &mut usize) -> Option<f64> {
        let n = self.t_ns.len();
        let mut i = (*hint).min(n);
        if i > 0 && self.t_ns[i - 1] >= t {
            i = self.t_ns.partition_point(|&x| x < t);
        } else {
            let stop = (i + 16).min(n);
            while i < stop && self.t_ns[i] < t {
                i += 1;
            }
            if i == stop && i < n && self.t_ns[i] < t {
                i += self.t_ns[i..].partition_point(|&x| x < t);
            }
        }
        *hint = i;
        if i < self.t_ns.len() && self.t_ns[i] == t {
            return Some(self.theta[i]);
        }
        if i == 0 || i >= self.t_ns.len() {
            return None;
        }
        let (t0, t1) = (self.t_ns[i - 1], self.t_ns[i]);
        if t1 - t0 > self.dt_ns.max(1).saturating_mul(5) {
            return None;
        }
        let w = (t - t0) as f64 / (t1 - t0) as f64;
        Some(self.theta[i - 1] + w * (self.theta[i] - self.theta[i - 1]))
    }

    /// Times where θ2 passes `tdc + 2πn` (increasing θ), with n.
    pub fn crossings(&self, tdc: f64) -> Vec<(i64, i64)> {
        let mut out = Vec::new();
        for i in 1..self.theta.len() {
            let (a, b) = (self.theta[i - 1] - tdc, self.theta[i] - tdc);
            let (na, nb) = ((a / TAU).floor(), (b / TAU).floor());
            if nb > na && self.t_ns[i] - self.t_ns[i - 1] <= self.dt_ns.max(1).saturating_mul(5) {
                // One crossing per revolution passed (more only across holes, excluded above).
                for n in (na as i64 + 1)..=(nb as i64) {
                    let target = n as f64 * TAU;
                    let w = (target - a) / (b - a);
                    let tt = self.t_ns[i - 1]
                        + ((self.t_ns[i] - self.t_ns[i - 1]) as f64 * w).round() as i64;
                    out.push((tt, n));
                }
            }
        }
        out
    }
}

/// Encoder counts per revolution, when the angles are multiples of 2π/N for an
/// integer N ≤ 100 000: N = 2π / (approximate GCD of the differences between
/// the distinct angle values), checked on up to 5000 samples. (A rig that
/// samples in step with the crank sees the same few counts every turn, so the
/// smallest difference alone is not the count.)
pub fn detect_encoder_counts(values: &[f64]) -> Option<u64> {
    if values.len() < 200 {
        return None;
    }
    let stride = (values.len() / 5000).max(1);
    let sub: Vec<f64> = values
        .iter()
        .step_by(stride)
        .map(|v| v.rem_euclid(TAU))
        .collect();
    let mut u = sub.clone();
    u.sort_by(|a, b| a.total_cmp(b));
    u.dedup_by(|a, b| (*a - *b).abs() < 1e-12);
    if u.len() < 3 {
        return None;
    }
    let tol = 1e-9;
    let fgcd = |a: f64, b: f64| {
        let (mut a, mut b) = (a.max(b), a.min(b));
        let mut steps = 0;
        while b > tol && steps < 200 {
            let mut r = a % b;
            if b - r < tol {
                r = 0.0;
            }
            a = b;
            b = r;
            steps += 1;
        }
        a
    };
    let g = u.windows(2).map(|w| w[1] - w[0]).fold(TAU, fgcd);
    if g <= tol {
        return None;
    }
    let n = (TAU / g).round();
    if !(8.0..=100_000.0).contains(&n) || (TAU / g - n).abs() > 1e-3 {
        return None;
    }
    let q = TAU / n;
    sub.iter()
        .all(|v| (v / q - (v / q).round()).abs() < 1e-6)
        .then_some(n as u64)
}
