//! Time series as the Signals pane draws them: a rig log's channels in
//! seconds from the log's start, or the model's prediction over time.
//! Plain data with a lazily built index of block extremes
//! ([`MinMaxBlocks`]) so charts of 10⁶-sample channels stay fast.

use serde::Serialize;

/// One channel of a log as the Signals pane draws it: time in seconds from
/// the log's start, values in the channel's unit.
#[derive(Debug, Clone, Serialize)]
pub struct Channel {
    pub name: String,
    pub unit: String,
    #[serde(skip)]
    pub t_s: Vec<f64>,
    #[serde(skip)]
    pub values: Vec<f64>,
    /// Block extremes of `values`, built on first use (long channels).
    #[serde(skip)]
    pub blocks: std::sync::OnceLock<MinMaxBlocks>,
}

impl Channel {
    pub fn new(
        name: impl Into<String>,
        unit: impl Into<String>,
        t_s: Vec<f64>,
        values: Vec<f64>,
    ) -> Self {
        Self {
            name: name.into(),
            unit: unit.into(),
            t_s,
            values,
            blocks: std::sync::OnceLock::new(),
        }
    }

    /// The block extremes (built once; None for short channels, where a
    /// plain scan is as fast).
    pub fn blocks(&self) -> Option<&MinMaxBlocks> {
        (self.values.len() >= 16 * BLOCK)
            .then(|| self.blocks.get_or_init(|| MinMaxBlocks::new(&self.values)))
    }
}

/// A time series source for the Signals pane: a rig log's channels, or the
/// model's prediction over time when no log is loaded.
#[derive(Debug, Clone, Serialize)]
pub struct SignalSet {
    pub source: String,
    pub channels: Vec<Channel>,
    /// Cycle starts: (time s, cycle index).
    pub cycles: Vec<(f64, u64)>,
    /// Metadata shown on the Session pane (rig, lot, part, clearance, speed …).
    pub meta: Vec<(String, String)>,
}

impl SignalSet {
    /// First and last sample time over every channel (None: no samples).
    fn extent(&self) -> Option<(f64, f64)> {
        let mut lo = f64::INFINITY;
        let mut hi = f64::NEG_INFINITY;
        for c in &self.channels {
            if let (Some(a), Some(b)) = (c.t_s.first(), c.t_s.last()) {
                lo = lo.min(*a);
                hi = hi.max(*b);
            }
        }
        lo.is_finite().then_some((lo, hi))
    }

    pub fn duration_s(&self) -> f64 {
        self.extent().map_or(0.0, |(lo, hi)| hi - lo)
    }

    /// The time axis to show: the samples' extent, one second when it is
    /// a single instant or empty.
    pub fn t_range(&self) -> [f64; 2] {
        match self.extent() {
            Some((lo, hi)) if hi > lo => [lo, hi],
            Some((lo, _)) => [lo, lo + 1.0],
            None => [0.0, 1.0],
        }
    }
}

/// Per-block minima and maxima of a long series (blocks of [`BLOCK`]
/// samples), so a column's extremes cost O(column / BLOCK + BLOCK) instead
/// of O(column): zoomed-out views of 10⁶-sample channels stay fast.
#[derive(Debug, Clone)]
pub struct MinMaxBlocks {
    min: Vec<(f64, usize)>,
    max: Vec<(f64, usize)>,
}

/// Samples per block of [`MinMaxBlocks`].
pub const BLOCK: usize = 64;

impl MinMaxBlocks {
    pub fn new(ys: &[f64]) -> Self {
        let nb = ys.len().div_ceil(BLOCK);
        let mut min = Vec::with_capacity(nb);
        let mut max = Vec::with_capacity(nb);
        for (b, chunk) in ys.chunks(BLOCK).enumerate() {
            let (mn, imn, mx, imx) = scan(chunk);
            let at = |i: usize| {
                if i == usize::MAX {
                    usize::MAX
                } else {
                    b * BLOCK + i
                }
            };
            min.push((mn, at(imn)));
            max.push((mx, at(imx)));
        }
        Self { min, max }
    }

    /// Extremes of `ys[a..b]`: (min, index, max, index); index usize::MAX
    /// when the range has no finite value.
    pub fn extremes(&self, ys: &[f64], a: usize, b: usize) -> (f64, usize, f64, usize) {
        let first_full = a.div_ceil(BLOCK);
        let last_full = b / BLOCK; // blocks first_full..last_full lie inside [a, b)
        if first_full >= last_full {
            let (mn, imn, mx, imx) = scan(&ys[a..b]);
            return (mn, shift(imn, a), mx, shift(imx, a));
        }
        let (mut mn, imn, mut mx, imx) = scan(&ys[a..first_full * BLOCK]);
        let (mut imn, mut imx) = (shift(imn, a), shift(imx, a));
        for k in first_full..last_full {
            if self.min[k].0 < mn {
                (mn, imn) = self.min[k];
            }
            if self.max[k].0 > mx {
                (mx, imx) = self.max[k];
            }
        }
        let t = last_full * BLOCK;
        let (tmn, timn, tmx, timx) = scan(&ys[t..b]);
        if tmn < mn {
            (mn, imn) = (tmn, shift(timn, t));
        }
        if tmx > mx {
            (mx, imx) = (tmx, shift(timx, t));
        }
        (mn, imn, mx, imx)
    }
}

fn shift(i: usize, by: usize) -> usize {
    if i == usize::MAX { i } else { i + by }
}

/// Minimum and maximum (with their positions) of the finite values; NaN
/// compares false and is skipped.
pub fn scan(seg: &[f64]) -> (f64, usize, f64, usize) {
    let (mut mn, mut mx) = (f64::INFINITY, f64::NEG_INFINITY);
    let (mut imn, mut imx) = (usize::MAX, usize::MAX);
    for (k, &y) in seg.iter().enumerate() {
        if y < mn {
            mn = y;
            imn = k;
        }
        if y > mx {
            mx = y;
            imx = k;
        }
    }
    (mn, imn, mx, imx)
}
