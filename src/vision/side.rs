//! Side view: a back-lit silhouette across the pin row. The housing is a
//! dark block at the bottom, pins are dark bars standing on it.
//!
//! Pipeline: coarse block-mean image → Otsu threshold → per column the
//! longest silhouette run; its top is the housing edge where no pin stands
//! (pins reach higher), so a RANSAC line through the run tops finds the
//! edge → sub-pixel edge points at full resolution (half-level crossing of
//! each column's profile between backlight and housing) and a robust line
//! → bars above the edge: axis from per-row coverage centroids, tip from
//! the half-level crossing along the axis, height = perpendicular distance
//! from the tip to the edge → pins placed along the row by a 1-D lattice
//! and a robust offset (and scale) fit, the housing block's centre
//! deciding when pins alone cannot → missing / bent / short / high, and
//! extras (anything dark above the housing that is not a pin).

use super::InspectOptions;
use super::backlight;
use super::detect;
use super::detect::check_contrast;
use super::error::VisionError;
use super::fit::{self, Similarity};
use super::gray::{Coarse, ImageInfo, Plane, Px};
use super::grid;
use super::label;
use super::measure::{self, Localiser, Roi};
use super::recipe::Recipe;
use super::result::*;
use super::side_bar::{BarEnd, BarWindow, RowRef, look_again, measure_bar};
use super::side_edge::{
    BarMask, body_x_range, clear_step, drop_steep_tops, edge_profile, housing_ends_u,
    level_edge_line, run_tops, solid_block,
};
use super::side_end::{EndAt, row_end_offset};
use super::side_place::place_row;
use super::side_row::{first_rise, median_f32};
use super::tip_levels;

/// A bar (pin candidate) measured at full resolution.
#[derive(Debug, Clone)]
struct Bar {
    tip: (f64, f64),
    /// Median silhouette width across the bar, px.
    width_px: f64,
    /// Along-row coordinate of the tip (projection on the edge direction), px.
    u_px: f64,
    height_px: f64,
}

/// Least contrast of a dust shadow, as a fraction of the silhouette's
/// (backlight to housing): dust is opaque, noise clumps are not.
const DUST_MIN_CONTRAST: f64 = 0.4;
/// ... and its core (the mean over a disc of the smallest area the extras
/// rule counts, at its centre) must stand `CORE_SIGMAS` of that mean's
/// noise above this fraction: the level of a noise clump's mask is
/// selected by the noise, its core's is not. In a dim, noisy backlight
/// (Rust 840 901: silhouette 38 DN, σ 14 DN) one clump of 23 read 0.45 by
/// its mask and 0.20 ± 0.09 by its core; opaque dust fills its core (a
/// small one, blurred, still about half way).
const DUST_MIN_CORE: f64 = 0.5 * DUST_MIN_CONTRAST;

/// How one attempt at a side view reads the silhouette (see
/// [`inspect_side`]).
#[derive(Clone, Copy)]
struct Attempt {
    /// The housing edge's runs read on the coarse image's 3 × 3 mean.
    smooth_runs: bool,
    /// Least depth the silhouette's level is taken at when the backlight
    /// is flattened (share of the backlight).
    min_depth: f32,
}

/// Inspects one side-view image. When the housing is not found (or no pin
/// on what was taken for it, or its edge steeper than a side view's), it
/// is sought again:
/// - with the runs read on the coarse image's 3 × 3 mean: noise pricks
///   holes in a low-contrast housing and speckles a dim band above it, and
///   the band's tops then outnumbered the block's (965 068, contrast
///   0.37). Smoothed first, a mottled backlight's patches outran a thin
///   housing (Python 590 048);
/// - with the backlight flattened as if the silhouette were at least the
///   envelope's least contrast deep: a small part in a large frame (Rust
///   1 050 098: the housing 0.4 % of a 3.5 Mpx frame) is not the frame's
///   darkest percent, and when the cubic backlight leaves a band (a
///   gradient that levels off beyond the part) the band's 13 % was taken
///   for the silhouette's level, kept out of the flattening as "surely
///   silhouette", and its edge, 70° off, for the housing's.
///
/// The first attempt that succeeds stands; when none does, the first's
/// error is reported.
pub fn inspect_side<P: Px>(
    recipe: &Recipe,
    plane: &Plane<P>,
    info: ImageInfo,
    full_scale: f32,
    opts: &InspectOptions,
) -> Result<Inspection, VisionError> {
    let _ = opts;
    let least = super::envelope::CONTRAST.0 as f32;
    let attempts = [(false, 0.0), (true, 0.0), (false, least)].map(|(s, d)| Attempt {
        smooth_runs: s,
        min_depth: d,
    });
    let [first, rest @ ..] = attempts;
    let first_err = match inspect_side_runs(recipe, plane, info.clone(), full_scale, first) {
        Err(e) if housing_not_read(&e) => e,
        r => return r,
    };
    for a in rest {
        match inspect_side_runs(recipe, plane, info.clone(), full_scale, a) {
            Err(e) if housing_not_read(&e) => {}
            r => return r,
        }
    }
    Err(first_err)
}

/// The start of the error for a housing edge steeper than a side view's.
const TILTED_EDGE: &str = "housing edge tilted";

/// Whether an attempt failed on the housing (none, no pin on it, or an
/// edge too steep), which another attempt may read; a row of pins that
/// does not fit the recipe is a judgement, not a failure to read.
fn housing_not_read(e: &VisionError) -> bool {
    match e {
        VisionError::NoHousing(_) | VisionError::NoPins { .. } => true,
        VisionError::WrongPart { msg, .. } => msg.starts_with(TILTED_EDGE),
        _ => false,
    }
}

/// One [`Attempt`] at a side view.
fn inspect_side_runs<P: Px>(
    recipe: &Recipe,
    plane: &Plane<P>,
    info: ImageInfo,
    full_scale: f32,
    attempt: Attempt,
) -> Result<Inspection, VisionError> {
    let Attempt {
        smooth_runs,
        min_depth,
    } = attempt;
    let part = recipe.part_number.clone();
    let mut warnings = Vec::new();
    // Silhouette is bright in `sign` space.
    let sign = recipe.polarity.sign();
    // Without `mm_per_px` nothing says how wide a pin is until the bars
    // are found: a fine coarse factor (2) then, and the width measured from
    // the bars below (never a guess from the image's size).
    let mut pin_px_prior = recipe.mm_per_px.map(|m| recipe.pin_mm / m);
    let k = pin_px_prior.map_or(2, detect::coarse_factor);
    let mut coarse = Coarse::build(plane, k, sign);
    check_contrast(&coarse, full_scale)?;
    // The full-resolution steps below are compared with the raw range.
    let (r_lo, r_hi) = detect::robust_range(&coarse.data);
    let contrast = r_hi - r_lo;
    let (cw, ch) = (coarse.w, coarse.h);
    // Back-lit silhouette: the backlight divided out (vignetting and
    // gradients leave it at one level everywhere), under heavy noise a box
    // no wider than a pin first; and the silhouette's depth below the
    // backlight (share of it).
    let (t, depth) = if sign < 0.0 {
        let widest = pin_px_prior.map_or(3, |p| (p / k as f64) as usize);
        backlight::silhouette_threshold_flat(plane, &mut coarse, sign, widest, min_depth)
    } else {
        (detect::otsu(&coarse.data, cw, ch), None)
    };
    let fg = |x: usize, y: usize| coarse.at(x, y) > t;

    // 1. Housing edge, coarse: top of the longest silhouette run per column.
    // A run must stand clear of the noise (a few coarse pixels; half a tip
    // when the scale says how wide a tip is), not a share of the frame: a
    // thin housing block in a tall frame is still the housing, and the
    // robust line below takes stray runs as outliers.
    let min_run = pin_px_prior.map_or(3, |p| {
        ((0.5 * p / k as f64) as usize).clamp(3, (ch / 40).max(3))
    });
    let smooth = smooth_runs.then(|| super::morph::box_mean(&coarse.data, cw, ch, 1));
    let fg_s = |x: usize, y: usize| match &smooth {
        Some(m) => m[y * cw + x] > t,
        None => fg(x, y),
    };
    let tops = run_tops(cw, ch, &fg_s, min_run);
    let tops = drop_steep_tops(&tops);
    let no_housing =
        |msg: &str| VisionError::NoHousing(format!("{msg} (recipe {part}, side view)"));
    if tops.len() < 8 {
        return Err(no_housing(
            "no dark block along the image: is this a side view?",
        ));
    }
    let (coarse_line, pool) = match level_edge_line(tops) {
        Ok(found) => found,
        Err(None) => return Err(no_housing("no straight top edge")),
        Err(Some(tilt)) => {
            return Err(VisionError::WrongPart {
                part,
                msg: format!("{TILTED_EDGE} {tilt:.1}°: not a side view of this part?"),
            });
        }
    };
    let inl_cols: Vec<usize> = pool
        .iter()
        .zip(&coarse_line.inlier)
        .filter(|(_, i)| **i)
        .map(|(p, _)| p.0 as usize)
        .collect();
    if inl_cols.len() < 6 {
        return Err(no_housing("too few columns on the housing's top edge"));
    }
    let (hx0_c, hx1_c) = (
        *inl_cols.iter().min().unwrap_or(&0),
        *inl_cols.iter().max().unwrap_or(&0),
    );
    let mut col_is_edge = vec![false; cw];
    for &c in &inl_cols {
        col_is_edge[c] = true;
    }

    // 2. Pins and dust: silhouette above the edge.
    let edge_c = |x: f64| coarse_line.line.y_at(x);
    let lab = label::label(cw, ch, |x, y| {
        fg(x, y) && (y as f64) < edge_c(x as f64) - 1.5
    });
    let mut bar_blobs = Vec::new();
    let mut dust_blobs = Vec::new();
    let touches_edge =
        |b: &label::Blob| (b.x_min..=b.x_max).any(|x| b.y_max as f64 >= edge_c(x as f64) - 3.5);
    // A bar stands on the edge and is taller than wide by a good part of
    // the recipe's height-to-width ratio (a fixed "twice as high as wide"
    // lost the envelope's stubby pins, 1.5 mm high on 0.9 mm: every pin
    // then was dust and the part "no pin standing"). The label stops 1.5
    // coarse pixels above the edge, so that much is added back.
    let bar_aspect =
        (0.6 * recipe.tolerance.height_mm.unwrap_or(0.0) / recipe.pin_mm).clamp(0.8, 2.0);
    let tall = |b: &label::Blob, w: f64| b.height() as f64 + 1.5 >= bar_aspect * w;
    let pin_px_prior = match pin_px_prior.take() {
        Some(p) => p,
        None => {
            // Median width of the bars standing on the edge, in
            // full-resolution pixels.
            let mut w: Vec<f64> = lab
                .blobs
                .iter()
                .filter(|b| touches_edge(b) && tall(b, b.width() as f64))
                .map(|b| (b.area as f64 / b.height() as f64) * k as f64)
                .collect();
            grid::median(&mut w).unwrap_or(8.0).max(3.0)
        }
    };
    // Nor is a bar a speck: at full resolution (k = 1 for pins about 7 px
    // wide) single noise pixels just above the edge stood on it and were
    // "tall", and as bars they cut the room beside their neighbours
    // (below) short, so those pins were lost (820 515: four ok pins
    // missing). A pin's silhouette is about a pin wide at the half level.
    // And a pin's end lies inside the frame: silhouette reaching the
    // frame's top border (backlight along a border the flattening took for
    // silhouette, 820 466) is no pin; it is judged as dust on the untouched
    // image. Nor, with the scale known, is a blob two pitches wide (965 068:
    // a dim band joined to the tips was a "bar" of 486 tips; a width
    // measured without the scale, 3 px on Python 590 048, cut every pin).
    let widest = match recipe.mm_per_px {
        Some(_) => 2.0 * pin_px_prior * recipe.pitch_mm[0] / recipe.pin_mm / k as f64,
        None => f64::INFINITY,
    };
    let pin_like = |b: &label::Blob| {
        let w = b.width() as f64;
        b.y_min > 0 && w >= 0.5 * pin_px_prior / k as f64 && w <= widest
    };
    for b in &lab.blobs {
        if touches_edge(b)
            && pin_like(b)
            && tall(b, (b.width() as f64).min(pin_px_prior / k as f64))
        {
            bar_blobs.push(b.clone());
        } else {
            dust_blobs.push(b.clone());
        }
    }

    // 3. Sub-pixel housing edge: half-level crossings in columns clear of bars.
    let kf = k as f64;
    let bodies: Vec<(u32, u32)> = bar_blobs
        .iter()
        .map(|b| body_x_range(b, &lab.runs))
        .collect();
    let near_bar = |xf: f64| {
        bodies.iter().any(|&(x0, x1)| {
            xf >= (x0 as f64 - 1.0) * kf - 2.0 && xf <= (x1 as f64 + 2.0) * kf + 2.0
        })
    };
    let half = (3 * k + 4) as i64;
    let mut edge_pts = Vec::new();
    let x_lo = (hx0_c + 1) * k;
    let x_hi = hx1_c.saturating_sub(1) * k;
    let step = (k / 2).max(1);
    let span = step;
    let mut xi = x_lo;
    while xi < x_hi.min(plane.w) {
        let xf = xi as f64;
        let c = (xi / k).min(cw - 1);
        let clear = !near_bar(xf) && !near_bar(xf - span as f64) && !near_bar(xf + span as f64);
        if col_is_edge[c] && clear {
            let (_, yc) = coarse.to_full(0.0, edge_c(c as f64));
            let y0 = (yc.round() as i64 - half).max(0) as usize;
            let y1 = ((yc.round() as i64 + half) as usize).min(plane.h - 1);
            if y1 > y0 + 6 {
                let prof = edge_profile(plane, sign, xi, (y0, y1), span, coarse_line.line.b);
                let mut top: Vec<f32> = prof[..3].to_vec();
                let mut bot: Vec<f32> = prof[prof.len() - 3..].to_vec();
                let (lo, hi) = (median_f32(&mut top), median_f32(&mut bot));
                if clear_step(lo, hi, contrast, depth)
                    && let Some(f) = first_rise(&prof, 0.5 * (lo + hi))
                {
                    edge_pts.push((xf, y0 as f64 + f));
                }
            }
        }
        xi += step;
    }
    let edge = fit::robust_line(&edge_pts, 1.0)
        .ok_or_else(|| no_housing("top edge not measurable between the pins"))?;
    let line = edge.line;
    let phi = line.b.atan();
    let (sn, cs) = phi.sin_cos();

    // 4. Bars at full resolution: axis and tip.
    let mut ends = Vec::new();
    let mut bars = Vec::new();
    for b in &bar_blobs {
        let x0f = b.x_min as f64 * kf;
        let x1f = (b.x_max as f64 + 1.0) * kf - 1.0;
        // Room on each side for the blurred edge and the background beside
        // it (`bar_edges` wants 5+ px of background), but never past the
        // middle of the gap to the next bar.
        let margin = (0.5 * pin_px_prior).max(9.0);
        let (mut gap_l, mut gap_r) = (f64::NEG_INFINITY, f64::INFINITY);
        for o in &bar_blobs {
            let (o0, o1) = (o.x_min as f64 * kf, (o.x_max as f64 + 1.0) * kf - 1.0);
            if o1 < x0f {
                gap_l = gap_l.max(0.5 * (o1 + x0f));
            } else if o0 > x1f {
                gap_r = gap_r.min(0.5 * (o0 + x1f));
            }
        }
        let win = BarWindow {
            x0: x0f,
            x1: x1f,
            tip_guess: b.y_min as f64 * kf,
            gap: (gap_l, gap_r),
            margin,
            tip_half: 2.0 * kf + 4.0,
            on_position: false,
        };
        if let Some(e) = measure_bar(plane, sign, &line, &win) {
            ends.push(e);
        }
    }
    // One part, one focus: the row's median end shape and blur.
    let mut cc: Vec<f64> = ends.iter().map(|e| e.tip.c).collect();
    let mut ss: Vec<f64> = ends.iter().map(|e| e.tip.sigma).collect();
    let (c_row, s_row) = (
        grid::median(&mut cc).unwrap_or(0.0),
        grid::median(&mut ss).unwrap_or(0.0),
    );
    // Where the apex lies from each bar's band crossing: the row's mean
    // end image fitted by a blurred end model (`side_end`); the old
    // contour correction where that cannot be measured.
    let end_offset = {
        let mut w: Vec<f64> = ends.iter().map(|e| e.width_px).collect();
        let hw0 = 0.5 * grid::median(&mut w).unwrap_or(0.0);
        let at: Vec<EndAt> = ends
            .iter()
            .map(|e| EndAt {
                axis: e.axis,
                y_band: e.tip.y_band,
                base: line.y_at(e.axis.y_at(e.tip.y_band)),
            })
            .collect();
        row_end_offset(plane, sign, &at, hw0, s_row)
    };
    let to_bar = |e: &BarEnd| {
        let ty = match end_offset {
            Some(a) => e.tip.y_band + a,
            None => e.tip.tip_y(c_row, s_row),
        };
        let tip = (e.axis.y_at(ty), ty);
        Bar {
            tip,
            width_px: e.width_px,
            u_px: cs * tip.0 + sn * tip.1,
            height_px: line.height_above(tip.0, tip.1),
        }
    };
    for e in &ends {
        bars.push(to_bar(e));
    }
    // Housing block ends along the row (coarse extent refined to the line).
    let (hx0, hx1) = (hx0_c as f64 * kf, (hx1_c as f64 + 1.0) * kf - 1.0);
    let u_h0 = cs * hx0 + sn * line.y_at(hx0);
    let u_h1 = cs * hx1 + sn * line.y_at(hx1);
    let pitch_mm = recipe.pitch_mm[0];
    let fixed_s = recipe.mm_per_px.map(|m| 1.0 / m);
    // Nothing stands on a housing that was found: every pin is missing.
    // That is a failed connector, not an image that cannot be judged (a
    // part with its pins knocked off must count against the yield). The
    // positions are placed centred on the housing block at the recipe's
    // scale, or, without `mm_per_px`, with the block taken as `cols`
    // pitches long (no pin is there to measure the scale from; said in a
    // note).
    let placed = if bars.is_empty() {
        if !solid_block((hx0_c, hx1_c.min(cw.saturating_sub(1))), ch, &edge_c, &fg) {
            return Err(VisionError::NoPins {
                part,
                msg: "no pin standing on the housing".into(),
            });
        }
        let s = match fixed_s {
            Some(s) => s,
            None => {
                let s = (u_h1 - u_h0).abs() / (recipe.cols as f64 * pitch_mm);
                warnings.push(format!(
                    "no pin standing on the housing: positions placed along the housing block, mm_per_px taken as its length over {} pitches ({:.5})",
                    recipe.cols,
                    1.0 / s
                ));
                s
            }
        };
        if !(s.is_finite() && s > 0.0) {
            return Err(VisionError::NoPins {
                part,
                msg: "no pin standing on the housing".into(),
            });
        }
        let a_u = 0.5 * (u_h0 + u_h1);
        Some((a_u, s, Vec::new(), 0.0, true, pitch_mm * s))
    } else {
        None
    };
    let (a_u, s, inl, rms, ambiguous, pitch_px) = match placed {
        Some(p) => p,
        None => {
            let us: Vec<f64> = bars.iter().map(|b| b.u_px).collect();
            let ws: Vec<f64> = bars.iter().map(|b| b.width_px).collect();
            let reach = 4.0 * kf + 8.0;
            let h = housing_ends_u(plane, sign, &line, (cs, sn), (hx0, hx1), reach);
            let h = h.0.zip(h.1);
            let r = place_row(recipe, &us, &ws, fixed_s, (u_h0, u_h1), h, &mut warnings)?;
            (r.a_u, r.s, r.inliers, r.rms, r.ambiguous, r.pitch_px)
        }
    };
    let mm_per_px = 1.0 / s;
    if fixed_s.is_none() && !bars.is_empty() {
        warnings.push(format!(
            "mm_per_px estimated from the pitch: {mm_per_px:.5}"
        ));
    }
    // Part frame: origin on the edge line at along-row coordinate a_u.
    // The edge line's points satisfy −sn·x + cs·y = c_e.
    let c_e = -sn * 0.0 + cs * line.a;
    let (ox, oy) = (cs * a_u - sn * c_e, sn * a_u + cs * c_e);
    let sim = Similarity {
        s,
        theta: phi,
        tx: ox,
        ty: oy,
    };

    // 6. Per position.
    let tol = &recipe.tolerance;
    let h_nom = tol.height_mm.unwrap_or(0.0);
    let h_tol = tol.height_tol_mm.unwrap_or(f64::INFINITY);
    let positions = recipe.positions();
    let mut used = vec![false; bars.len()];
    // The row's pins as found on the blobs: the reference for a second
    // look where no blob made a bar.
    let row_ref = (ends.len() >= 2).then(|| {
        let mut w: Vec<f64> = ends.iter().map(|e| e.width_px).collect();
        let mut c: Vec<f32> = ends.iter().map(|e| e.contrast).collect();
        RowRef {
            width_px: grid::median(&mut w).unwrap_or(0.0),
            contrast: median_f32(&mut c),
            height_px: h_nom * s,
            pitch_px,
            tip_half: 2.0 * kf + 4.0 + 2.0 * (h_tol * s).min(0.25 * h_nom * s),
        }
    });
    let mut second_look: Vec<(BarEnd, Bar)> = Vec::new();
    let mut pins = Vec::with_capacity(positions.len());
    for &(row, col) in &positions {
        let u_nom = recipe.nominal_uv_mm(row, col).0;
        let (nx, ny) = sim.apply(u_nom, -h_nom);
        let u_nom_px = a_u + s * u_nom;
        let best = bars
            .iter()
            .enumerate()
            .filter(|(i, b)| !used[*i] && (b.u_px - u_nom_px).abs() < 0.4 * pitch_px)
            .min_by(|a, b| {
                (a.1.u_px - u_nom_px)
                    .abs()
                    .total_cmp(&(b.1.u_px - u_nom_px).abs())
            });
        let mut pr = PinResult::missing(row, col, (nx, ny));
        let found = match best {
            Some((i, b)) => {
                used[i] = true;
                Some(b.clone())
            }
            None => row_ref.as_ref().and_then(|rr| {
                let foot = sim.apply(u_nom, 0.0);
                let e = look_again(plane, sign, &line, foot, rr)?;
                let b = to_bar(&e);
                ((b.u_px - u_nom_px).abs() < 0.4 * pitch_px).then(|| {
                    second_look.push((e, b.clone()));
                    b
                })
            }),
        };
        if let Some(b) = found {
            let du = (b.u_px - u_nom_px) * mm_per_px;
            let h = b.height_px * mm_per_px;
            pr.x_px = Some(b.tip.0);
            pr.y_px = Some(b.tip.1);
            pr.dx_mm = Some(du);
            pr.offset_mm = Some(du.abs());
            pr.height_mm = Some(h);
            pr.width_ratio = Some(b.width_px * mm_per_px / recipe.pin_mm);
            pr.status = PinStatus::side(tol, du, h);
            pr.reason = match pr.status {
                PinStatus::Bent => Some(format!(
                    "offset along the row {:.3} mm = {:.2} × position_mm {}",
                    du.abs(),
                    du.abs() / tol.position_mm,
                    tol.position_mm
                )),
                PinStatus::Short | PinStatus::High => Some(format!(
                    "height {h:.3} mm is {:.3} mm {} nominal {h_nom} = {:.2} × height_tol_mm {h_tol}",
                    (h - h_nom).abs(),
                    if h < h_nom { "below" } else { "above" },
                    (h - h_nom).abs() / h_tol
                )),
                _ => None,
            };
        } else {
            pr.reason = Some(format!(
                "no pin standing within {:.1} px (0.4 pitch) of the position along the row",
                0.4 * pitch_px
            ));
        }
        pins.push(pr);
    }

    // 7. Extras: dust and unassigned bars above the housing.
    let tip_px = recipe.pin_mm * recipe.pin_mm * s * s;
    let rule = &recipe.extras;
    let mut extras = Vec::new();
    let mut ignored = Vec::new();
    for (i, b) in bars.iter().enumerate() {
        if !used[i] {
            let ar = b.width_px * b.height_px / tip_px;
            extras.push(ExtraResult {
                x_px: b.tip.0,
                y_px: b.tip.1,
                area_ratio: ar,
                distance_mm: None,
                ignored_because: None,
                contrast_ratio: None,
                snr: None,
                reason: Some(format!(
                    "a pin-like bar ({:.2} mm high) that no grid position claims",
                    b.height_px * mm_per_px
                )),
            });
        }
    }
    let (margin, dilate) = super::measure::tip_window(pin_px_prior);
    // The bars' coarse pixels: a dust blob whose measured shadow lies on
    // (or against) one is that bar, not dust.
    let on_bar = BarMask::new(cw, ch, &bar_blobs, &lab.runs);
    let reach = ((0.25 * pin_px_prior).max(2.0) / kf).ceil() as usize;
    for d in &dust_blobs {
        let roi = Roi::around_coarse(d, kf, margin, plane.w, plane.h);
        let seed = coarse.to_full(d.cx, d.cy);
        let Some(m) =
            measure::measure_blob(plane, sign, roi, seed, Localiser::Coverage, dilate, None)
        else {
            continue;
        };
        // At full resolution (coarse factor 1 for thin pins) noise pixels
        // beside a pin pass the threshold on their own; the window around
        // one takes in the pin, and its measure was a piece of that pin
        // (py 550 034: fifteen "dust" shadows along six pins, noise 14 DN
        // on a 100 DN silhouette). Dust lies clear of the pins.
        // Likewise a speck just above the housing's edge measures the
        // housing (py 550 034).
        let on_edge = m.y >= line.y_at(m.x) - (0.25 * pin_px_prior).max(2.0);
        // Likewise the pieces of a pin found on a second look.
        let on_found = second_look.iter().any(|(e, b)| {
            m.y >= b.tip.1 - 0.25 * pin_px_prior
                && (m.x - e.axis.y_at(m.y)).abs() <= 0.5 * e.width_px + 0.25 * pin_px_prior
        });
        if on_bar.near(m.x / kf, m.y / kf, reach) || on_edge || on_found {
            continue;
        }
        let ar = m.area_px / tip_px;
        // Dust is opaque: its shadow stands most of the way from the
        // backlight to the housing's level, and clear of the noise. A
        // clump of noise in a dim, noisy backlight does neither.
        let c_ratio = ((m.hi - m.lo) / contrast.max(1e-6)) as f64;
        let snr = if m.noise > 0.0 {
            ((m.hi - m.lo) as f64) * (m.mask_px as f64).sqrt() / m.noise as f64
        } else {
            f64::INFINITY
        };
        let e = ExtraResult {
            x_px: m.x,
            y_px: m.y,
            area_ratio: ar,
            distance_mm: None,
            ignored_because: None,
            contrast_ratio: Some(c_ratio),
            snr: snr.is_finite().then_some(snr),
            reason: None,
        };
        let core_r = (rule.min_area_ratio * tip_px / std::f64::consts::PI).sqrt();
        let core = tip_levels::disc_mean(plane, sign, (m.x, m.y), core_r)
            .map_or(0.0, |v| (v - m.lo as f64) / contrast.max(1e-6) as f64);
        let core_sd = m.noise as f64
            / (std::f64::consts::PI * core_r * core_r).max(1.0).sqrt()
            / contrast.max(1e-6) as f64;
        if c_ratio < DUST_MIN_CONTRAST || snr < tip_levels::MIN_SNR {
            if ar >= rule.min_area_ratio {
                ignored.push(ExtraResult {
                    ignored_because: Some(format!(
                        "faint: contrast {c_ratio:.2} of the silhouette's (needs {DUST_MIN_CONTRAST}), SNR {snr:.1} (needs {})",
                        tip_levels::MIN_SNR
                    )),
                    ..e
                });
            }
        } else if core - tip_levels::CORE_SIGMAS * core_sd < DUST_MIN_CORE {
            if ar >= rule.min_area_ratio {
                ignored.push(ExtraResult {
                    ignored_because: Some(format!(
                        "its core reaches {core:.2} ± {core_sd:.2} (noise σ) of the silhouette's contrast, not {} σ above {DUST_MIN_CORE}: a clump of noise, not an opaque shadow",
                        tip_levels::CORE_SIGMAS
                    )),
                    ..e
                });
            }
        } else if ar >= rule.min_area_ratio {
            extras.push(ExtraResult {
                reason: Some(format!(
                    "dust above the housing: area {ar:.2} of a tip ≥ {}, contrast {c_ratio:.2} of the silhouette's, {} above the noise",
                    rule.min_area_ratio,
                    if snr.is_finite() {
                        format!("{snr:.0} σ")
                    } else {
                        "far".to_string()
                    }
                )),
                ..e
            });
        } else if ar >= 0.5 * rule.min_area_ratio {
            ignored.push(ExtraResult {
                ignored_because: Some(format!(
                    "area {:.2} of a tip, below {}",
                    ar, rule.min_area_ratio
                )),
                ..e
            });
        }
    }

    let (hu0, hu1) = ((u_h0 - a_u) * mm_per_px, (u_h1 - a_u) * mm_per_px);
    let depth_mm = (plane.h as f64 - line.y_at(0.5 * (hx0 + hx1))).max(0.0) * mm_per_px;
    let housing = Housing {
        corners_px: [
            sim.apply(hu0, 0.0),
            sim.apply(hu1, 0.0),
            sim.apply(hu1, depth_mm),
            sim.apply(hu0, depth_mm),
        ],
        extent_mm: [hu0, hu1, 0.0, depth_mm],
        edge: Some(EdgeLine {
            a: line.a,
            b: line.b,
            rms_px: edge.rms,
            points: edge.inlier.iter().filter(|b| **b).count(),
        }),
    };
    let grid = GridFit {
        transform: sim,
        centre_px: (ox, oy),
        rotation_deg: phi.to_degrees(),
        mm_per_px,
        mm_per_px_estimated: fixed_s.is_none(),
        fit_inliers: inl.iter().filter(|b| **b).count(),
        fit_rms_px: rms,
        anchored_by_housing: ambiguous,
    };
    let found = Findings {
        pins,
        extras,
        ignored,
    };
    Ok(Inspection::judged(
        recipe,
        info,
        grid,
        Some(housing),
        found,
        warnings,
    ))
}

#[cfg(test)]
#[path = "side_tests.rs"]
mod tests;
