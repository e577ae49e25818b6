//! The side view's housing edge, coarse: the silhouette's threshold, each
//! column's longest silhouette run (its top is the housing's top edge where
//! no pin stands), and the columns near a pin left out of the sub-pixel
//! edge. Kept apart from `side.rs` (the pipeline).

use super::fit::{LineFit, robust_line};
use super::gray::{Plane, Px};
use super::grid::MAX_TILT_DEG;
use super::label::{Blob, Run};

/// The backlight's level after `backlight::normalise_backlight` (sign
/// space: the silhouette above it).
pub(super) const BACKLIGHT: f32 = -1000.0;

/// Share of the frame the darkest silhouette quantile is read at: the
/// housing block covers more than 1 % of any side view that shows it.
const DARK_QUANTILE: f64 = 0.99;

/// The silhouette's threshold on the backlight-normalised coarse image:
/// Otsu's, but never nearer the backlight than halfway from it to the
/// silhouette's level (an opaque silhouette's edge lies at that half level
/// whatever the blur). When the silhouette covers a few per cent of the
/// frame and the backlight varies more than the cubic backlight model
/// follows (vignetting times a gradient across a small part), Otsu splits
/// the backlight itself (at 93 % of it on py 540 143, contrast 0.40): the
/// frame's dimmer patches became silhouette, stood above the housing as
/// "pins" as wide as the frame, and left no column for the housing edge.
///
/// The silhouette's level is the median of what lies beyond a first
/// threshold halfway to the darkest 1 % (noise puts that quantile past the
/// housing's level, and a threshold from it alone cut thin pins under
/// noise: 400 202). Where nothing beyond Otsu's threshold lies twice as
/// far from the backlight, Otsu stands.
pub(super) fn silhouette_threshold(data: &[f32], otsu: f32) -> f32 {
    match silhouette_level(data, otsu) {
        Some(level) => otsu.max(0.5 * (BACKLIGHT + level)),
        None => otsu,
    }
}

/// The silhouette's level (see [`silhouette_threshold`]); `None` when
/// nothing lies beyond the first threshold.
pub(super) fn silhouette_level(data: &[f32], otsu: f32) -> Option<f32> {
    if data.is_empty() {
        return None;
    }
    let mut v = data.to_vec();
    let q = ((v.len() - 1) as f64 * DARK_QUANTILE) as usize;
    let dark = *v.select_nth_unstable_by(q, |a, b| a.total_cmp(b)).1;
    let first = otsu.max(0.5 * (BACKLIGHT + dark));
    let mut beyond: Vec<f32> = data.iter().copied().filter(|&x| x > first).collect();
    if beyond.is_empty() {
        return None;
    }
    let m = beyond.len() / 2;
    Some(*beyond.select_nth_unstable_by(m, |a, b| a.total_cmp(b)).1)
}

/// Each column's longest silhouette run of at least `min_run` coarse px,
/// as (column, top row), sorted by column. A run that starts on the
/// frame's top border is left out: its top is the frame, not an edge, and
/// the housing's top edge lies inside the frame with the pins above it.
/// Under a backlight the cubic model does not follow (a gradient across a
/// narrow part, 800 126), a dim corner of the frame passed the threshold;
/// its runs, all starting at row 0, outnumbered a 1 × 2 part's edge
/// columns and the robust line lay along the frame's top.
pub(super) fn run_tops(
    cw: usize,
    ch: usize,
    fg: &dyn Fn(usize, usize) -> bool,
    min_run: usize,
) -> Vec<(f64, f64)> {
    let mut tops = Vec::new();
    for x in 0..cw {
        let (mut best, mut best_start, mut run, mut start) = (0usize, 0usize, 0usize, 0usize);
        for y in 0..ch {
            if fg(x, y) {
                if run == 0 {
                    start = y;
                }
                run += 1;
                if start > 0 && run > best {
                    best = run;
                    best_start = start;
                }
            } else {
                run = 0;
            }
        }
        if best >= min_run {
            tops.push((x as f64, best_start as f64));
        }
    }
    tops
}

/// Whether a column's profile across the housing's edge (sign space: `lo`
/// the backlight above it, `hi` the silhouette below) steps far enough to
/// hold the edge: by 0.3 of the frame's raw `contrast`, or, where the
/// backlight was divided out (`depth`: the silhouette's share below the
/// backlight), by 0.3 of the step the local backlight gives. The raw
/// contrast is set by the brightest backlight in the frame; under a
/// gradient or vignetting the housing's edge in a dim corner steps by far
/// less (965 147: pins at the frame's dim top, one column passed and the
/// housing was "not found").
pub(super) fn clear_step(lo: f32, hi: f32, contrast: f32, depth: Option<f32>) -> bool {
    let local = match depth {
        Some(d) if lo < 0.0 => 0.3 * d * -lo,
        _ => f32::INFINITY,
    };
    hi - lo > (0.3 * contrast).min(local)
}

/// Whether the silhouette below the housing's top edge (`edge_c`: its row
/// at a coarse column) is an opaque block over the columns `cols`
/// (inclusive): a side view's housing is, and every column runs on about
/// equally far below the edge. A top view inspected with a side recipe
/// shows its tips and holes there, which cut the runs of the columns
/// through them short: that stays an error.
pub(super) fn solid_block(
    cols: (usize, usize),
    ch: usize,
    edge_c: &dyn Fn(f64) -> f64,
    fg: &dyn Fn(usize, usize) -> bool,
) -> bool {
    let mut runs: Vec<f64> = (cols.0..=cols.1)
        .map(|x| {
            let y0 = (edge_c(x as f64) + 2.0).ceil().max(0.0) as usize;
            (y0..ch).take_while(|&y| fg(x, y)).count() as f64
        })
        .collect();
    runs.sort_by(|a, b| a.total_cmp(b));
    let q = |f: f64| runs.get(((runs.len() as f64 - 1.0) * f) as usize).copied();
    matches!((q(0.25), q(0.5)), (Some(lo), Some(med)) if med >= 2.0 && lo >= 0.7 * med)
}

/// Columns (coarse, inclusive) a bar stands on: the median left and right
/// ends of its rows in its lower half, leaving out the foot (rows more than
/// half as wide again as the bar's median row). The label reaches down to
/// 1.5 coarse px above the coarse edge, where the housing's blurred top
/// edge still passes the threshold, and noise pixels cling to a bar's
/// sides: the bounding box of a 1 × 4 part's 6.5 px pins (800 205, blur
/// 2.1 px, noise 8.4 DN) was 12–14 px wide on a 22 px pitch, which left no
/// column between the pins for the sub-pixel edge. The lower half, not the
/// whole bar: in a tilted view the base stands to the side of the tip.
pub(super) fn body_x_range(b: &Blob, runs: &[Run]) -> (u32, u32) {
    let h = (b.y_max - b.y_min + 1) as usize;
    let mut rows = vec![(u32::MAX, 0u32); h];
    for &i in &b.runs {
        let r = runs[i as usize];
        if r.x1 > r.x0 {
            let e = &mut rows[(r.y - b.y_min) as usize];
            e.0 = e.0.min(r.x0);
            e.1 = e.1.max(r.x1 - 1);
        }
    }
    let width = |e: &(u32, u32)| (e.1 + 1).saturating_sub(e.0);
    let mut w: Vec<u32> = rows.iter().filter(|e| e.0 <= e.1).map(width).collect();
    if w.is_empty() {
        return (b.x_min, b.x_max);
    }
    let m = w.len() / 2;
    let w_med = *w.select_nth_unstable(m).1;
    let (mut l, mut r): (Vec<u32>, Vec<u32>) = rows[h / 2..]
        .iter()
        .filter(|e| e.0 <= e.1 && 2 * width(e) <= 3 * w_med + 2)
        .map(|e| (e.0, e.1))
        .unzip();
    if l.is_empty() {
        return (b.x_min, b.x_max);
    }
    let m = l.len() / 2;
    (*l.select_nth_unstable(m).1, *r.select_nth_unstable(m).1)
}

/// The profile (sign space) down column `xi` over rows `ys` (inclusive),
/// averaged over the columns `xi ± span` along the coarse edge's `slope`
/// (bilinear). One column's first half-level crossing under heavy noise is
/// a noise spike in the backlight above the edge: on py 530 092 (noise
/// 11.5 DN on a 52 DN step, one column per point) the robust line took a
/// chance alignment of such spikes 17 px above the housing and every pin
/// was short. The mean along the edge leaves the crossing where it is.
pub(super) fn edge_profile<P: Px>(
    plane: &Plane<P>,
    sign: f32,
    xi: usize,
    ys: (usize, usize),
    span: usize,
    slope: f64,
) -> Vec<f32> {
    let (xmax, ymax) = ((plane.w - 1) as f64, (plane.h - 1) as f64);
    let n = (2 * span + 1) as f32;
    (ys.0..=ys.1)
        .map(|y| {
            (-(span as i64)..=span as i64)
                .map(|d| {
                    let x = (xi as f64 + d as f64).clamp(0.0, xmax);
                    let yy = (y as f64 + slope * d as f64).clamp(0.0, ymax);
                    sign * plane.bilinear(x, yy)
                })
                .sum::<f32>()
                / n
        })
        .collect()
}

/// Largest step (coarse px) between neighbouring columns' run tops on an
/// edge the housing's top can be: a top edge tilted up to
/// [`grid::MAX_TILT_DEG`] moves 0.2 px a column, a side edge of a block
/// rotated that much 4.7 px or more.
const MAX_TOP_STEP: f64 = 3.0;

/// The run tops (column, top row; sorted by column) without those on a
/// steep edge: a top whose neighbouring columns' tops both lie more than
/// [`MAX_TOP_STEP`] away. A housing block taller than wide, rotated, shows
/// one of its sides to the columns as a staircase of run tops (each column
/// left of that side starts its run where the side crosses it); in a tall
/// frame those outnumber the top edge's columns, and the robust line then
/// found the side (tilted 85°). A column without a neighbouring top (an
/// isolated run) is kept: the robust line decides.
pub(super) fn drop_steep_tops(tops: &[(f64, f64)]) -> Vec<(f64, f64)> {
    let near = |i: usize, j: Option<usize>| {
        j.and_then(|j| tops.get(j))
            .filter(|q| (q.0 - tops[i].0).abs() == 1.0)
            .map(|q| (q.1 - tops[i].1).abs() <= MAX_TOP_STEP)
    };
    (0..tops.len())
        .filter(
            |&i| match (near(i, i.checked_sub(1)), near(i, Some(i + 1))) {
                (None, None) => true,
                (l, r) => l.unwrap_or(false) || r.unwrap_or(false),
            },
        )
        .map(|i| tops[i])
        .collect()
}

/// A level edge line and the run tops it was fitted among (its `inlier`
/// flags index these).
pub(super) type LevelEdge = (LineFit, Vec<(f64, f64)>);

/// The housing's top edge through the run tops: a robust line no more
/// tilted than [`MAX_TILT_DEG`], with the tops it was fitted among.
/// A backlight's boundary the backlight model leaves (a ramp of light
/// across a small part) can give the longest runs a line of their own:
/// tilted past what a housing can be, its tops are set aside and the edge
/// sought again among the rest (970 686: a ramp's dim side cut the
/// frame's corner at 49°, and the 1 × 2 part's level edge lay in the tops
/// it left). `Err(None)`: no line at all; `Err(Some(t))`: only a line
/// tilted `t`°, with too few tops beside it or no line among them.
pub(super) fn level_edge_line(tops: Vec<(f64, f64)>) -> Result<LevelEdge, Option<f64>> {
    let mut pool = tops;
    // The last tilted line's angle: what the refusal names when the tops
    // left beside it hold no line at all.
    let mut tilted = None;
    loop {
        let line = robust_line(&pool, 1.5).ok_or(tilted)?;
        let tilt = line.line.b.atan().to_degrees();
        if tilt.abs() <= MAX_TILT_DEG {
            return Ok((line, pool));
        }
        let rest: Vec<(f64, f64)> = pool
            .iter()
            .zip(&line.inlier)
            .filter(|(_, i)| !**i)
            .map(|(p, _)| *p)
            .collect();
        if rest.len() < 8 || rest.len() == pool.len() {
            return Err(Some(tilt));
        }
        tilted = Some(tilt);
        pool = rest;
    }
}

/// The coarse pixels of the bars (pins) standing on the housing.
pub(super) struct BarMask {
    w: usize,
    h: usize,
    on: Vec<bool>,
}

impl BarMask {
    pub(super) fn new(w: usize, h: usize, bars: &[Blob], runs: &[Run]) -> BarMask {
        let mut on = vec![false; w * h];
        for b in bars {
            for &i in &b.runs {
                let r = runs[i as usize];
                for x in r.x0..r.x1.min(w as u32) {
                    if (r.y as usize) < h {
                        on[r.y as usize * w + x as usize] = true;
                    }
                }
            }
        }
        BarMask { w, h, on }
    }

    /// Whether a bar pixel lies within `reach` coarse px (Chebyshev) of
    /// the coarse point (x, y).
    ///
    /// At full resolution (coarse factor 1, thin pins) a few noise pixels
    /// beside a pin pass the threshold on their own; the window a dust
    /// candidate is measured in then takes in the pin, and what it
    /// measured was a piece of that pin (py 550 034: fifteen "dust"
    /// shadows along six pins, noise 14 DN on a 100 DN silhouette). Dust
    /// lies clear of the pins, so a measure that lands on a bar is the bar.
    pub(super) fn near(&self, x: f64, y: f64, reach: usize) -> bool {
        if !(x.is_finite() && y.is_finite()) {
            return false;
        }
        let (cx, cy) = (x.floor() as i64, y.floor() as i64);
        let r = reach as i64;
        (cy - r..=cy + r).any(|yy| {
            (cx - r..=cx + r).any(|xx| {
                xx >= 0
                    && yy >= 0
                    && (xx as usize) < self.w
                    && (yy as usize) < self.h
                    && self.on[yy as usize * self.w + xx as usize]
            })
        })
    }
}

/// The housing block's two ends along the row, sub-pixel: the along-row
/// coordinates u = cs·x + sn·y (px) of the half-level crossings of row
/// profiles taken just below the top edge `line`, across each coarse end
/// `x_ends` (full-resolution px) ± `reach` px, the median over up to 16
/// rows 2–17 px below the edge; `None` for an end whose profiles leave
/// the frame or cross in fewer than 5 rows. A side perpendicular to the
/// edge gives the same u on every row. Only what stands below the edge
/// (the block and the backlight beside it) is read: no pin reaches there.
pub(super) fn housing_ends_u<P: Px>(
    plane: &Plane<P>,
    sign: f32,
    line: &super::fit::Line,
    (cs, sn): (f64, f64),
    x_ends: (f64, f64),
    reach: f64,
) -> (Option<f64>, Option<f64>) {
    let step = 0.5;
    let n = (2.0 * reach / step) as usize + 1;
    let (xmax, ymax) = ((plane.w - 1) as f64, (plane.h - 1) as f64);
    // `dir` +1: outside on the left (the block's left end), −1: right end.
    let end_u = |x_end: f64, dir: f64| -> Option<f64> {
        let x_out = x_end - dir * reach;
        let x_in = x_end + dir * reach;
        if x_out.min(x_in) < 0.0 || x_out.max(x_in) > xmax {
            return None;
        }
        let mut us = Vec::new();
        for d in 2..18 {
            let y = line.y_at(x_end) + d as f64;
            if y > ymax {
                break;
            }
            // Outside → inside: the silhouette rises (sign space).
            let prof: Vec<f32> = (0..n)
                .map(|i| sign * plane.bilinear(x_out + dir * i as f64 * step, y))
                .collect();
            let lo = super::side_row::median_f32(&mut prof[..4].to_vec());
            let hi = super::side_row::median_f32(&mut prof[n - 4..].to_vec());
            if !(hi > lo) {
                continue;
            }
            if let Some(f) = super::side_row::step_rise(&prof, 0.5 * (lo + hi)) {
                let x = x_out + dir * f * step;
                us.push(cs * x + sn * y);
            }
        }
        if us.len() < 5 {
            return None;
        }
        super::grid::median(&mut us)
    };
    (end_u(x_ends.0, 1.0), end_u(x_ends.1, -1.0))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::vision::fit;

    /// Sign space, raw levels: the frame's brightest backlight 1000 DN
    /// over a silhouette 0.32 deep, so the frame's raw contrast is 320 DN.
    /// Where the backlight is dimmed to 250 DN the edge steps 80 DN, under
    /// 0.3 of the frame's contrast (96 DN) but 0.32 of its own light; noise
    /// of 40 DN in the bright part is no edge.
    #[test]
    fn a_dim_corners_edge_step_is_judged_against_its_own_backlight() {
        let (contrast, depth) = (320.0, Some(0.32));
        // The dim corner: backlight 400, silhouette 272.
        assert!(clear_step(-400.0, -272.0, contrast, depth));
        // Dimmer still: lost by the raw measure, held by its own light's.
        assert!(!clear_step(-250.0, -170.0, contrast, None));
        assert!(clear_step(-250.0, -170.0, contrast, depth));
        // Noise alone (40 DN in a bright part) is no edge either way.
        assert!(!clear_step(-1000.0, -960.0, contrast, depth));
    }

    /// Run tops of a housing block 30 columns wide and much taller than
    /// the frame shows, rotated 4.4°: the top edge (with three pins on
    /// it) and, right of it, the staircase its side leaves (12.9 rows a
    /// column), longer than the top edge.
    fn tall_block_tops() -> Vec<(f64, f64)> {
        let slope = 4.4f64.to_radians().tan();
        let mut tops = Vec::new();
        for x in 0..30 {
            let mut y = 100.0 + slope * x as f64;
            if [5, 6, 15, 16, 25].contains(&x) {
                y -= 20.0; // pins
            }
            tops.push((x as f64, y.round()));
        }
        for x in 30..70 {
            let y = 100.0 + slope * 30.0 + (x - 29) as f64 / slope;
            tops.push((x as f64, y.round()));
        }
        tops
    }

    #[test]
    fn a_tall_blocks_side_is_not_its_top_edge() {
        let tops = tall_block_tops();
        // All tops: the staircase wins (the error this guards against).
        let all = fit::robust_line(&tops, 1.5).unwrap();
        assert!(all.line.b.atan().to_degrees().abs() > 45.0);
        let kept = drop_steep_tops(&tops);
        assert!(kept.iter().all(|p| p.0 < 31.0));
        let l = fit::robust_line(&kept, 1.5).unwrap();
        assert!((l.line.b.atan().to_degrees() - 4.4).abs() < 1.0);
    }

    #[test]
    fn tops_of_a_flat_edge_and_isolated_runs_are_kept() {
        let tops: Vec<(f64, f64)> = (0..20)
            .map(|x| (x as f64, 50.0 + (x % 3) as f64))
            .chain([(40.0, 10.0)])
            .collect();
        assert_eq!(drop_steep_tops(&tops).len(), tops.len());
    }

    #[test]
    fn a_dim_corner_at_the_frames_top_is_no_housing_edge() {
        // A 60 x 40 coarse frame: a dim corner (columns 0-39) passes the
        // threshold from row 0 to row 14; the housing (columns 44-55)
        // from row 20 down, and runs from the frame's top are longer.
        let fg = |x: usize, y: usize| (x < 40 && y < 15) || ((44..56).contains(&x) && y >= 20);
        let tops = run_tops(60, 40, &fg, 3);
        assert_eq!(tops.len(), 12);
        assert!(tops.iter().all(|p| p.1 == 20.0));
    }

    #[test]
    fn the_threshold_stays_halfway_to_the_silhouette() {
        // Backlight at -1000 with dim patches to -900, a silhouette of 5 %
        // at -600 (its darkest pixels at -500 under noise): a threshold at
        // -930 is raised to -800, halfway to the silhouette's median.
        let mut d: Vec<f32> = (0..950).map(|i| -1000.0 + (i % 10) as f32 * 10.0).collect();
        d.extend((0..50).map(|i| {
            if i % 2 == 0 {
                -600.0
            } else {
                -640.0 + i as f32 * 3.0
            }
        }));
        d.extend([-600.0; 10]);
        let t = silhouette_threshold(&d, -930.0);
        assert!((t + 800.0).abs() < 1e-3, "{t}");
        // Backlight alone (no silhouette): Otsu's threshold stands.
        let d: Vec<f32> = (0..1000).map(|i| -1000.0 + (i % 100) as f32).collect();
        assert_eq!(silhouette_threshold(&d, -950.0), -950.0);
    }

    #[test]
    fn a_measure_on_a_pin_is_the_pin_and_dust_clear_of_it_is_dust() {
        // A 40 x 25 coarse mask above the housing edge: a pin (columns
        // 10-13, rows 5-24); a noise speck 2 px right of the pin (column
        // 16, rows 12-13); dust clear of the pin (columns 20-23, rows 8-11).
        let fg = |x: usize, y: usize| {
            ((10..14).contains(&x) && (5..25).contains(&y))
                || (x == 16 && (12..14).contains(&y))
                || ((20..24).contains(&x) && (8..12).contains(&y))
        };
        let lab = crate::vision::label::label(40, 25, fg);
        assert_eq!(lab.blobs.len(), 3);
        let pin: Vec<Blob> = lab
            .blobs
            .iter()
            .filter(|b| b.height() == 20)
            .cloned()
            .collect();
        let mask = BarMask::new(40, 25, &pin, &lab.runs);
        // The speck's window took in the pin: its measure lands on the
        // pin's edge (x 13.6) or beside it (x 15.2, the speck's column).
        assert!(mask.near(13.6, 12.5, 1));
        assert!(mask.near(15.2, 12.5, 2));
        // The dust's own measure, 9.5 px from the pin's centre, is dust.
        assert!(!mask.near(21.5, 9.5, 2));
        // Above the pin's tip by more than the reach: not the pin.
        assert!(!mask.near(11.5, 1.5, 2));
    }

    #[test]
    fn a_bars_body_leaves_out_its_foot() {
        // A bar 4 columns wide (10-13), rows 0-19, whose lowest rows spread
        // along the edge (columns 5-18).
        let mut runs = Vec::new();
        for y in 0..20u32 {
            let (x0, x1) = match y {
                17.. => (5, 19),
                // A noise pixel clinging to the bar's left side.
                12 => (8, 14),
                _ => (10, 14),
            };
            runs.push(Run { y, x0, x1 });
        }
        let lab = crate::vision::label::label(30, 20, |x, y| {
            let r = runs[y];
            (r.x0 as usize..r.x1 as usize).contains(&x)
        });
        let b = &lab.blobs[0];
        assert_eq!((b.x_min, b.x_max), (5, 18));
        assert_eq!(body_x_range(b, &lab.runs), (10, 13));
    }

    #[test]
    fn the_edge_crossing_survives_a_noise_spike_above_the_edge() {
        // A step from 200 (backlight) to 150 (housing) at row 20 in a
        // 9-column strip; one column has a spike to 170 at row 12. Its own
        // profile's first half-level crossing is the spike; the mean over
        // the strip crosses at the edge.
        let (w, h) = (9usize, 40usize);
        let mut d = vec![0u8; w * h];
        for y in 0..h {
            for x in 0..w {
                d[y * w + x] = if y >= 20 { 150 } else { 200 };
            }
        }
        d[12 * w + 4] = 170;
        let plane = Plane { w, h, data: &d[..] };
        let cross = |p: &[f32]| {
            let level = 0.5 * (p[0] + p[p.len() - 1]);
            crate::vision::side_row::first_rise(p, level).unwrap()
        };
        let one = edge_profile(&plane, -1.0, 4, (0, 39), 0, 0.0);
        assert!((cross(&one) - 11.5).abs() < 0.6, "{}", cross(&one));
        let mean = edge_profile(&plane, -1.0, 4, (0, 39), 4, 0.0);
        assert!((cross(&mean) - 19.5).abs() < 0.01, "{}", cross(&mean));
    }

    /// A dark block (silhouette 60 on a backlight of 200) from x = 40.3 to
    /// x = 160.7 (pixel i spans i ± 0.5; boundary pixels area-weighted), its
    /// top edge y = 49.5: each end within 0.15 px (an unblurred step read
    /// by linear interpolation), their centre within 0.02 px; `None` where
    /// the reach leaves the frame.
    #[test]
    fn the_housing_blocks_ends_are_read_to_a_fraction_of_a_pixel() {
        use super::super::fit::Line;
        use super::super::gray::Plane;
        let (w, h) = (200usize, 100usize);
        let (x0, x1) = (40.3f32, 160.7f32);
        let mut d = vec![200u16 * 64; w * h];
        for y in 50..h {
            for x in 0..w {
                let cover = ((x as f32 + 0.5).min(x1) - (x as f32 - 0.5).max(x0)).clamp(0.0, 1.0);
                d[y * w + x] = ((200.0 - 140.0 * cover) * 64.0).round() as u16;
            }
        }
        let plane = Plane { w, h, data: &d[..] };
        let line = Line { a: 49.5, b: 0.0 };
        let (l, r) = housing_ends_u(&plane, -1.0, &line, (1.0, 0.0), (42.0, 158.0), 10.0);
        let (l, r) = (l.unwrap(), r.unwrap());
        assert!(
            (l - 40.3).abs() < 0.15 && (r - 160.7).abs() < 0.15,
            "{l} {r}"
        );
        assert!((0.5 * (l + r) - 100.5).abs() < 0.02, "{l} {r}");
        let (l, _) = housing_ends_u(&plane, -1.0, &line, (1.0, 0.0), (5.0, 158.0), 10.0);
        assert_eq!(l, None);
    }
}
