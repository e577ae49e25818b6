//! The side view's pin row placed along the housing's edge: the pitch
//! (the recipe's scale, or the spacings refined from the pins' width), the
//! wrong-part test on the row as a whole, the 1-D lattice and its window
//! among the recipe's columns (the housing block's centre deciding when
//! the pins cannot), and the robust offset (and scale) fit. Kept apart
//! from `side.rs` (the pipeline).

use super::error::VisionError;
use super::grid;
use super::recipe::Recipe;
use super::side_row::{refine_pitch, robust_offset_scale, row_fits_lattice};

/// Up to this many pins on the row, at the recipe's scale, the housing
/// block's centre places it (their own offset follows one pin's bend).
const FEW_PINS: usize = 3;

/// Where the row stands: the along-row offset `a_u` (px) of the part
/// frame's origin, the scale `s` (px/mm), the fit's inliers and RMS (px),
/// whether the housing decided the window, and the pitch (px).
pub(super) struct RowPlacement {
    pub a_u: f64,
    pub s: f64,
    pub inliers: Vec<bool>,
    pub rms: f64,
    pub ambiguous: bool,
    pub pitch_px: f64,
}

/// Places the row of bars at along-row coordinates `bars_u` (px, widths
/// `bars_w`) on the recipe's columns; `fixed_s` is the recipe's scale
/// (px/mm), `(u_h0, u_h1)` the housing block's coarse ends along the row
/// (px) and `housing_u` the same measured at full resolution, when both
/// are.
pub(super) fn place_row(
    recipe: &Recipe,
    bars_u: &[f64],
    bars_w: &[f64],
    fixed_s: Option<f64>,
    (u_h0, u_h1): (f64, f64),
    housing_u: Option<(f64, f64)>,
    warnings: &mut Vec<String>,
) -> Result<RowPlacement, VisionError> {
    let part = recipe.part_number.clone();
    let pitch_mm = recipe.pitch_mm[0];
    // 5. Along-row placement: 1-D lattice, housing anchor, robust fit.
    // Spacings along the row between neighbouring bars (a missing pin
    // leaves a double spacing, so neither a median nor the smallest spacing
    // is the pitch on its own).
    let spacings: Vec<f64> = {
        let mut u: Vec<f64> = bars_u.to_vec();
        u.sort_by(|a, b| a.total_cmp(b));
        u.windows(2).map(|w| w[1] - w[0]).collect()
    };
    let pitch_px = match fixed_s {
        Some(s) => pitch_mm * s,
        None => {
            // The pins' own width is a second ruler (pin_mm is known): it
            // sets the scale of the spacings, which then refine it.
            let mut w: Vec<f64> = bars_w.to_vec();
            let width_px = grid::median(&mut w).unwrap_or(f64::NAN);
            let prior = pitch_mm * width_px / recipe.pin_mm;
            let mut d = spacings.clone();
            match refine_pitch(&spacings, prior).or_else(|| grid::median(&mut d)) {
                Some(p) => p,
                None if prior.is_finite() && prior > 0.0 => {
                    warnings.push(format!(
                        "one pin only: mm_per_px taken from its width ({:.5}), not from the pitch",
                        recipe.pin_mm / width_px
                    ));
                    prior
                }
                None => {
                    return Err(VisionError::NoPins {
                        part: part.clone(),
                        msg: "cannot estimate mm_per_px: no pin width measured".into(),
                    });
                }
            }
        }
    };
    // Reject the wrong part: bars off the recipe's lattice, judged on the
    // row as a whole (a pin bent towards its neighbour changes two
    // spacings, not the lattice).
    let u_bars: Vec<f64> = bars_u.to_vec();
    let ok_off_px = fixed_s.map_or(0.0, |s| recipe.tolerance.position_mm * s);
    if fixed_s.is_some() && !row_fits_lattice(&u_bars, pitch_px, ok_off_px.max(0.15 * pitch_px)) {
        let mut d = spacings.clone();
        let md = grid::median(&mut d).unwrap_or(f64::NAN);
        return Err(VisionError::WrongPart {
            part,
            msg: format!(
                "pins are {md:.1} px apart, the recipe expects {pitch_px:.1} px ({pitch_mm} mm at {} mm/px)",
                recipe.mm_per_px.unwrap_or(f64::NAN)
            ),
        });
    }
    let u_ref = bars_u[0];
    let (mut cph, mut sph) = (0.0, 0.0);
    for &u in bars_u {
        let a = (u - u_ref) / pitch_px;
        cph += (2.0 * std::f64::consts::PI * a).cos();
        sph += (2.0 * std::f64::consts::PI * a).sin();
    }
    let phase = sph.atan2(cph) / (2.0 * std::f64::consts::PI);
    let lat_a = |u: f64| (u - u_ref) / pitch_px - phase;
    let idx: Vec<Option<i64>> = bars_u
        .iter()
        .map(|&u| {
            let a = lat_a(u);
            ((a - a.round()).abs() < 0.3).then_some(a.round() as i64)
        })
        .collect();
    let members: Vec<(i64, i64)> = idx.iter().flatten().map(|&a| (a, 0)).collect();
    let anchor = Some((lat_a(0.5 * (u_h0 + u_h1)), 0.0));
    let skipped = |r: u32, c: u32| recipe.is_skipped(r, c);
    let placement =
        grid::place_window(&members, 1, recipe.cols, &skipped, anchor).ok_or_else(|| {
            VisionError::NoPins {
                part: part.clone(),
                msg: "no pins on a common pitch".into(),
            }
        })?;
    let col_of = |a: i64| -> Option<u32> {
        let c = a - placement.col0;
        (c >= 0 && c < recipe.cols as i64 && !recipe.is_skipped(0, c as u32)).then_some(c as u32)
    };
    let outside = idx
        .iter()
        .flatten()
        .filter(|&&a| col_of(a).is_none())
        .count();
    if outside >= 2 && outside * 4 >= placement.score {
        return Err(VisionError::WrongPart {
            part,
            msg: format!(
                "{outside} pins stand outside the recipe's {} positions ({} inside): a different part?",
                recipe.cols, placement.score
            ),
        });
    }
    if placement.ambiguous {
        warnings.push("pins alone do not place the grid (an end pin missing): the housing block's centre decided".into());
    }
    let (mut nn, mut uu) = (Vec::new(), Vec::new());
    for (&u, i) in bars_u.iter().zip(&idx) {
        if let Some(c) = i.and_then(col_of) {
            nn.push(recipe.nominal_uv_mm(0, c).0);
            uu.push(u);
        }
    }
    // One pin on the grid and no mm_per_px: the scale from the pitch
    // estimate (which then came from the pin's width).
    let fit_s = fixed_s.or((nn.len() < 2).then_some(pitch_px / pitch_mm));
    let (mut a_u, s, inl, mut rms) =
        robust_offset_scale(&nn, &uu, fit_s, 0.1).ok_or_else(|| VisionError::NoPins {
            part: part.clone(),
            msg: "cannot fit the pin row (need two pins to estimate mm_per_px)".into(),
        })?;
    // Two or three pins at the recipe's scale: their offset follows any
    // one pin's bend (a 1 × 2 splits it in halves, each inside the
    // tolerance: Rust 1 050 910, 1 050 378, 920 533, 1 000 591); the
    // housing block, centred on the pin field, places the row instead
    // where its two ends are measured and agree with the pins within a
    // quarter pitch.
    if let (Some(_), Some((l, r))) = (fixed_s, housing_u)
        && (2..=FEW_PINS).contains(&nn.len())
    {
        let a_h = 0.5 * (l + r);
        if (a_h - a_u).abs() <= 0.25 * pitch_px {
            a_u = a_h;
            let ss: f64 = nn
                .iter()
                .zip(&uu)
                .map(|(n, u)| (u - a_u - s * n).powi(2))
                .sum();
            rms = (ss / nn.len() as f64).sqrt();
            warnings.push(format!(
                "{} pins: the row placed on the housing block's centre (its ends measured at full resolution)",
                nn.len()
            ));
        }
    }
    Ok(RowPlacement {
        a_u,
        s,
        inliers: inl,
        rms,
        ambiguous: placement.ambiguous,
        pitch_px,
    })
}
