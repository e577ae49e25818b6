//! Bounded series for a whole shift: the raw samples of the last window
//! (a sliding vector: appended at the end, the oldest dropped in blocks so
//! the data stays one slice for the charts) and a min/max history of the
//! whole shift in a fixed number of buckets (two neighbours merge, and the
//! bucket width doubles, when they are all used).

use serde::{Deserialize, Serialize};

/// Appends samples (times in s) to a sliding window of `span_s` seconds.
/// The front is dropped once it holds a quarter more than the span, so the
/// copy is amortised (each sample moves at most four times).
pub fn slide(
    t: &mut Vec<f64>,
    v: &mut Vec<f64>,
    new_t: &[f64],
    new_v: &[f64],
    span_s: f64,
) -> bool {
    t.extend_from_slice(new_t);
    v.extend_from_slice(new_v);
    let (Some(&first), Some(&last)) = (t.first(), t.last()) else {
        return false;
    };
    if last - first <= span_s * 1.25 {
        return false;
    }
    let cut = t.partition_point(|&x| x < last - span_s);
    t.drain(..cut);
    v.drain(..cut);
    true
}

/// Min/max of a signal over the whole shift in at most `cap` buckets.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct MinMaxHistory {
    cap: usize,
    width_s: f64,
    origin_s: f64,
    /// Bucket k covers [origin + k·width, origin + (k+1)·width): (min, max).
    buckets: Vec<(f64, f64)>,
}

impl MinMaxHistory {
    pub fn new(cap: usize, width_s: f64) -> Self {
        MinMaxHistory {
            cap: cap.max(4) & !1,
            width_s: width_s.max(1e-6),
            origin_s: f64::NAN,
            buckets: Vec::new(),
        }
    }

    pub fn len(&self) -> usize {
        self.buckets.len()
    }

    pub fn is_empty(&self) -> bool {
        self.buckets.is_empty()
    }

    pub fn width_s(&self) -> f64 {
        self.width_s
    }

    fn merge_pairs(&mut self) {
        let merged: Vec<(f64, f64)> = self
            .buckets
            .chunks(2)
            .map(|c| {
                c.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |a, b| {
                    (a.0.min(b.0), a.1.max(b.1))
                })
            })
            .collect();
        self.buckets = merged;
        self.width_s *= 2.0;
    }

    /// Adds samples in time order.
    pub fn add(&mut self, t: &[f64], v: &[f64]) {
        for (&t, &y) in t.iter().zip(v) {
            if !y.is_finite() {
                continue;
            }
            if self.origin_s.is_nan() {
                self.origin_s = t;
            }
            let mut k = ((t - self.origin_s) / self.width_s).floor().max(0.0) as usize;
            while k >= self.cap {
                self.merge_pairs();
                k = ((t - self.origin_s) / self.width_s).floor().max(0.0) as usize;
            }
            if k >= self.buckets.len() {
                self.buckets
                    .resize(k + 1, (f64::INFINITY, f64::NEG_INFINITY));
            }
            let b = &mut self.buckets[k];
            b.0 = b.0.min(y);
            b.1 = b.1.max(y);
        }
    }

    /// The history as points to draw: (time, min) and (time, max) at each
    /// filled bucket's middle.
    pub fn points(&self) -> (Vec<f64>, Vec<f64>) {
        let mut t = Vec::with_capacity(2 * self.buckets.len());
        let mut v = Vec::with_capacity(2 * self.buckets.len());
        for (k, &(lo, hi)) in self.buckets.iter().enumerate() {
            if lo.is_finite() {
                let m = self.origin_s + (k as f64 + 0.5) * self.width_s;
                t.extend([m, m]);
                v.extend([lo, hi]);
            }
        }
        (t, v)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_window_slides_and_the_history_stays_bounded() {
        let (mut t, mut v) = (Vec::new(), Vec::new());
        let mut h = MinMaxHistory::new(64, 0.01);
        let mut peak = 0usize;
        for s in 0..2000 {
            let nt: Vec<f64> = (0..100).map(|i| s as f64 + i as f64 * 0.01).collect();
            let nv: Vec<f64> = nt
                .iter()
                .map(|x| (x * 0.37).sin() * (1.0 + x / 1000.0))
                .collect();
            slide(&mut t, &mut v, &nt, &nv, 10.0);
            h.add(&nt, &nv);
            peak = peak.max(t.len());
            assert!(h.len() <= 64);
        }
        // 10 s at 100 samples/s, plus at most a quarter more.
        assert!(t.len() >= 1000 && peak <= 1251 + 100, "{} {peak}", t.len());
        assert!(t.last().unwrap() - t.first().unwrap() <= 12.5 + 1e-9);
        // The history's extremes are the data's.
        let (_, hv) = h.points();
        let max = hv.iter().cloned().fold(f64::NEG_INFINITY, f64::max);
        let want = (0..200_000)
            .map(|i| {
                let x = (i / 100) as f64 + (i % 100) as f64 * 0.01;
                (x * 0.37).sin() * (1.0 + x / 1000.0)
            })
            .fold(f64::NEG_INFINITY, f64::max);
        assert_eq!(max, want);
        assert!(h.width_s() * 64.0 >= 2000.0);
    }
}
