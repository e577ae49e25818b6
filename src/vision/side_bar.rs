//! One bar (pin) of the side view measured at full resolution: its axis,
//! width and end, in a window across the bar (`side.rs` finds the bars,
//! this measures one). Also used to look again at a position where no bar
//! was found: the same measurement where the lattice puts the pin.

use super::fit;
use super::gray::{Plane, Px};
use super::side_row::{TipCrossing, bar_edges, median_f32, tip_crossing_recentred};

/// A bar's axis, width and end as measured.
#[derive(Debug, Clone, Copy)]
pub(super) struct BarEnd {
    pub axis: fit::Line,
    pub width_px: f64,
    pub tip: TipCrossing,
    /// The bar's level over its middle part above the background beside
    /// it (sign space: bar high), in the image's units.
    pub contrast: f32,
    /// Whether both halves of the middle part gave their edges (so its
    /// lean was measured, not assumed).
    pub both_halves: bool,
}

/// Where to measure one bar: its columns `x0..=x1` (full-resolution px),
/// the coarse guess of its end `tip_guess` (y px), the columns it may not
/// reach past (half way to the neighbouring bars) and the room beside it
/// for the background (`margin`).
#[derive(Debug, Clone, Copy)]
pub(super) struct BarWindow {
    pub x0: f64,
    pub x1: f64,
    pub tip_guess: f64,
    pub gap: (f64, f64),
    pub margin: f64,
    /// Half-width of the end's search window around `tip_guess`, px.
    pub tip_half: f64,
    /// Whether the row's lattice puts a pin here (the second look): a bar
    /// narrowed by blur is then measured from its peak
    /// ([`bar_edges`]).
    pub on_position: bool,
}

/// Measures the bar in `win` standing on the housing edge `line`.
pub(super) fn measure_bar<P: Px>(
    plane: &Plane<P>,
    sign: f32,
    line: &fit::Line,
    win: &BarWindow,
) -> Option<BarEnd> {
    let (x0f, x1f, tip_guess) = (win.x0, win.x1, win.tip_guess);
    let xa = (x0f - win.margin).max(win.gap.0).max(0.0) as usize;
    let xb = ((x1f + win.margin).min(win.gap.1).max(0.0) as usize).min(plane.w - 1);
    let xm = 0.5 * (x0f + x1f);
    let base = line.y_at(xm);
    let len = base - tip_guess;
    if len < 4.0 || xb <= xa + 4 {
        return None;
    }
    // Centre across the bar over its middle part, from row profiles
    // averaged along the expected axis (perpendicular to the housing
    // edge): one row's edges are lost in the noise of a dim backlight
    // (a noise spike passes for the edge), the mean of many rows is
    // not. The two halves' centres tell a lean (a pin bent sideways).
    let ya = (tip_guess + 0.3 * len).round().max(0.0) as usize;
    let yb = (base - 0.15 * len).round().max(ya as f64 + 1.0) as usize;
    let yb = yb.min(plane.h);
    if yb < ya + 3 {
        return None;
    }
    let ym = 0.5 * (ya + yb - 1) as f64;
    let shear = -line.b;
    let mean_prof = |y0: usize, y1: usize| -> Vec<f32> {
        let n = (y1 - y0).max(1) as f32;
        (xa..=xb)
            .map(|x| {
                (y0..y1)
                    .map(|y| {
                        let xf =
                            (x as f64 + shear * (y as f64 - ym)).clamp(0.0, (plane.w - 1) as f64);
                        sign * plane.bilinear(xf, y as f64)
                    })
                    .sum::<f32>()
                    / n
            })
            .collect()
    };
    let ymid = (ya + yb) / 2;
    let whole = mean_prof(ya, yb);
    let edges = |prof: &[f32]| bar_edges(prof, win.on_position);
    let (l, r) = edges(&whole)?;
    let contrast = bar_contrast(&whole, l, r);
    let mx = xa as f64 + 0.5 * (l + r);
    // Centres of the halves, at their mean rows, relative to the
    // perpendicular through the whole bar's centre.
    let halves = (edges(&mean_prof(ya, ymid)), edges(&mean_prof(ymid, yb)));
    let both_halves = halves.0.is_some() && halves.1.is_some();
    let lean = lean_of(
        halves.0.map(|(a, b)| 0.5 * (a + b)),
        halves.1.map(|(a, b)| 0.5 * (a + b)),
        (yb - ya) as f64,
    );
    let perp = fit::Line {
        a: mx + line.b * ym,
        b: -line.b,
    };
    let axis = if lean.abs() * (yb - ya) as f64 > 1.5 {
        fit::Line {
            a: mx - (perp.b + lean) * ym,
            b: perp.b + lean,
        }
    } else {
        perp
    };
    let width_px = r - l;
    // Tip: the apex of the half-level contour, corrected for the blur's
    // pull on a rounded end (`side_row::tip_crossing`, the row's median
    // shape and blur applied by the caller).
    // The window is re-centred on the first crossing and widened by the
    // blur (`side_row::tip_crossing_recentred`); it stays above the
    // bar's measured middle part and inside the frame.
    let sample = |d: f64, y: f64| sign * plane.bilinear(axis.y_at(y) + d, y);
    let limits = (0.0, ya as f64);
    // The blob's top is a guess: where the bar still stands over the
    // backlight beside it by half its contrast further up its axis than
    // the end's window reaches, the end is sought there (`climb_to_end`).
    let climbed = climb_to_end(&sample, tip_guess, 0.5 * width_px, 0.5 * contrast);
    let tip_guess = if tip_guess - climbed > win.tip_half {
        climbed
    } else {
        tip_guess
    };
    let tip = tip_crossing_recentred(&sample, tip_guess, win.tip_half, 0.5 * width_px, limits)?;
    Some(BarEnd {
        axis,
        width_px,
        tip,
        contrast,
        both_halves,
    })
}

/// The lean (px across per px along) of a bar whose middle part, `len` px
/// long, has its upper and lower halves centred at `upper` and `lower`.
/// A half holds half the rows of the whole, so its mean profile is √2
/// noisier, and under a dim backlight its edges were sometimes not found
/// where the whole bar's were (Rust 890 535, 890 666, 900 864: noise
/// 9–14 DN, blur 2–2.4 px); the pin was then dropped and read missing.
/// With a half lost the bar is taken as standing perpendicular, as an
/// unbent pin does. The lost half's reflection of the other through the
/// whole's centre was tried first: one half's noise doubled passed the
/// lean test, the axis leaned off the pin, and good Python pins read high
/// (590 048).
fn lean_of(upper: Option<f64>, lower: Option<f64>, len: f64) -> f64 {
    match (upper, lower) {
        (Some(a), Some(b)) => (b - a) / (0.5 * len),
        _ => 0.0,
    }
}

/// How far up its axis (y px, from `guess`) a bar of half-width `half_w`
/// stands over the backlight beside it by `rise` (sign space: bar high):
/// the mean of three samples across its middle, less the mean of the
/// backlight on both sides (5 px past its edges, clear of a blur of
/// 2.5 px), over each next two rows, must stay over it. A thin bar under
/// blur, its upper part dimmed by the backlight's gradient, can fall under
/// the silhouette's coarse threshold there, and its blob then starts half
/// way down (Rust 1 010 713: a clean 1 × 2, the blob's top 65 px under the
/// pin's end; its end was sought inside the bar and the good pin read
/// short, 1.38 mm for 3.60). Measured against the backlight beside it, not
/// a level: under vignetting the backlight above a pin's end can be as
/// dark as the bar (Rust 965 147).
fn climb_to_end(sample: &dyn Fn(f64, f64) -> f32, guess: f64, half_w: f64, rise: f32) -> f64 {
    let (d, out) = (0.3 * half_w, half_w + 5.0);
    let at = |y: f64| {
        let bar = (sample(-d, y) + sample(0.0, y) + sample(d, y)) / 3.0;
        bar - 0.5 * (sample(-out, y) + sample(out, y))
    };
    let mut y = guess.floor();
    while y >= 2.0 && 0.5 * (at(y - 1.0) + at(y - 2.0)) > rise {
        y -= 1.0;
    }
    y.min(guess)
}

/// The bar's interior (inside its half-level edges `l`, `r`, a pixel in
/// from each) above the background beside it (2–7 px out on both sides).
fn bar_contrast(prof: &[f32], l: f64, r: f64) -> f32 {
    let n = prof.len() as i64;
    let (li, ri) = (l.ceil() as i64 + 1, r.floor() as i64 - 1);
    let mut inner: Vec<f32> = (li..=ri)
        .filter(|&i| (0..n).contains(&i))
        .map(|i| prof[i as usize])
        .collect();
    if inner.is_empty() {
        inner.push(prof[((l + r) * 0.5).round().clamp(0.0, (n - 1) as f64) as usize]);
    }
    let mut out: Vec<f32> = ((l.floor() as i64 - 7)..=(l.floor() as i64 - 2))
        .chain((r.ceil() as i64 + 2)..=(r.ceil() as i64 + 7))
        .filter(|&i| (0..n).contains(&i))
        .map(|i| prof[i as usize])
        .collect();
    if out.is_empty() {
        return 0.0;
    }
    median_f32(&mut inner) - median_f32(&mut out)
}

/// What a pin of this row looks like: the medians of the bars found on
/// the blobs (width, contrast), the recipe's height and pitch at the
/// image's scale, and how far from the nominal height an end is sought.
#[derive(Debug, Clone, Copy)]
pub(super) struct RowRef {
    pub width_px: f64,
    pub contrast: f32,
    /// Nominal height above the edge, px.
    pub height_px: f64,
    pub pitch_px: f64,
    /// Half-width of the end's first search window, px.
    pub tip_half: f64,
}

/// Least contrast of a pin found on a second look, as a fraction of the
/// row's: the mean profile over the pin's middle part averages the noise
/// down (over 20+ rows), so a pin whose blob broke up under noise keeps
/// nearly its full contrast there, and an empty position (backlight only)
/// stays near zero.
pub(super) const LOOK_AGAIN_MIN_CONTRAST: f32 = 0.5;

/// A second look at a position where no blob made a bar: a pin whose
/// silhouette broke up in the noise at the coarse threshold (or merged
/// with a dim patch) is still a bar in the mean profile across its middle
/// part. The pin is measured where the lattice puts it, `foot` its point
/// on the housing edge, with its end sought around the nominal height;
/// kept only when it has the row's width and most of its contrast.
pub(super) fn look_again<P: Px>(
    plane: &Plane<P>,
    sign: f32,
    line: &fit::Line,
    foot: (f64, f64),
    row: &RowRef,
) -> Option<BarEnd> {
    let (h_nom_px, pitch_px) = (row.height_px, row.pitch_px);
    let hw = 0.5 * row.width_px;
    // The pin stands perpendicular to the edge: its columns are taken at
    // the middle part's height (where `measure_bar` centres its window).
    let (sn, cs) = line.b.atan().sin_cos();
    let xc = foot.0 + sn * 0.425 * h_nom_px;
    let win = BarWindow {
        x0: xc - hw,
        x1: xc + hw,
        tip_guess: foot.1 - cs * h_nom_px,
        gap: (xc - 0.5 * pitch_px, xc + 0.5 * pitch_px),
        margin: hw.max(9.0),
        tip_half: row.tip_half.min(0.25 * h_nom_px),
        on_position: true,
    };
    let e = measure_bar(plane, sign, line, &win)?;
    let w_ok = e.width_px >= 0.5 * row.width_px && e.width_px <= 1.6 * row.width_px;
    let c_ok = row.contrast > 0.0 && e.contrast >= LOOK_AGAIN_MIN_CONTRAST * row.contrast;
    // No blob stood here, so nothing but this profile says a pin does:
    // both halves must show it (a structure at a truly missing pin's
    // position whose one half gave edges read bent, Python 650 354).
    (w_ok && c_ok && e.both_halves).then_some(e)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A bar (sign space: bar high) 8 px wide whose end is at y = 20, its
    /// upper half (y < 60) at 0.6 of its contrast of 100 over a backlight
    /// of 0: from a guess at 60 the climb reaches the end within a pixel.
    /// The same bar under a backlight that darkens above its end to the
    /// bar's own level within 10 px (vignetting; sign space: rising to
    /// 100): the climb stops at the end, not in the dark backlight above.
    #[test]
    fn the_climb_reaches_a_dimmed_bars_end_and_not_the_dark_backlight_above() {
        for dark_above in [false, true] {
            let sample = move |d: f64, y: f64| -> f32 {
                let back = if dark_above && y < 20.0 {
                    (100.0 * (20.0 - y) / 10.0).min(100.0) as f32
                } else {
                    0.0
                };
                if d.abs() <= 4.0 && y >= 20.0 {
                    back.max(if y < 60.0 { 60.0 } else { 100.0 })
                } else {
                    back
                }
            };
            let y = climb_to_end(&sample, 60.0, 4.0, 50.0);
            assert!((y - 20.0).abs() <= 1.0, "dark above {dark_above}: {y}");
        }
    }

    /// A dark pin 8 px wide on a housing (backlight 200, silhouette 60),
    /// its end at the pixel boundary y = 30 (29.5 in pixel-centre
    /// coordinates, as the edge at row 70 is 69.5), a faint shadow of the
    /// same size (a quarter of the contrast) and an empty position.
    fn scene() -> (usize, usize, Vec<u8>) {
        let (w, h) = (160usize, 100usize);
        let mut d = vec![200u8; w * h];
        for y in 0..h {
            for x in 0..w {
                let pin = (30..38).contains(&x) && y >= 30;
                let shadow = (120..128).contains(&x) && y >= 30;
                d[y * w + x] = if y >= 70 || pin {
                    60
                } else if shadow {
                    165
                } else {
                    200
                };
            }
        }
        (w, h, d)
    }

    #[test]
    fn a_second_look_finds_the_pin_where_the_lattice_puts_it() {
        let (w, h, d) = scene();
        let plane = Plane { w, h, data: &d[..] };
        let line = fit::Line { a: 69.5, b: 0.0 };
        let row = RowRef {
            width_px: 8.0,
            contrast: 140.0,
            height_px: 40.0,
            pitch_px: 45.0,
            tip_half: 8.0,
        };
        // The lattice's position 1.5 px off the pin's centre (33.5).
        let e = look_again(&plane, -1.0, &line, (35.0, 69.5), &row).expect("the pin is there");
        assert!((e.width_px - 8.0).abs() < 0.05, "{e:?}");
        assert!((e.axis.y_at(50.0) - 33.5).abs() < 0.05, "{e:?}");
        assert!((e.tip.tip_y(0.0, 0.0) - 29.5).abs() < 0.05, "{e:?}");
        assert!((e.contrast - 140.0).abs() < 1.0, "{e:?}");
        // Nothing stands at x = 78: the position stays empty.
        assert!(look_again(&plane, -1.0, &line, (78.0, 69.5), &row).is_none());
        // A shadow of a quarter of the row's contrast is not a pin.
        assert!(look_again(&plane, -1.0, &line, (123.5, 69.5), &row).is_none());
    }
}
