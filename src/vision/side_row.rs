//! One-dimensional measurements of the side view: half-level crossings
//! and a bar's two edges in a profile, the pitch from the spacings between
//! pins, and the robust offset/scale fit of the pin row. Kept apart from
//! `side.rs` (the pipeline) so each can be read and tested on its own.

use super::grid;

/// Half-level crossing in a profile: first index pair (from the start)
/// where the profile passes `level` going up; returns the fractional index.
pub(super) fn first_rise(prof: &[f32], level: f32) -> Option<f64> {
    for i in 1..prof.len() {
        if prof[i - 1] < level && prof[i] >= level {
            let f = (level - prof[i - 1]) / (prof[i] - prof[i - 1]);
            return Some((i - 1) as f64 + f as f64);
        }
    }
    None
}

/// The rise through `level` where the profile steps up for good: of the
/// upward crossings, the one nearest the split that best fits a step (the
/// start of the suffix whose sum above `level` is largest). Under heavy
/// noise the first crossing from the start is a spike in the background
/// before the step (810 669: noise 12 DN on a 45 DN silhouette, tips of
/// pins 6 px wide found 4.5 px above the truth and called high); a spike
/// followed by background adds less to the suffix than it loses.
pub(super) fn step_rise(prof: &[f32], level: f32) -> Option<f64> {
    let n = prof.len();
    let (mut best, mut split, mut acc) = (f64::NEG_INFINITY, 0usize, 0f64);
    for i in (1..n).rev() {
        acc += (prof[i] - level) as f64;
        if acc >= best {
            best = acc;
            split = i;
        }
    }
    let mut pick: Option<(usize, f64)> = None;
    for i in 1..n {
        if prof[i - 1] < level && prof[i] >= level {
            let f = (level - prof[i - 1]) / (prof[i] - prof[i - 1]);
            let x = (i - 1) as f64 + f as f64;
            if pick.is_none_or(|(j, _)| i.abs_diff(split) < j.abs_diff(split)) {
                pick = Some((i, x));
            }
        }
    }
    pick.map(|p| p.1)
}

pub(super) fn median_f32(v: &mut [f32]) -> f32 {
    if v.is_empty() {
        return 0.0;
    }
    let m = v.len() / 2;
    *v.select_nth_unstable_by(m, |a, b| a.total_cmp(b)).1
}

/// The two half-level edge crossings of a bar in a row profile (sign space:
/// bar high): each edge is placed halfway between the bar's interior level
/// and the background level on its own side, so uneven backlight does not
/// shift the centre. Returns fractional indices (left, right).
///
/// Where `narrow`, also of a bar whose steepest rise and fall lie only
/// 2–3 samples apart, its level then read from the peak. Only where the
/// row's lattice puts a pin (`side_bar::look_again`): anywhere, a noise
/// clump under a vignetted backlight passes so and made a "pin-like bar"
/// no position claims (Rust 1 150 141).
pub(super) fn bar_edges(prof: &[f32], narrow: bool) -> Option<(f64, f64)> {
    let n = prof.len();
    if n < 12 {
        return None;
    }
    // The bar is the profile's peak, its edges the steepest rise left of
    // it and the steepest fall right of it (blur spreads an edge over a
    // few px, a backlight's patches over tens). One level for both sides,
    // halfway from the lowest background anywhere to the peak, put a side
    // whose backlight is dimmer (a darker patch of a mottled backlight, py
    // 550 219: 30 DN on a 60 DN silhouette) above the cut: the bar reached
    // the profile's end and the pin was lost.
    let mut im = 0usize;
    for (i, &v) in prof.iter().enumerate() {
        if v > prof[im] {
            im = i;
        }
    }
    let slope = |i: usize| prof[i + 1] - prof[i - 1];
    // The steepest points snapped inwards to the first sample past their
    // step's midpoint (as the first sample above a half level was).
    let sl = (1..im.min(n - 1)).max_by(|&a, &b| slope(a).total_cmp(&slope(b)))?;
    let sr = (im.max(1)..n - 1).min_by(|&a, &b| slope(a).total_cmp(&slope(b)))?;
    let past = |i: usize| prof[i] >= 0.5 * (prof[i - 1] + prof[i + 1]);
    let l0 = if past(sl) { sl } else { sl + 1 };
    let r0 = if past(sr) { sr } else { sr - 1 };
    if r0 < l0 + if narrow { 2 } else { 4 } || l0 < 5 || r0 + 5 >= n {
        return None;
    }
    // The bar's level: its samples two or more inside both steepest
    // points, or where blur leaves none (the steepest points 2–3 px
    // apart), those from the peak to the nearer of them. Under blur
    // 2.45 px on a 7 px pin, noise put the steepest points 3 px apart
    // about the peak of a plain bar (contrast 1400 on 12 bits), and the
    // pins were read missing (Rust 1 220 454).
    let inner_at = if r0 >= l0 + 4 {
        l0 + 2..=r0 - 2
    } else {
        (l0 + 2).min(im)..=(r0 - 2).max(im)
    };
    let mut inner: Vec<f32> = prof[inner_at].to_vec();
    let level_in = median_f32(&mut inner);
    let mut left: Vec<f32> = prof[l0.saturating_sub(7)..l0 - 2].to_vec();
    let mut right: Vec<f32> = prof[r0 + 3..(r0 + 8).min(n)].to_vec();
    let (bl, br) = (median_f32(&mut left), median_f32(&mut right));
    let half_l = 0.5 * (bl + level_in);
    let half_r = 0.5 * (br + level_in);
    // The steepest point of a linear ramp (a pillbox blur spreads an edge
    // evenly over several px) is wherever the noise puts it, often low on
    // the flank, and two samples inside it may still lie under the half
    // level; the crossing is searched from the first sample at or over
    // the half level on the interior's side (py 580 327, 590 085: end pins
    // read missing for a profile whose edges were plain).
    let start_l = (l0 + 2..=im.max(l0 + 2))
        .find(|&i| prof[i] >= half_l)
        .unwrap_or(l0 + 2);
    let start_r = (im.min(r0 - 2)..=r0 - 2)
        .rev()
        .find(|&i| prof[i] >= half_r)
        .unwrap_or(r0 - 2);
    // Left: last rise through half_l before the interior.
    let mut xl = None;
    for i in (1..=start_l).rev() {
        if prof[i - 1] < half_l && prof[i] >= half_l {
            xl = Some((i - 1) as f64 + ((half_l - prof[i - 1]) / (prof[i] - prof[i - 1])) as f64);
            break;
        }
    }
    let mut xr = None;
    for i in start_r..n - 1 {
        if prof[i] >= half_r && prof[i + 1] < half_r {
            xr = Some(i as f64 + ((prof[i] - half_r) / (prof[i] - prof[i + 1])) as f64);
            break;
        }
    }
    Some((xl?, xr?))
}

/// From this many pins on, a free scale's robust fit starts from the
/// repeated median ([`repeated_median_slope`]).
const REPEATED_MEDIAN_FROM: usize = 4;

/// Siegel's repeated median slope of u over n: for each point the median
/// slope to every other, then the median of those. Half the points may
/// stand off the line before it moves, where least squares follows each:
/// a pin bent along a row of four to seven at an estimated scale pulled
/// the plain fit's scale by 1–8 %, which the Tukey weights started from it
/// kept (the bent pin's residual shrank into the good pins' spread), so
/// the bend read ok and every height was scaled by the error (Rust
/// 1 110 708, a 1 × 5: heights 1.3 tolerances high). `None` with fewer
/// than two distinct n.
fn repeated_median_slope(n: &[f64], u: &[f64]) -> Option<f64> {
    let mut per_point: Vec<f64> = Vec::with_capacity(n.len());
    for i in 0..n.len() {
        let mut slopes: Vec<f64> = (0..n.len())
            .filter(|&j| j != i && (n[j] - n[i]).abs() > 1e-12)
            .map(|j| (u[j] - u[i]) / (n[j] - n[i]))
            .collect();
        if let Some(m) = grid::median(&mut slopes) {
            per_point.push(m);
        }
    }
    grid::median(&mut per_point)
}

/// Robust 1-D fit u = a + b·n (n nominal mm, u measured px) with `b` fixed
/// when the scale is known; Tukey IRLS with MAD scale floored at `floor`.
pub(super) fn robust_offset_scale(
    n: &[f64],
    u: &[f64],
    fixed_b: Option<f64>,
    floor: f64,
) -> Option<(f64, f64, Vec<bool>, f64)> {
    let k = n.len();
    if k == 0 || (fixed_b.is_none() && k < 2) {
        return None;
    }
    let solve = |w: &[f64]| -> Option<(f64, f64)> {
        let sw: f64 = w.iter().sum();
        if !(sw > 0.0) {
            return None;
        }
        match fixed_b {
            Some(b) => {
                let a = n
                    .iter()
                    .zip(u)
                    .zip(w)
                    .map(|((n, u), w)| w * (u - b * n))
                    .sum::<f64>()
                    / sw;
                Some((a, b))
            }
            None => {
                let mn = n.iter().zip(w).map(|(n, w)| w * n).sum::<f64>() / sw;
                let mu = u.iter().zip(w).map(|(u, w)| w * u).sum::<f64>() / sw;
                let (mut snn, mut snu) = (0.0, 0.0);
                for ((n, u), w) in n.iter().zip(u).zip(w) {
                    snn += w * (n - mn) * (n - mn);
                    snu += w * (n - mn) * (u - mu);
                }
                if snn <= 1e-12 {
                    return None;
                }
                let b = snu / snn;
                Some((mu - b * mn, b))
            }
        }
    };
    // Start from the median offset, or with a free scale from Siegel's
    // repeated median (the plain fit with three or fewer pins).
    let b0 = match fixed_b {
        Some(b) => Some(b),
        None if k >= REPEATED_MEDIAN_FROM => Some(repeated_median_slope(n, u)?),
        None => None,
    };
    let (mut a, mut b) = match b0 {
        Some(b) => {
            let mut d: Vec<f64> = n.iter().zip(u).map(|(n, u)| u - b * n).collect();
            (grid::median(&mut d)?, b)
        }
        None => solve(&vec![1.0; k])?,
    };
    let mut sigma = floor;
    for _ in 0..10 {
        let r: Vec<f64> = n
            .iter()
            .zip(u)
            .map(|(n, u)| (u - a - b * n).abs())
            .collect();
        let mut rr = r.clone();
        sigma = (1.4826 * grid::median(&mut rr).unwrap_or(0.0)).max(floor);
        let c = 4.685 * sigma;
        let w: Vec<f64> = r
            .iter()
            .map(|ri| {
                let t = ri / c;
                if t < 1.0 { (1.0 - t * t).powi(2) } else { 0.0 }
            })
            .collect();
        match solve(&w) {
            Some((na, nb)) => {
                let moved = (na - a).abs() + (nb - b).abs();
                a = na;
                b = nb;
                if moved < 1e-9 {
                    break;
                }
            }
            None => break,
        }
    }
    let c = 4.685 * sigma;
    let inl: Vec<bool> = n
        .iter()
        .zip(u)
        .map(|(n, u)| (u - a - b * n).abs() < c)
        .collect();
    let w: Vec<f64> = inl.iter().map(|&x| if x { 1.0 } else { 0.0 }).collect();
    if let Some((na, nb)) = solve(&w) {
        a = na;
        b = nb;
    }
    let (mut ss, mut m) = (0.0, 0);
    for ((n, u), &i) in n.iter().zip(u).zip(&inl) {
        if i {
            ss += (u - a - b * n).powi(2);
            m += 1;
        }
    }
    Some((
        a,
        b,
        inl,
        if m > 0 {
            (ss / m as f64).sqrt()
        } else {
            f64::NAN
        },
    ))
}

/// The pitch from the spacings between neighbouring pins, given a rough
/// `prior` (from the pins' width): each spacing is divided by the whole
/// number of pitches it spans, and the median taken over those that sit
/// near a whole number. `None` without a usable spacing.
pub(super) fn refine_pitch(spacings: &[f64], prior: f64) -> Option<f64> {
    if !(prior.is_finite() && prior > 0.0) {
        let mut d = spacings.to_vec();
        return grid::median(&mut d);
    }
    let mut est: Vec<f64> = spacings
        .iter()
        .filter_map(|&d| {
            let k = (d / prior).round();
            (k >= 1.0 && (d / prior - k).abs() < 0.3).then_some(d / k)
        })
        .collect();
    grid::median(&mut est)
}

/// Whether pins at positions `u` along the row (px) lie on a lattice of
/// pitch `pitch` as a whole: the lattice's offset is the one that puts the
/// most pins within `tol` px of a node (`tol`: what an ok pin may be off),
/// and the row fits when at least half the pins sit on nodes and fewer than
/// a quarter sit midway between them (0.4 pitch or more off: no bent pin of
/// this part stands there). Judged as a whole, not spacing by spacing, so
/// two neighbours bent apart (a spacing of 1.6 pitch and one of 0.4) do not
/// make a wrong part.
pub(super) fn row_fits_lattice(u: &[f64], pitch: f64, tol: f64) -> bool {
    if u.len() < 3 || !(pitch.is_finite() && pitch > 0.0) {
        return true;
    }
    let tol = tol.min(0.35 * pitch);
    let res = |u0: f64, x: f64| {
        let a = (x - u0) / pitch;
        (a - a.round()) * pitch
    };
    let mut best = (0usize, u[0]);
    for &u0 in u {
        let n = u.iter().filter(|&&x| res(u0, x).abs() <= tol).count();
        if n > best.0 {
            best = (n, u0);
        }
    }
    // Refine the offset to the mean residual of the pins on nodes.
    let on: Vec<f64> = u
        .iter()
        .map(|&x| res(best.1, x))
        .filter(|r| r.abs() <= tol)
        .collect();
    let u0 = best.1 + on.iter().sum::<f64>() / on.len().max(1) as f64;
    let inl = u.iter().filter(|&&x| res(u0, x).abs() <= tol).count();
    let between = u
        .iter()
        .filter(|&&x| res(u0, x).abs() >= 0.4 * pitch)
        .count();
    2 * inl >= u.len() && !(between >= 2 && 4 * between >= u.len())
}

/// The end of a bar standing up, measured along its axis: see
/// [`tip_crossing`].
#[derive(Debug, Clone, Copy)]
pub(super) struct TipCrossing {
    /// Half-level crossing near the axis, y px.
    pub y_in: f64,
    /// Mean d² of the near-axis samples, px².
    pub e_in: f64,
    /// Contour shape y = a + c·d² (c ≥ 0; 0 for a square end).
    pub c: f64,
    /// Blur σ from the near-axis profile's 25–75 % rise, px.
    pub sigma: f64,
    /// Half-level crossing of the profile averaged across the middle of
    /// the width (seven offsets over ±½ of the half-width) and smoothed
    /// along the axis by 0.6 σ, y px: the end's position with a few times
    /// less noise than `y_in`; its offset from the apex (which depends on
    /// the end's shape and the blur) is the row's, measured by
    /// [`super::side_end::row_end_offset`].
    pub y_band: f64,
}

impl TipCrossing {
    /// The tip (y px) for a contour shape `c` and blur `sigma` (the row's
    /// medians: one part, one focus): the contour's apex moved out by
    /// σ²·c, the pull of blur on an end of curvature κ = 2c (σ²κ/2).
    pub fn tip_y(&self, c: f64, sigma: f64) -> f64 {
        self.y_in - c * self.e_in - sigma * sigma * c
    }
}

/// The end of a bar standing up (sign space: bar high), from profiles
/// along its axis sampled by `sample(d, y)` (d: lateral offset from the
/// axis, px) over y in [t0, t1] (background first).
///
/// A rounded end is curved: the half-level crossing off the axis lies
/// lower than on it, and blur σ pulls a curved edge's half-level contour
/// towards its centre of curvature by about σ²κ/2. So the crossing is taken
/// near the axis (±0.2 of the half-width) and off it (±0.55), the contour
/// is fitted as y = a + c·d² (κ = 2c, at most that of a radius of half the
/// half-width), with σ from the near-axis profile's 25–75 % rise (1.349 σ
/// for a Gaussian edge). One bar's c and σ are noisy; the caller takes the
/// row's medians ([`TipCrossing::tip_y`]).
pub(super) fn tip_crossing(
    sample: &dyn Fn(f64, f64) -> f32,
    t0: f64,
    t1: f64,
    half_w: f64,
) -> Option<TipCrossing> {
    const STEP: f64 = 0.25;
    let n = ((t1 - t0) / STEP) as usize;
    if n < 20 {
        return None;
    }
    let prof_at = |ds: &[f64]| -> Vec<f32> {
        (0..=n)
            .map(|i| {
                let y = t0 + i as f64 * STEP;
                ds.iter().map(|&d| sample(d, y)).sum::<f32>() / ds.len() as f32
            })
            .collect()
    };
    let levels = |p: &[f32]| {
        let m = p.len();
        let mut top: Vec<f32> = p[..8].to_vec();
        let mut bot: Vec<f32> = p[m - 8..].to_vec();
        (median_f32(&mut top), median_f32(&mut bot))
    };
    let half_w = if half_w.is_finite() { half_w } else { 0.0 };
    let (di, dout) = (0.2 * half_w, 0.55 * half_w);
    let inner = prof_at(&[-di, 0.0, di]);
    let (lo, hi) = levels(&inner);
    let at = |p: &[f32], lo: f32, hi: f32, frac: f32| {
        step_rise(p, lo + frac * (hi - lo)).map(|f| t0 + f * STEP)
    };
    let y_in = at(&inner, lo, hi, 0.5)?;
    let e_in = 2.0 / 3.0 * di * di;
    let sigma = match (at(&inner, lo, hi, 0.25), at(&inner, lo, hi, 0.75)) {
        (Some(a), Some(b)) if b > a => ((b - a) / 1.349).min(half_w.max(1.0)),
        _ => 0.0,
    };
    let mut c = 0.0;
    if half_w >= 2.0 {
        let outer = prof_at(&[-dout, dout]);
        let (lo_o, hi_o) = levels(&outer);
        if let Some(yo) = at(&outer, lo_o, hi_o, 0.5) {
            c = ((yo - y_in) / (dout * dout - e_in)).clamp(0.0, 1.0 / half_w);
        }
    }
    let y_band = if half_w >= 2.0 {
        let band = smooth_along(
            &prof_at(&BAND_OFFSETS.map(|f| f * half_w)),
            0.6 * sigma / STEP,
        );
        let (lo_b, hi_b) = levels(&band);
        match at(&band, lo_b, hi_b, 0.5) {
            Some(y) if (y - y_in).abs() <= 2.0 * sigma.max(1.0) => y,
            _ => y_in,
        }
    } else {
        y_in
    };
    Some(TipCrossing {
        y_in,
        e_in,
        c,
        sigma,
        y_band,
    })
}

/// Lateral offsets of the band profile, in half-widths.
const BAND_OFFSETS: [f64; 7] = [-0.5, -1.0 / 3.0, -1.0 / 6.0, 0.0, 1.0 / 6.0, 1.0 / 3.0, 0.5];

/// A profile smoothed by a Gaussian of `s` samples (at most 6; none under
/// 1), its ends renormalised: a symmetric second blur moves no half-level
/// crossing of a straight step, and averages the noise down.
fn smooth_along(raw: &[f32], s: f64) -> Vec<f32> {
    let s = s.min(6.0);
    if !(s >= 1.0) {
        return raw.to_vec();
    }
    let r = (3.0 * s).ceil() as i64;
    let k: Vec<f64> = (-r..=r)
        .map(|i| (-((i * i) as f64) / (2.0 * s * s)).exp())
        .collect();
    let n = raw.len() as i64;
    (0..n)
        .map(|i| {
            let (mut acc, mut w) = (0.0, 0.0);
            for (j, kj) in (-r..=r).zip(&k) {
                let t = i + j;
                if (0..n).contains(&t) {
                    acc += kj * raw[t as usize] as f64;
                    w += kj;
                }
            }
            (acc / w) as f32
        })
        .collect()
}

/// [`tip_crossing`] in a window that clears the blurred end on both sides,
/// wherever the coarse guess put it.
///
/// The end's levels are the medians of the window's first and last 2 px,
/// so the window must reach past the blur on each side of the end: under a
/// blur of σ = 2.5 px, a window of ±6 px whose centre (the coarse blob's
/// top) lies 3 px inside the bar takes its background level from the
/// blur's foot and puts the end 0.6 px too low (ok pins called short, the
/// side view's largest class). So a first pass over `guess ± half` gives
/// the crossing and σ, and a second pass re-centred on that crossing, over
/// ± (`half` + 3 σ), measures the end; the first pass is kept where the
/// second finds none.
pub(super) fn tip_crossing_recentred(
    sample: &dyn Fn(f64, f64) -> f32,
    guess: f64,
    half: f64,
    half_w: f64,
    limits: (f64, f64),
) -> Option<TipCrossing> {
    let first = tip_crossing(sample, guess - half, guess + half, half_w)?;
    let m = half + 3.0 * first.sigma;
    let (t0, t1) = (
        (first.y_in - m).max(limits.0),
        (first.y_in + m).min(limits.1),
    );
    if t0 >= first.y_in - half || t1 <= first.y_in + half {
        return Some(first);
    }
    Some(tip_crossing(sample, t0, t1, half_w).unwrap_or(first))
}

#[cfg(test)]
mod tests {
    /// A pillbox blur makes an edge a straight ramp; noise put the
    /// steepest point near its foot (here index 38: 30 → 6), two samples
    /// inside which the profile is already under the half level (40 at
    /// 36). The right edge still crosses 50 at exactly 35.0.
    #[test]
    fn an_edge_whose_steepest_point_is_low_on_a_ramp_is_found() {
        let mut prof = vec![0f32; 48];
        for v in &mut prof[20..=30] {
            *v = 100.0;
        }
        for (i, v) in [90.0, 80.0, 70.0, 60.0, 50.0, 40.0, 30.0, 20.0, 6.0]
            .into_iter()
            .enumerate()
        {
            prof[31 + i] = v;
        }
        let (l, r) = super::bar_edges(&prof, false).expect("both edges");
        assert!((l - 19.5).abs() < 1e-9, "{l}");
        assert!((r - 35.0).abs() < 1e-9, "{r}");
    }

    /// A blurred bar whose steepest rise (index 10) and fall (15) snap
    /// inwards to 11 and 14, three samples apart: no sample lies two
    /// inside both, and the bar was dropped (Rust 1 220 454, two good
    /// pins read missing). Where the lattice puts a pin, its level is the
    /// peak's (100) over a background of 0; the half level 50 is crossed
    /// at 10 + 20/50 and 14 + 40/50.
    #[test]
    fn a_bar_whose_steepest_points_are_three_samples_apart_keeps_its_edges() {
        let mut prof = vec![0f32; 27];
        prof[9..18].copy_from_slice(&[10.0, 30.0, 80.0, 95.0, 100.0, 90.0, 40.0, 20.0, 10.0]);
        assert!(
            super::bar_edges(&prof, false).is_none(),
            "no room inside the edges"
        );
        let (l, r) = super::bar_edges(&prof, true).expect("both edges");
        assert!((l - 10.4).abs() < 1e-6, "{l}");
        assert!((r - 14.8).abs() < 1e-6, "{r}");
    }

    #[test]
    fn a_noise_spike_before_the_step_is_not_the_rise() {
        // Background 0 with a spike to 80 at index 5; the step up to 100
        // crosses 50 at exactly 20.5 (45 at 20, 55 at 21). The first rise
        // from the start is the spike.
        let mut prof = vec![0f32; 40];
        prof[5] = 80.0;
        prof[20] = 45.0;
        for v in &mut prof[21..] {
            *v = 100.0;
        }
        prof[21] = 55.0;
        assert!((super::first_rise(&prof, 50.0).unwrap() - 4.625).abs() < 1e-9);
        let x = super::step_rise(&prof, 50.0).unwrap();
        assert!((x - 20.5).abs() < 1e-9, "{x}");
    }

    #[test]
    fn a_bar_beside_a_dimmer_patch_of_backlight_keeps_its_edges() {
        // Sign space: backlight at -200 on the right; on the left a patch
        // rising to -170 (30 DN dimmer) in the 8 px next to the bar; the
        // bar at -140 covers [20, 31] exactly (pixel i spans i ± 0.5), so
        // its half-level crossings lie at 20.0 and 31.0.
        let prof: Vec<f32> = (0..48)
            .map(|i| {
                let x = i as f64;
                let cov = ((x + 0.5).min(31.0) - (x - 0.5).max(20.0)).clamp(0.0, 1.0) as f32;
                let bg = if i <= 20 {
                    (-200.0 + 30.0 * ((i as f32 - 4.0) / 8.0)).clamp(-200.0, -170.0)
                } else {
                    -200.0
                };
                bg + cov * (-140.0 - bg)
            })
            .collect();
        let (l, r) = super::bar_edges(&prof, false).unwrap();
        assert!(
            (l - 20.0).abs() < 1e-3 && (r - 31.0).abs() < 1e-3,
            "{l} {r}"
        );
    }

    #[test]
    fn pitch_from_spacings_with_a_missing_pin_between() {
        // Pins at 0, 10, 30 (one missing): the median of [10, 20] would be
        // 15; with a width prior of 9 px the spacings give 10.
        let p = super::refine_pitch(&[10.0, 20.0], 9.0).unwrap();
        assert!((p - 10.0).abs() < 1e-9, "{p}");
        // Spacings far from any whole multiple of the prior are ignored.
        let p = super::refine_pitch(&[10.0, 14.5, 30.3], 10.0).unwrap();
        assert!((p - 10.05).abs() < 1e-9, "{p}");
        assert_eq!(super::refine_pitch(&[], 10.0), None);
    }

    #[test]
    fn a_pin_bent_along_a_row_of_five_leaves_the_scale_alone() {
        // Five pins 1.27 mm apart at 20 px/mm from u = 100 px; the last
        // bent along the row by 3 px (the others exact).
        let n: Vec<f64> = (0..5).map(|i| i as f64 * 1.27).collect();
        let mut u: Vec<f64> = n.iter().map(|n| 100.0 + 20.0 * n).collect();
        u[4] += 3.0;
        // Least squares over all five moves the scale by 3 px × 2 pitches
        // over Σ(n − n̄)² = 10 pitches², 2.4 %.
        let b_ls = {
            let (mn, mu) = (n.iter().sum::<f64>() / 5.0, u.iter().sum::<f64>() / 5.0);
            let snu: f64 = n.iter().zip(&u).map(|(n, u)| (n - mn) * (u - mu)).sum();
            let snn: f64 = n.iter().map(|n| (n - mn) * (n - mn)).sum();
            snu / snn
        };
        assert!((b_ls / 20.0 - 1.0236).abs() < 1e-3, "{b_ls}");
        assert!((super::repeated_median_slope(&n, &u).unwrap() - 20.0).abs() < 1e-9);
        let (a, b, inl, rms) = super::robust_offset_scale(&n, &u, None, 0.1).unwrap();
        assert!(
            (b - 20.0).abs() < 1e-9 && (a - 100.0).abs() < 1e-9,
            "{a} {b}"
        );
        assert_eq!(inl, vec![true, true, true, true, false]);
        assert!(rms < 1e-9, "{rms}");
        // A bend in the middle of the row, the same.
        let mut u: Vec<f64> = n.iter().map(|n| 100.0 + 20.0 * n).collect();
        u[2] -= 3.0;
        let (_, b, inl, _) = super::robust_offset_scale(&n, &u, None, 0.1).unwrap();
        assert!((b - 20.0).abs() < 1e-9, "{b}");
        assert_eq!(inl, vec![true, true, false, true, true]);
    }

    #[test]
    fn a_row_is_judged_against_its_lattice_as_a_whole() {
        use super::row_fits_lattice as fits;
        // Pitch 20 px, ok pins within 1 px; pins 1 and 2 of 5 bent apart
        // by 0.3 pitch: spacings 14, 32, 14 but the row is this part.
        assert!(fits(&[0.0, 14.0, 46.0, 60.0, 80.3], 20.0, 3.0));
        // A part at 1.27 × the pitch: most pins off the nodes.
        let u: Vec<f64> = (0..10).map(|i| i as f64 * 25.4).collect();
        assert!(!fits(&u, 20.0, 3.0));
        // A part at half the pitch: every other pin midway between nodes.
        let u: Vec<f64> = (0..8).map(|i| i as f64 * 10.0).collect();
        assert!(!fits(&u, 20.0, 3.0));
        // Twice the pitch (every other pin missing) is still on the lattice.
        let u: Vec<f64> = (0..5).map(|i| i as f64 * 40.0 + 0.5).collect();
        assert!(fits(&u, 20.0, 3.0));
    }

    #[test]
    fn a_blurred_rounded_end_is_found_at_its_apex() {
        // A bar 8 px wide with a semicircular end (apex at y = 20), blurred
        // with σ = 2 px, sampled on a 0.25 px grid around its axis x = 0.
        let (r, apex, sigma) = (4.0f64, 20.0f64, 2.0f64);
        let inside = |x: f64, y: f64| {
            let yc = apex + r;
            y >= yc && x.abs() <= r || (x * x + (y - yc) * (y - yc)) <= r * r
        };
        // Blurred value by numeric convolution (±3σ, 0.2 px steps).
        let blurred = |x: f64, y: f64| -> f32 {
            let (mut s, mut w) = (0.0, 0.0);
            let n = (3.0 * sigma / 0.2) as i32;
            for i in -n..=n {
                for j in -n..=n {
                    let (dx, dy) = (i as f64 * 0.2, j as f64 * 0.2);
                    let g = (-(dx * dx + dy * dy) / (2.0 * sigma * sigma)).exp();
                    w += g;
                    if inside(x + dx, y + dy) {
                        s += g;
                    }
                }
            }
            (100.0 * s / w) as f32
        };
        let sample = |d: f64, y: f64| blurred(d, y);
        let t = super::tip_crossing(&sample, 10.0, 34.0, r).unwrap();
        let raw = t.y_in - apex;
        let fixed = t.tip_y(t.c, t.sigma) - apex;
        // The plain half-level crossing lies inside the end; the corrected
        // tip is at least twice as close to the apex.
        assert!(raw > 0.2, "raw crossing {raw:.3} px below the apex");
        assert!(
            fixed.abs() < 0.5 * raw,
            "corrected {fixed:.3} px, raw {raw:.3} px"
        );
        // A square end keeps its half-level crossing.
        let square = |d: f64, y: f64| {
            let _ = d;
            (100.0 * 0.5 * (1.0 + libm_erf((y - apex) / (sigma * std::f64::consts::SQRT_2)))) as f32
        };
        let t = super::tip_crossing(&square, 10.0, 34.0, r).unwrap();
        assert!((t.tip_y(t.c, t.sigma) - apex).abs() < 0.05, "{t:?}");
    }

    #[test]
    fn a_blurred_end_is_measured_wherever_the_coarse_guess_lies() {
        // A square end at y = 20 under blur σ = 2.5 px; the coarse guess 3 px
        // inside the bar, the window ±6 px around it (as for k = 1).
        let (apex, sigma) = (20.0f64, 2.5f64);
        let square = |_d: f64, y: f64| {
            (100.0 * 0.5 * (1.0 + libm_erf((y - apex) / (sigma * std::f64::consts::SQRT_2)))) as f32
        };
        let guess = apex + 3.0;
        let once = super::tip_crossing(&square, guess - 6.0, guess + 6.0, 4.0).unwrap();
        assert!(once.tip_y(0.0, 0.0) - apex > 0.4, "{once:?}");
        let t = super::tip_crossing_recentred(&square, guess, 6.0, 4.0, (0.0, 60.0)).unwrap();
        assert!((t.tip_y(0.0, 0.0) - apex).abs() < 0.05, "{t:?}");
        // The same guess 3 px outside the bar: too high before, right after.
        let guess = apex - 3.0;
        let once = super::tip_crossing(&square, guess - 6.0, guess + 6.0, 4.0).unwrap();
        assert!(apex - once.tip_y(0.0, 0.0) > 0.4, "{once:?}");
        let t = super::tip_crossing_recentred(&square, guess, 6.0, 4.0, (0.0, 60.0)).unwrap();
        assert!((t.tip_y(0.0, 0.0) - apex).abs() < 0.05, "{t:?}");
    }

    /// erf by Abramowitz–Stegun 7.1.26 (|error| < 1.5e-7).
    fn libm_erf(x: f64) -> f64 {
        let s = x.signum();
        let x = x.abs();
        let t = 1.0 / (1.0 + 0.3275911 * x);
        let y = 1.0
            - (((((1.061405429 * t - 1.453152027) * t) + 1.421413741) * t - 0.284496736) * t
                + 0.254829592)
                * t
                * (-x * x).exp();
        s * y
    }
}
