//! Coarse search shared by both views: block-mean image, white top-hat,
//! threshold, run-length labelling. It finds every bright (in `sign`
//! space) blob about the size of a pin tip in a few milliseconds even at
//! 5 MP; the sub-pixel work then happens at full resolution in small
//! regions around each blob ([`super::measure`]).

use super::gray::{Coarse, Plane, Px};
use super::label::{self, Blob};
use super::morph;
use super::side_row::median_f32;

/// Choice of the coarse factor for a tip `pin_px` pixels wide: about five
/// coarse pixels across a tip.
pub fn coarse_factor(pin_px: f64) -> usize {
    ((pin_px / 5.0).round() as usize).clamp(1, 8)
}

/// Robust spread of the samples: (p0.1, p99.9) via a histogram.
pub fn robust_range(data: &[f32]) -> (f32, f32) {
    // Every third sample is plenty for 0.1 % quantiles of a coarse image.
    let sub: Vec<f32> = data.iter().step_by(3).cloned().collect();
    let data = &sub[..];
    let (mut lo, mut hi) = (f32::INFINITY, f32::NEG_INFINITY);
    for &v in data {
        lo = lo.min(v);
        hi = hi.max(v);
    }
    if !(hi > lo) {
        return (lo, hi);
    }
    const NB: usize = 1024;
    let mut hist = vec![0u32; NB];
    let scale = (NB - 1) as f32 / (hi - lo);
    for &v in data {
        hist[((v - lo) * scale) as usize] += 1;
    }
    let n = data.len() as f64;
    let q = |frac: f64| -> f32 {
        let target = (n * frac) as u64;
        let mut acc = 0u64;
        for (i, &h) in hist.iter().enumerate() {
            acc += h as u64;
            if acc > target {
                return lo + i as f32 / scale;
            }
        }
        hi
    };
    (q(0.001), q(0.999))
}

/// Otsu threshold of the values, via imageproc's `otsu_level` on an 8-bit
/// map of [min, max].
pub fn otsu(values: &[f32], w: usize, h: usize) -> f32 {
    let (mut lo, mut hi) = (f32::INFINITY, f32::NEG_INFINITY);
    for &v in values {
        lo = lo.min(v);
        hi = hi.max(v);
    }
    if !(hi > lo) {
        return lo;
    }
    let scale = 255.0 / (hi - lo);
    let px: Vec<u8> = values
        .iter()
        .map(|&v| ((v - lo) * scale).clamp(0.0, 255.0) as u8)
        .collect();
    match image::GrayImage::from_raw(w as u32, h as u32, px) {
        Some(img) => lo + (imageproc::contrast::otsu_level(&img) as f32 + 0.5) / scale,
        None => lo,
    }
}

/// A blob found on the coarse top-hat image.
#[derive(Debug, Clone)]
pub struct CoarseBlob {
    pub blob: Blob,
    /// Highest top-hat value in it.
    pub peak: f32,
}

/// Result of the coarse search.
#[derive(Debug, Clone)]
pub struct CoarseSearch {
    pub coarse: Coarse,
    pub tophat: Vec<f32>,
    /// See [`Found::background`].
    pub background: Vec<f32>,
    /// Typical tip contrast on the top-hat (median blob peak).
    pub tip_contrast: f32,
    pub threshold: f32,
    /// See [`Found::noise_floor`].
    pub noise_floor: f32,
    pub blobs: Vec<CoarseBlob>,
}

/// Runs the coarse search. `pin_px` is the expected tip width in pixels;
/// blobs outside `[min_area, max_area]` (in tip areas) or wider than
/// `max_dim` tips are dropped (housing structure, noise). `expected_tips`,
/// the number of pins the recipe has, bounds how many blobs the typical
/// tip contrast is read from (see [`search_coarse_expecting`]).
pub fn coarse_search<P: Px>(
    plane: &Plane<P>,
    sign: f32,
    pin_px: f64,
    mask: Option<&dyn Fn(usize, usize) -> bool>,
    expected_tips: Option<usize>,
) -> CoarseSearch {
    coarse_search_smoothed(plane, sign, pin_px, mask, expected_tips, Smoothing::Normal)
}

/// [`coarse_search`] with the smoothing box of `smoothing`
/// ([`Smoothing::Faint`] for the second pass when the first found no tips).
pub fn coarse_search_smoothed<P: Px>(
    plane: &Plane<P>,
    sign: f32,
    pin_px: f64,
    mask: Option<&dyn Fn(usize, usize) -> bool>,
    expected_tips: Option<usize>,
    smoothing: Smoothing,
) -> CoarseSearch {
    let k = coarse_factor(pin_px);
    let coarse = Coarse::build(plane, k, sign);
    let f = search_coarse_smoothed(&coarse, pin_px, mask, expected_tips, smoothing);
    CoarseSearch {
        coarse,
        tophat: f.tophat,
        background: f.background,
        tip_contrast: f.tip_contrast,
        threshold: f.threshold,
        noise_floor: f.noise_floor,
        blobs: f.blobs,
    }
}

/// What [`search_coarse`] finds on a coarse image.
#[derive(Debug, Clone)]
pub struct Found {
    pub tophat: Vec<f32>,
    /// Local background (coarse, `sign` space): the housing's and the
    /// fixture's level with tips removed and holes filled.
    pub background: Vec<f32>,
    pub tip_contrast: f32,
    pub threshold: f32,
    /// The top-hat's noise floor: its median + 6 σ (σ from the median
    /// absolute deviation of every 7th value, mostly background). The
    /// threshold is the larger of this and 0.35 of the tip contrast.
    pub noise_floor: f32,
    pub blobs: Vec<CoarseBlob>,
}

/// The search on a prebuilt coarse image (of any factor; `pin_px` is in
/// full-resolution pixels).
pub fn search_coarse(
    coarse: &Coarse,
    pin_px: f64,
    mask: Option<&dyn Fn(usize, usize) -> bool>,
) -> Found {
    search_coarse_expecting(coarse, pin_px, mask, None)
}

/// [`search_coarse`] for a part of `expected_tips` pins: the typical tip
/// contrast is the median peak of the strongest `expected_tips` tip-sized
/// blobs rather than of all of them. The tips are the scene's strongest
/// blobs, but a textured fixture can hold many more tip-sized blobs than
/// the part has pins (a grainy backdrop around a 1 × 17 part: 71 of them);
/// their median is then the texture's contrast, the threshold (0.35 of it)
/// lets the texture in, and its blobs, on the tips' lattice by chance,
/// read as pins of a larger part ("pins outside the recipe's positions").
/// Without a count (the scale search, which tries widths it does not yet
/// know the part's pins at) every tip-sized blob is counted.
pub fn search_coarse_expecting(
    coarse: &Coarse,
    pin_px: f64,
    mask: Option<&dyn Fn(usize, usize) -> bool>,
    expected_tips: Option<usize>,
) -> Found {
    search_coarse_smoothed(coarse, pin_px, mask, expected_tips, Smoothing::Normal)
}

/// How wide the coarse search's smoothing box is.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Smoothing {
    /// About half a tip (radius a quarter of a tip): a tip's and a
    /// quarter-tip debris' peak stay whole.
    Normal,
    /// About four fifths of a tip (radius 0.4 of a tip), nearer the
    /// matched filter: the noise of the box's mean falls by another ~1.6
    /// while a blurred tip's peak falls little. For the second pass only,
    /// when the first finds no tips (small faint tips under heavy noise,
    /// whose peaks stand below the first pass's 6 σ floor); debris small
    /// against a tip is flattened more by it.
    Faint,
    /// [`Smoothing::Normal`]'s box, with the background's closing bounded
    /// to a clearance hole's reach ([`morph::background_square`]). For the
    /// last pass only, when neither other pass finds a tip: a one-row
    /// housing narrower than the closing's window, on a fixture beyond the
    /// tips' level (dark tips on a white housing on a black fixture), is
    /// filled to the fixture's level by the unbounded closing and its tips
    /// vanish from the top-hat. Bounded everywhere, the closing leaves the
    /// valleys of a textured fixture unfilled and the threshold rises over
    /// faint debris; so it is the last resort, not the rule.
    HoleReach,
    /// [`Smoothing::Faint`]'s box with the noise floor lowered to
    /// [`LOW_FLOOR_SIGMAS`]. For the very last pass only, whose blobs
    /// must stand a pitch apart to count
    /// ([`super::top_candidates::last_passes`]).
    FaintLowFloor,
    /// [`Smoothing::Normal`]'s box, its noise floor from the image's noise
    /// alone ([`pixel_noise_floor`]) rather than from the top-hat's spread.
    /// For the very last pass only, whose blobs must stand a pitch apart
    /// to count: an image of almost no noise whose top-hat is mostly
    /// structure (a housing's dark rim band, light rims about the holes,
    /// vignetting) has a spread of that structure, above its tips.
    NoiseOnlyFloor,
}

/// The noise floor's multiple of σ for every search but
/// [`Smoothing::FaintLowFloor`]'s.
pub const NOISE_FLOOR_SIGMAS: f32 = 6.0;

/// The noise floor's least value, in steps of the raw data
/// ([`super::gray::quantum`]). An image with almost no noise (σ 0.1 DN)
/// has a zero spread, so the floor fell to nothing, and under vignetting
/// its background's one-step terraces became thousands of blobs, lattices
/// at every width (Rust seed 925 251, 8-bit, 2305 × 2129: "109 pins lie on
/// the grid but outside the recipe's 2 × 5 positions"). A terrace's
/// top-hat is one step where the background ramps by less than a step
/// across the opening's window, two where it is steeper; a tip inside the
/// envelope stands at several (30 % contrast at gain 0.6 is about 10 DN
/// in 8 bits).
pub const QUANTUM_FLOOR_STEPS: f32 = 2.0;

/// The noise floor's multiple of σ for [`Smoothing::FaintLowFloor`].
pub const LOW_FLOOR_SIGMAS: f32 = 4.0;

/// The half-width (coarse px) of the smoothing box of `smoothing` for
/// tips `pin_c` coarse px wide: the box is `2m + 1` across.
pub fn smoothing_half_width(pin_c: f64, smoothing: Smoothing) -> usize {
    match smoothing {
        Smoothing::Normal | Smoothing::HoleReach | Smoothing::NoiseOnlyFloor => {
            (pin_c / 4.0).floor() as usize
        }
        Smoothing::Faint | Smoothing::FaintLowFloor => (pin_c / 2.5).round() as usize,
    }
}

/// The coarse search's top-hat for tips `pin_px` wide (full px) and its
/// background: the coarse image smoothed by the box of `smoothing`, less
/// its opening-like background ([`morph::background_square`]), clipped at
/// zero. Shared by the search and the scale's periodicity pass
/// ([`super::scale_period`]).
pub fn tophat(coarse: &Coarse, pin_px: f64, smoothing: Smoothing) -> (Vec<f32>, Vec<f32>) {
    let k = coarse.k;
    let pin_c = pin_px / k as f64;
    let r = (1.1 * pin_c).ceil() as usize + 1;
    // Smoothing over about half a tip (a matched filter's better half):
    // noise falls by the box's width, a tip's (or a quarter-tip debris')
    // peak does not.
    let m = smoothing_half_width(pin_c, smoothing);
    let smooth = if m >= 1 {
        std::borrow::Cow::Owned(morph::box_mean(&coarse.data, coarse.w, coarse.h, m))
    } else {
        std::borrow::Cow::Borrowed(&coarse.data)
    };
    // Bounded, the closing fills clearance holes (diameter up to 1.8 tips,
    // blurred by up to 3 px) and reaches no further.
    let reach = match smoothing {
        Smoothing::HoleReach => ((0.9 * pin_px + 3.0) / k as f64).ceil() as usize,
        _ => r,
    };
    let background = morph::background_square(&smooth, coarse.w, coarse.h, r, reach);
    let tophat: Vec<f32> = smooth
        .iter()
        .zip(&background)
        .map(|(a, b)| (a - b).max(0.0))
        .collect();
    (tophat, background)
}

/// [`search_coarse_expecting`] with the smoothing box of `smoothing`.
pub fn search_coarse_smoothed(
    coarse: &Coarse,
    pin_px: f64,
    mask: Option<&dyn Fn(usize, usize) -> bool>,
    expected_tips: Option<usize>,
    smoothing: Smoothing,
) -> Found {
    let pin_c = pin_px / coarse.k as f64;
    let (tophat, background) = tophat(coarse, pin_px, smoothing);
    let (w, h) = (coarse.w, coarse.h);
    let tip_area_c = pin_c * pin_c;
    let inside = |x: usize, y: usize| mask.is_none_or(|m| m(x, y));
    let t_otsu = otsu(&tophat, w, h);
    let max_dim = 4.0 * pin_c + 2.0;
    let too_big = |b: &Blob| {
        b.area as f64 / tip_area_c > 10.0
            || b.width() as f64 > max_dim
            || b.height() as f64 > max_dim
    };
    // Typical tip contrast: median peak of tip-sized blobs at Otsu's level
    // (a blob too large for a tip split at higher levels, see
    // `split_blobs`: tips joined to a bright band are tips still).
    let lab = label::label(w, h, |x, y| tophat[y * w + x] > t_otsu && inside(x, y));
    let mut peaks: Vec<f64> = split_blobs(&lab, &tophat, w, t_otsu, &too_big)
        .iter()
        .filter(|b| {
            let a = b.blob.area as f64 / tip_area_c;
            (0.3..3.0).contains(&a)
        })
        .map(|b| b.peak as f64)
        .collect();
    if let Some(n) = expected_tips.filter(|&n| n >= 1 && peaks.len() > n) {
        peaks.sort_by(|a, b| b.total_cmp(a));
        peaks.truncate(n);
    }
    let tip_contrast = super::grid::median(&mut peaks)
        .map(|v| v as f32)
        .unwrap_or_else(|| tophat.iter().cloned().fold(0f32, f32::max));
    let sigmas = match smoothing {
        Smoothing::FaintLowFloor => LOW_FLOOR_SIGMAS,
        _ => NOISE_FLOOR_SIGMAS,
    };
    let noise_floor = match smoothing {
        Smoothing::NoiseOnlyFloor => {
            let m = smoothing_half_width(pin_c, smoothing);
            pixel_noise_floor(coarse, &tophat, m, sigmas)
        }
        _ => tophat_noise_floor(coarse, &tophat, sigmas),
    };
    let threshold = (0.35 * tip_contrast).max(noise_floor);
    let lab = label::label(w, h, |x, y| tophat[y * w + x] > threshold && inside(x, y));
    let blobs = split_blobs(&lab, &tophat, w, threshold, &too_big)
        .into_iter()
        .filter(|b| {
            let a = b.blob.area as f64 / tip_area_c;
            (0.08..=10.0).contains(&a) && !too_big(&b.blob)
        })
        .collect();
    Found {
        tophat,
        background,
        tip_contrast,
        threshold,
        noise_floor,
        blobs,
    }
}

/// The noise floor of `tophat` (a top-hat of `coarse`): the median of its
/// [`noise_sample`] (mostly background) plus `sigmas` robust σ (1.4826 ×
/// the median absolute deviation), never below the quantisation's terraces
/// ([`QUANTUM_FLOOR_STEPS`]).
pub fn tophat_noise_floor(coarse: &Coarse, tophat: &[f32], sigmas: f32) -> f32 {
    let mut sample = noise_sample(&coarse.data, tophat);
    let mid = sample.len() / 2;
    let med = if sample.is_empty() {
        0.0
    } else {
        *sample.select_nth_unstable_by(mid, |a, b| a.total_cmp(b)).1
    };
    let mut dev: Vec<f32> = sample.iter().map(|v| (v - med).abs()).collect();
    let mad = if dev.is_empty() {
        0.0
    } else {
        let m = dev.len() / 2;
        *dev.select_nth_unstable_by(m, |a, b| a.total_cmp(b)).1
    };
    (med + sigmas * 1.4826 * mad).max(QUANTUM_FLOOR_STEPS * coarse.quantum)
}

/// A noise floor from the coarse image's noise alone: the top-hat's
/// median plus `sigmas` σ of the smoothing box's mean (a box `2m + 1`
/// coarse px across), σ of a coarse pixel from the median absolute
/// difference of horizontal neighbours (an edge or a ramp moves few of
/// them); never below the quantisation's terraces (an empty image has
/// only those).
pub fn pixel_noise_floor(coarse: &Coarse, tophat: &[f32], m: usize, sigmas: f32) -> f32 {
    let (w, h) = (coarse.w, coarse.h);
    let mut d: Vec<f32> = (0..h)
        .flat_map(|y| (1..w).map(move |x| (x, y)))
        .step_by(3)
        .map(|(x, y)| (coarse.data[y * w + x] - coarse.data[y * w + x - 1]).abs())
        .collect();
    let mut t: Vec<f32> = tophat.iter().step_by(7).cloned().collect();
    let (mad, med) = (median_f32(&mut d), median_f32(&mut t));
    let sigma = 1.4826 * mad / std::f32::consts::SQRT_2 / (2 * m + 1) as f32;
    (med + sigmas * sigma).max(QUANTUM_FLOOR_STEPS * coarse.quantum)
}

/// Every 7th top-hat value, the sample the noise floor is read from;
/// when blocks clipped flat at the image's bright end (exactly at the
/// coarse image's brightest raw value) make up more than [`FLAT_SHARE`]
/// of it, those are left out. A background driven into saturation (gain
/// 1.2 and more over a bright fixture) has no noise at all, and as most of
/// the frame it pulled the floor to the top-hat of a flat image, nothing:
/// every noise blob of the rest came through, and they formed lattices at
/// every width (Rust seed 860 612, 60 % of it clipped white, "3320 pins
/// outside the recipe's positions"). Clipped tips, a few blocks, leave the
/// sample as it was. The dark end is left alone: a noise-free image's flat
/// background sits there unclipped, and its floor is rightly nothing.
///
/// Raw samples are never negative, so the coarse image (raw × sign) holds
/// its bright end at its maximum when any value is positive (sign +1) and
/// at its minimum otherwise (sign −1).
fn noise_sample(coarse: &[f32], tophat: &[f32]) -> Vec<f32> {
    let (lo, hi) = coarse
        .iter()
        .fold((f32::INFINITY, f32::NEG_INFINITY), |(l, h), &v| {
            (l.min(v), h.max(v))
        });
    let bright = if hi > 0.0 { hi } else { lo };
    let flat = |v: f32| v == bright;
    let n = tophat.len().div_ceil(7);
    let n_flat = coarse.iter().step_by(7).filter(|&&v| flat(v)).count();
    if (n_flat as f64) <= FLAT_SHARE * n as f64 {
        return tophat.iter().step_by(7).cloned().collect();
    }
    coarse
        .iter()
        .zip(tophat)
        .step_by(7)
        .filter(|&(&c, _)| !flat(c))
        .map(|(_, &t)| t)
        .collect()
}

/// See [`noise_sample`].
const FLAT_SHARE: f64 = 0.2;

/// A blob a search found on the top-hat `tophat` (a coarse image `w` ×
/// `h`) above `threshold`, as it stands at half its peak when the
/// threshold cut it higher than that.
///
/// The threshold is the larger of 0.35 of the typical tip's peak and the
/// top-hat's noise floor (6 σ). Fixture texture blotchy at the tips' own
/// scale (the Python renderer's at 40–45 px tips under contrast 0.3) lifts
/// that floor to the tips' peak: the tips then come through as their
/// cores, a tenth to a third of their area, and no tip width fits them.
/// Grown down to half its peak inside a window `reach` coarse px around
/// it, a core becomes the tip's footprint again (a blurred tip's half
/// maximum is about its edge). A blob the threshold already cut below its
/// half peak is returned as it is.
pub fn at_half_peak(
    tophat: &[f32],
    threshold: f32,
    b: &CoarseBlob,
    (w, h): (usize, usize),
    reach: usize,
) -> Blob {
    let level = 0.5 * b.peak;
    if threshold <= level {
        return b.blob.clone();
    }
    let x0 = (b.blob.x_min as usize).saturating_sub(reach);
    let y0 = (b.blob.y_min as usize).saturating_sub(reach);
    let x1 = (b.blob.x_max as usize + reach + 1).min(w);
    let y1 = (b.blob.y_max as usize + reach + 1).min(h);
    let lab = label::label(x1 - x0, y1 - y0, |x, y| {
        tophat[(y0 + y) * w + x0 + x] > level
    });
    // The component holding the blob's centroid (a core lies inside its
    // own half-peak component).
    let (cx, cy) = (b.blob.cx - x0 as f64, b.blob.cy - y0 as f64);
    let Some(g) = lab.blobs.iter().min_by(|a, c| {
        let d = |q: &Blob| (q.cx - cx).powi(2) + (q.cy - cy).powi(2);
        d(a).total_cmp(&d(c))
    }) else {
        return b.blob.clone();
    };
    Blob {
        area: g.area,
        x_min: g.x_min + x0 as u32,
        y_min: g.y_min + y0 as u32,
        x_max: g.x_max + x0 as u32,
        y_max: g.y_max + y0 as u32,
        cx: g.cx + x0 as f64,
        cy: g.cy + y0 as f64,
        runs: Vec::new(),
    }
}

/// [`at_half_peak`] for every blob of a search, peaks kept.
pub fn grown_to_half_peak(
    tophat: &[f32],
    threshold: f32,
    blobs: &[CoarseBlob],
    size: (usize, usize),
    reach: usize,
) -> Vec<CoarseBlob> {
    blobs
        .iter()
        .map(|b| CoarseBlob {
            blob: at_half_peak(tophat, threshold, b, size, reach),
            peak: b.peak,
        })
        .collect()
}

/// The blobs of `lab` (labelled above `level` on `values`, `w` wide) with
/// their peaks; a blob `too_big` for a tip is labelled again inside its
/// own pixels at a level a third of the way up to its peak, recursively
/// (four levels at most). A tip joined to a bright band at the first level
/// (a one-row housing narrower than the top-hat's window stays in the
/// top-hat as a band about a third of the tips' contrast) comes apart from
/// it, as in a component tree; blobs not too big are returned as found.
/// The returned blobs' `runs` are empty (they index sub-labellings).
fn split_blobs(
    lab: &label::Labelling,
    values: &[f32],
    w: usize,
    level: f32,
    too_big: &dyn Fn(&Blob) -> bool,
) -> Vec<CoarseBlob> {
    let mut out = Vec::with_capacity(lab.blobs.len());
    split_into(lab, values, w, level, (0, 0), too_big, 0, &mut out);
    out
}

#[allow(clippy::too_many_arguments)]
fn split_into(
    lab: &label::Labelling,
    values: &[f32],
    w: usize,
    level: f32,
    off: (u32, u32),
    too_big: &dyn Fn(&Blob) -> bool,
    depth: u32,
    out: &mut Vec<CoarseBlob>,
) {
    for b in &lab.blobs {
        let peak = blob_peak(lab, b, values, w);
        if depth < 4 && too_big(b) && peak > level {
            let (bw, bh) = (b.width() as usize, b.height() as usize);
            let mut sub = vec![f32::NEG_INFINITY; bw * bh];
            for &ri in &b.runs {
                let r = lab.runs[ri as usize];
                let (sy, row) = ((r.y - b.y_min) as usize, r.y as usize * w);
                for x in r.x0..r.x1 {
                    sub[sy * bw + (x - b.x_min) as usize] = values[row + x as usize];
                }
            }
            let next = level + (peak - level) / 3.0;
            let sl = label::label(bw, bh, |x, y| sub[y * bw + x] > next);
            let o = (off.0 + b.x_min, off.1 + b.y_min);
            split_into(&sl, &sub, bw, next, o, too_big, depth + 1, out);
        } else {
            let mut blob = b.clone();
            blob.runs = Vec::new();
            blob.x_min += off.0;
            blob.x_max += off.0;
            blob.y_min += off.1;
            blob.y_max += off.1;
            blob.cx += off.0 as f64;
            blob.cy += off.1 as f64;
            out.push(CoarseBlob { blob, peak });
        }
    }
}

pub(crate) fn blob_peak(lab: &label::Labelling, b: &Blob, values: &[f32], w: usize) -> f32 {
    let mut p = f32::NEG_INFINITY;
    for &ri in &b.runs {
        let r = lab.runs[ri as usize];
        for x in r.x0..r.x1 {
            p = p.max(values[r.y as usize * w + x as usize]);
        }
    }
    p
}

/// Minimum contrast (fraction of full scale) below which an image is blank.
pub(crate) const MIN_CONTRAST: f32 = 0.012;

pub(crate) fn check_contrast(
    coarse: &super::gray::Coarse,
    full_scale: f32,
) -> Result<(), super::error::VisionError> {
    let (lo, hi) = robust_range(&coarse.data);
    let (a, b) = (lo.abs().min(hi.abs()), lo.abs().max(hi.abs()));
    if !(hi - lo >= MIN_CONTRAST * full_scale) {
        return Err(super::error::VisionError::NoContrast {
            lo: a.round(),
            hi: b.round(),
        });
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The floor from the image's noise: noise of σ 10 under bands of
    /// 1000 (a housing's rim, light rims about holes: one column in five
    /// of the image, their edges one difference in twenty) reads σ within
    /// 10 % (the edges move the median absolute difference by about 6 %),
    /// divided by the smoothing box's width (5 for m = 2) and added to the
    /// top-hat's median: 6 σ / 5 = 12 above it.
    #[test]
    fn the_pixel_noise_floor_reads_the_noise_under_strong_structure() {
        let (w, h) = (200usize, 200usize);
        let mut rng = crate::vision::synth::Rng::new(7);
        let band = |x: usize| if x % 40 < 8 { 1000.0 } else { 0.0 };
        let data: Vec<f32> = (0..w * h)
            .map(|i| band(i % w) + (10.0 * rng.normal()) as f32)
            .collect();
        let coarse = Coarse {
            w,
            h,
            k: 1,
            data,
            quantum: 1.0,
        };
        let tophat: Vec<f32> = (0..w * h).map(|i| band(i % w) + 3.0).collect();
        let floor = pixel_noise_floor(&coarse, &tophat, 2, 6.0);
        let above = floor - 3.0;
        assert!((above / 12.0 - 1.0).abs() < 0.1, "floor {floor}");
    }

    /// Blocks clipped flat at the image's bright end leave the noise
    /// sample when they are more than a fifth of it, and only then; a flat
    /// dark end (a noise-free background) stays.
    #[test]
    fn clipped_blocks_leave_the_noise_sample_only_when_they_are_many() {
        let n = 7000;
        let tophat: Vec<f32> = (0..n).map(|i| (i % 13) as f32).collect();
        let every_7th = |keep: &dyn Fn(usize) -> bool| -> Vec<f32> {
            (0..n)
                .step_by(7)
                .filter(|&i| keep(i))
                .map(|i| tophat[i])
                .collect()
        };
        let image = |clip: &dyn Fn(usize) -> Option<f32>| -> Vec<f32> {
            (0..n)
                .map(|i| clip(i).unwrap_or(1.0 + (i % 17) as f32))
                .collect()
        };
        // Bright polarity (sign +1): 60 % clipped at 100, the brightest.
        let coarse = image(&|i| (i < 4200).then_some(100.0));
        assert_eq!(noise_sample(&coarse, &tophat), every_7th(&|i| i >= 4200));
        // 10 % clipped (tips driven into saturation): as it was.
        let coarse = image(&|i| (i < 700).then_some(100.0));
        assert_eq!(noise_sample(&coarse, &tophat), every_7th(&|_| true));
        // Dark polarity (sign −1, every value ≤ 0): the bright end is the
        // minimum.
        let coarse: Vec<f32> = image(&|i| (i >= 2000).then_some(100.0))
            .iter()
            .map(|v| -v)
            .collect();
        assert_eq!(noise_sample(&coarse, &tophat), every_7th(&|i| i < 2000));
        // A flat dark end (60 % at 0, below everything else) stays.
        let coarse = image(&|i| (i < 4200).then_some(0.0));
        assert_eq!(noise_sample(&coarse, &tophat), every_7th(&|_| true));
    }

    /// A noise-free frame's top-hat has no spread: its floor is then two
    /// steps of the raw data (8-bit, and 12 bits in the high bits of 16),
    /// and the four tips 12 steps over faint shading that rounds to
    /// islands one step high are the only blobs at the tips' width and
    /// at larger ones (as the scale search tries them). Seed 925 251 of
    /// `tests/vision/faint_and_clipped.rs` is the case that failed.
    #[test]
    fn a_noise_free_frame_has_a_floor_of_two_steps_of_its_data() {
        let (w, h) = (480usize, 360usize);
        let mut raw: Vec<u16> = (0..w * h)
            .map(|i| {
                let (x, y) = ((i % w) as f64, (i / w) as f64);
                (40.2 + 0.6 * (x / 5.0).sin() * (y / 5.0).sin()).round() as u16
            })
            .collect();
        for t in 0..4 {
            let (x0, y0) = (150 + 50 * t, 170);
            for y in y0..y0 + 8 {
                for x in x0..x0 + 8 {
                    raw[y * w + x] += 12;
                }
            }
        }
        for step in [1u16, 16] {
            let data: Vec<u16> = raw.iter().map(|v| v * step).collect();
            let plane = Plane { w, h, data: &data };
            let coarse = Coarse::build(&plane, 1, 1.0);
            assert_eq!(coarse.quantum, step as f32);
            for pin_px in [8.0, 16.0, 24.0] {
                let found = search_coarse(&coarse, pin_px, None);
                assert_eq!(found.noise_floor, 2.0 * step as f32, "{pin_px} px");
                assert_eq!(
                    found.blobs.len(),
                    4,
                    "{pin_px} px: threshold {}",
                    found.threshold
                );
            }
        }
    }

    /// Four tips (peak 100) beside 120 fainter tip-sized texture blobs
    /// (peak 20, enough of them for Otsu's level to fall below them):
    /// counted over every blob, the typical contrast is the texture's and
    /// the texture passes the threshold; counted over the four strongest
    /// (the part has four pins), it is the tips' and only the tips remain.
    #[test]
    fn texture_that_outnumbers_the_tips_does_not_set_their_contrast() {
        let (w, h) = (320usize, 240usize);
        let mut data = vec![0f32; w * h];
        let mut square = |x0: usize, y0: usize, v: f32| {
            for y in y0..y0 + 6 {
                for x in x0..x0 + 6 {
                    data[y * w + x] = v;
                }
            }
        };
        for i in 0..4 {
            square(40 + 70 * i, 20, 100.0);
        }
        for i in 0..120 {
            square(8 + 16 * (i % 20), 60 + 28 * (i / 20), 20.0);
        }
        let coarse = Coarse {
            w,
            h,
            k: 1,
            data,
            quantum: 0.0,
        };
        let all = search_coarse(&coarse, 6.0, None);
        assert!(all.tip_contrast < 30.0, "{}", all.tip_contrast);
        assert_eq!(all.blobs.len(), 124);
        let four = search_coarse_expecting(&coarse, 6.0, None, Some(4));
        assert!(four.tip_contrast > 90.0, "{}", four.tip_contrast);
        assert_eq!(four.blobs.len(), 4);
        assert!(four.blobs.iter().all(|b| b.peak > 90.0));
    }

    /// A cone of peak 100 and radius 10 on a flat top-hat: cut at 80 it is
    /// a core of radius 2; grown to half its peak it is the disc of radius
    /// 5, centred where the cone is. A blob the
    /// threshold cut below its half peak comes back as it was.
    #[test]
    fn a_core_cut_near_its_peak_grows_to_its_half_peak_footprint() {
        let (w, h) = (40usize, 40usize);
        let tophat: Vec<f32> = (0..w * h)
            .map(|i| {
                let (x, y) = ((i % w) as f32 - 20.0, (i / w) as f32 - 20.0);
                (100.0 - 10.0 * x.hypot(y)).max(0.0)
            })
            .collect();
        let core = |t: f32| {
            let lab = label::label(w, h, |x, y| tophat[y * w + x] > t);
            CoarseBlob {
                blob: lab.blobs[0].clone(),
                peak: 100.0,
            }
        };
        let cut = core(80.0);
        assert!(cut.blob.area < 20, "{}", cut.blob.area);
        let grown = at_half_peak(&tophat, 80.0, &cut, (w, h), 8);
        // Pixels strictly inside radius 5 (value above 50): 69 of them.
        let disc = (-5i32..=5)
            .flat_map(|y| (-5i32..=5).map(move |x| x * x + y * y))
            .filter(|&d2| d2 < 25)
            .count() as u64;
        assert_eq!(grown.area, disc);
        assert!((grown.cx - 20.0).abs() < 0.01 && (grown.cy - 20.0).abs() < 0.01);
        let low = core(30.0);
        assert_eq!(
            at_half_peak(&tophat, 30.0, &low, (w, h), 8).area,
            low.blob.area
        );
    }
}
