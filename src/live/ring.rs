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
    give_back_room(t, v);
    true
}

/// After the front of a pair of parallel vectors was cut: a burst (a
/// follower catching up after a stall, minutes of log in one batch) grew
/// them far past what they hold now, and a vector keeps its room, so give
/// it back, or one burst sets the memory for the whole shift. Room for half
/// as much again is kept, so a steady slide never reallocates.
pub fn give_back_room<A, B>(a: &mut Vec<A>, b: &mut Vec<B>) {
    if a.capacity() > 2 * a.len() + SHRINK_SLACK {
        let keep = a.len() + a.len() / 2;
        a.shrink_to(keep);
        b.shrink_to(keep);
    }
}

/// Spare samples below which a window's vectors are never shrunk.
const SHRINK_SLACK: usize = 4096;

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

    #[test]
    fn a_burst_does_not_keep_its_room() {
        // 10 s windows at 1 000 samples/s, batches of 0.1 s; then one
        // batch of 200 s (a follower that caught up), then normal again.
        let (mut t, mut v) = (Vec::new(), Vec::new());
        let batch = |from: f64, secs: f64| -> Vec<f64> {
            (0..(secs * 1000.0) as usize)
                .map(|i| from + i as f64 * 1e-3)
                .collect()
        };
        let mut now = 0.0;
        for _ in 0..300 {
            let nt = batch(now, 0.1);
            slide(&mut t, &mut v, &nt, &nt, 10.0);
            now += 0.1;
        }
        let steady = t.capacity();
        assert!(steady <= 2 * 12_500 + SHRINK_SLACK, "{steady}");
        let nt = batch(now, 200.0);
        slide(&mut t, &mut v, &nt, &nt, 10.0);
        now += 200.0;
        // Given back at the same slide: the burst's room lived only while
        // it was cut down to the window.
        assert!(
            t.capacity() <= 2 * 12_500 + SHRINK_SLACK,
            "{}",
            t.capacity()
        );
        let mut caps = Vec::new();
        for _ in 0..300 {
            let nt = batch(now, 0.1);
            slide(&mut t, &mut v, &nt, &nt, 10.0);
            now += 0.1;
            caps.push(t.capacity());
        }
        // The room of a window, and it stays put (no reallocation at every
        // slide).
        let last = *caps.last().unwrap();
        assert!(last <= 2 * 12_500 + SHRINK_SLACK, "{last}");
        assert_eq!(v.capacity(), t.capacity());
        assert!(caps[100..].windows(2).all(|w| w[0] == w[1]), "{caps:?}");
        // The data are the window's: the newest 10–12.5 s.
        assert!((t.last().unwrap() - now).abs() < 2e-3);
        assert!(t.last().unwrap() - t.first().unwrap() <= 12.5 + 1e-9);
        assert_eq!(t, v);
    }
}
