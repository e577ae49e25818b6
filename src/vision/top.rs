//! Top view: pin tips seen down the insertion axis.
//!
//! Pipeline: coarse search ([`super::detect`]) → sub-pixel measurement of
//! every blob at full resolution ([`super::measure`]) → lattice by medians
//! ([`super::grid`]) → housing outline by edge profiles along the lattice
//! axes (anchors the grid when pins alone cannot, bounds where extras count)
//! → robust similarity fit ([`super::fit`]) → assignment of blobs to grid
//! positions → verdicts (missing, damaged, bent) and extras.

use super::InspectOptions;
use super::detect::{self, CoarseSearch};
use super::disc::disc_energy;
use super::end_level::DiscLevel;
use super::error::VisionError;
use super::fit::{self, Similarity};
use super::gray::{ImageInfo, Plane, Px};
use super::grid::{self, LatticeError};
use super::housing::find_housing;
use super::measure::{self, Roi};
use super::recipe::Recipe;
use super::result::*;
use super::scale::ScaleStart;
use super::tip_levels::{
    BLUR_RELATIVE, Candidate, LocalLevels, MIN_SNR, MIN_TIP_CONTRAST, OFF_HOLE, TIP_LIKE_AREA,
    area_ratio_of, contrast_ratio, core_contrast, dim_tip_on_position, housing_not_tip,
    neighbour_medians, snr_of, tip_disc_radius,
};
use super::top_candidates::{
    add_faint_debris, assign_to_positions, faint_pass, last_passes, measure_candidates,
    use_blobs_at,
};
use super::top_first_fit::FitPoints;
use super::top_not_proven;
use super::top_outline::{Outline, chosen_note};

/// Inspects one top-view image.
pub fn inspect_top<P: Px>(
    recipe: &Recipe,
    plane: &Plane<P>,
    info: ImageInfo,
    full_scale: f32,
    opts: &InspectOptions,
) -> Result<Inspection, VisionError> {
    inspect_top_with(recipe, plane, info, full_scale, opts, ScaleStart::Search)
}

/// [`inspect_top`], the scale (when the recipe has no `mm_per_px`) started
/// as `start` says.
pub(crate) fn inspect_top_with<P: Px>(
    recipe: &Recipe,
    plane: &Plane<P>,
    info: ImageInfo,
    full_scale: f32,
    opts: &InspectOptions,
    start: ScaleStart,
) -> Result<Inspection, VisionError> {
    let sign = recipe.polarity.sign();
    let part = recipe.part_number.clone();
    let mut warnings = Vec::new();
    let (pin_px0, estimate) = match (recipe.mm_per_px, start) {
        (Some(m), _) => (recipe.pin_mm / m, None),
        (None, ScaleStart::TipWidth(w)) => (w, None),
        (None, _) => {
            let e = super::scale::estimate(plane, sign, recipe, full_scale)?;
            (e.pin_px, Some(e))
        }
    };
    let s0 = pin_px0 / recipe.pin_mm;
    let n_pos = Some(recipe.positions().len());
    let mut cs = detect::coarse_search(plane, sign, pin_px0, None, n_pos);
    detect::check_contrast(&cs.coarse, full_scale)?;
    let tip_px0 = recipe.tip_area_mm2() * s0 * s0;
    let candidates = |cs: &CoarseSearch| -> Vec<Candidate> {
        measure_candidates(plane, sign, cs, pin_px0, opts)
            .into_iter()
            .map(|(m, roi, seed)| {
                let a = m.area_px / tip_px0;
                let pinlike = TIP_LIKE_AREA.contains(&a) && m.elongation < 3.0 && !m.touches_border;
                Candidate {
                    m,
                    pinlike,
                    roi,
                    seed,
                }
            })
            .collect()
    };
    let mut cands = candidates(&cs);
    // Too few tips: a second pass with the wider smoothing box
    // ([`faint_pass`]).
    if let Some(cs2) = faint_pass(plane, sign, recipe, pin_px0, &candidates, &mut cands) {
        cs = cs2;
    }
    // Still no tip, or no two a pitch apart: the last passes
    // ([`last_passes`]).
    let pitch_px0 = (recipe.pitch_mm[0] * s0, recipe.pitch_mm[1] * s0);
    if let Some((cs_last, cands_last)) =
        last_passes(plane, sign, pin_px0, pitch_px0, n_pos, &candidates, &cands)
    {
        cs = cs_last;
        cands = cands_last;
    }
    let pin_pts: Vec<(f64, f64)> = cands
        .iter()
        .filter(|c| c.pinlike)
        .map(|c| (c.m.x, c.m.y))
        .collect();
    let too_faint = super::scale_period::too_faint(estimate.as_ref());
    if pin_pts.is_empty() {
        return Err(VisionError::NoPins {
            part,
            msg: format!(
                "no tip-sized {} blob found (expected tips about {:.0} px wide; wrong recipe, view or polarity?){too_faint}",
                if sign > 0.0 { "bright" } else { "dark" },
                pin_px0
            ),
        });
    }
    let (px_mm, py_mm) = (recipe.pitch_mm[0], recipe.pitch_mm[1]);
    let pitch_px = Some((px_mm * s0, py_mm * s0));
    let lattice = |pitch_px| {
        grid::estimate_lattice(&pin_pts, pitch_px, py_mm / px_mm, recipe.rows, recipe.cols)
    };
    let lat = match lattice(pitch_px) {
        Ok(l) => l,
        // An estimated scale is a prior from the image, not a fact: when
        // the tip-sized blobs form a lattice at another spacing, that
        // lattice is the evidence (the fit then takes the scale from it).
        Err(LatticeError::PitchMismatch { .. })
            if recipe.mm_per_px.is_none() && lattice(None).is_ok() =>
        {
            lattice(None).map_err(|_| VisionError::NoPins {
                part: part.clone(),
                msg: "cannot estimate the pitch".into(),
            })?
        }
        Err(LatticeError::NoPoints) => {
            return Err(VisionError::NoPins {
                part,
                msg: "cannot estimate the pitch: no two pins side by side".into(),
            });
        }
        Err(LatticeError::PitchMismatch {
            expected_px,
            found_px,
        }) => {
            return Err(VisionError::WrongPart {
                part,
                msg: format!(
                    "pins are {found_px:.1} px apart, the recipe expects {expected_px:.1} px ({} mm at {} mm/px)",
                    if recipe.cols > 1 { px_mm } else { py_mm },
                    recipe.mm_per_px.unwrap_or(f64::NAN)
                ),
            });
        }
    };
    // An estimated scale is a prior: when the tips agree on another
    // lattice that explains more of them, and their areas do not speak
    // against its scale (`scale::areas_allow`), theirs is taken.
    // With `mm_per_px` given the pitch is known: no search.
    let consensus = recipe.mm_per_px.is_none().then(|| {
        let alt = grid::lattice_by_consensus(&pin_pts, &lat, recipe.rows, recipe.cols)?;
        let pinlike = cands.iter().filter(|c| c.pinlike);
        let areas: Vec<f64> = pinlike.map(|c| c.m.area_px / tip_px0).collect();
        super::scale::areas_allow(&areas, alt.px / lat.px).then_some(alt)
    });
    let lat = consensus.flatten().unwrap_or(lat);
    // Lattice members (pin-like blobs on lattice nodes), read again on
    // the lattice refitted to them.
    let pin_like: Vec<Option<(f64, f64)>> = cands
        .iter()
        .map(|c| c.pinlike.then_some((c.m.x, c.m.y)))
        .collect();
    let (lat, idx) = grid::members_refined(lat, &pin_like);
    let members: Vec<(i64, i64)> = idx.iter().flatten().map(|i| (i.a, i.b)).collect();
    if members.is_empty() {
        return Err(VisionError::NoPins {
            part,
            msg: "no pins on a common grid".into(),
        });
    }
    let a_span = (
        members.iter().map(|m| m.0).min().unwrap_or(0),
        members.iter().map(|m| m.0).max().unwrap_or(0),
    );
    let b_span = (
        members.iter().map(|m| m.1).min().unwrap_or(0),
        members.iter().map(|m| m.1).max().unwrap_or(0),
    );
    let housing_lat = find_housing(
        &cs.coarse,
        &lat,
        a_span,
        b_span,
        pin_px0,
        0.15 * cs.tip_contrast,
    );
    let anchor = housing_lat.map(|h| (0.5 * (h[0] + h[1]), 0.5 * (h[2] + h[3])));
    let skipped = |r: u32, c: u32| recipe.is_skipped(r, c);
    let mut placement = grid::place_window(&members, recipe.rows, recipe.cols, &skipped, anchor)
        .ok_or_else(|| VisionError::NoPins {
            part: part.clone(),
            msg: "cannot place the grid".into(),
        })?;
    let mut by_evidence = false;
    if placement.ambiguous {
        let (rows, cols) = (recipe.rows, recipe.cols);
        if let Some(p) = super::top_window::settle_by_evidence(
            &cs,
            &lat,
            &members,
            (rows, cols),
            &skipped,
            &placement,
            pin_px0,
        ) {
            placement = p;
            by_evidence = true;
        }
    }
    let in_window = |i: &grid::LatticeIndex| -> Option<(u32, u32)> {
        let (c, r) = (i.a - placement.col0, i.b - placement.row0);
        (c >= 0
            && r >= 0
            && c < recipe.cols as i64
            && r < recipe.rows as i64
            && !recipe.is_skipped(r as u32, c as u32))
        .then_some((r as u32, c as u32))
    };
    let outside = idx
        .iter()
        .flatten()
        .filter(|i| in_window(i).is_none())
        .count();
    if outside >= 2 && outside * 4 >= placement.score {
        return Err(VisionError::WrongPart {
            part,
            msg: format!(
                "{} pins lie on the grid but outside the recipe's {} × {} positions ({} inside): a different part?",
                outside, recipe.rows, recipe.cols, placement.score
            ),
        });
    }
    if by_evidence {
        warnings.push("pins alone do not place the grid (an end column or end pin missing): the tips' contrast at the window's places decided".into());
    } else if placement.ambiguous {
        if housing_lat.is_some() {
            warnings.push("pins alone do not place the grid (an end column or end pin missing): the housing centre decided".into());
        } else {
            warnings.push("pins alone do not place the grid and the housing was not found: grid centred on the pins found".into());
        }
    }

    // Robust fit of the nominal grid to the pins (damaged tips left out).
    let [ta_lo, ta_hi] = recipe.tip_area();
    let in_win: Vec<(usize, (u32, u32))> = idx
        .iter()
        .enumerate()
        .filter_map(|(ci, i)| i.as_ref().and_then(in_window).map(|rc| (ci, rc)))
        .collect();
    let one_tip = start == ScaleStart::SearchOrOneTip;
    let points = FitPoints::of(&cands, &in_win, recipe, tip_px0, one_tip);
    let fixed = recipe.mm_per_px.map(|_| s0);
    let lat_s = lat.px / px_mm;
    let centre_lat = (
        placement.col0 as f64 + (recipe.cols as f64 - 1.0) / 2.0,
        placement.row0 as f64 + (recipe.rows as f64 - 1.0) / 2.0,
    );
    let c0 = lat.to_image(centre_lat.0, centre_lat.1);
    let init = Similarity {
        s: fixed.unwrap_or(lat_s),
        theta: lat.theta,
        tx: c0.0,
        ty: c0.1,
    };
    let (mut sim, mut inliers, mut rms) = points.first_fit(recipe, init, fixed, &mut warnings);
    let FitPoints {
        model,
        image,
        one_area,
    } = points;
    if fixed.is_none() && model.len() < 2 && one_area.is_none() {
        return Err(VisionError::NoPins {
            part,
            msg: format!("cannot estimate mm_per_px from fewer than two pins{too_faint}"),
        });
    }
    let (u_half, v_half) = (
        (recipe.cols as f64 - 1.0) / 2.0 * px_mm,
        (recipe.rows as f64 - 1.0) / 2.0 * py_mm,
    );
    let outline = Outline {
        plane,
        lat: &lat,
        housing_lat,
        half_mm: (u_half, v_half),
        pin_pitch_min: if recipe.rows > 1 {
            px_mm.min(py_mm)
        } else {
            px_mm
        },
        position_mm: recipe.tolerance.position_mm,
        fixed,
    };
    let by_housing = outline.for_few_pins(&sim, &model, &image).map(|(h, note)| {
        warnings.push(note);
        h
    });
    sim = by_housing.unwrap_or(sim);
    let mut by_outline = false;
    if by_housing.is_none()
        && let Some(f) = outline.consensus(&sim, &model, &image)
    {
        warnings.push(chosen_note(&f));
        (sim, inliers, rms) = (f.sim, f.inlier.iter().filter(|b| **b).count(), f.rms_px);
        by_outline = true;
    }
    // Most pins off the recipe's grid: the robust fit's scale grows with
    // them and its RMS becomes a sizeable part of the pitch (real parts on
    // the interop set stay below 0.4 px, < 1 % of the pitch). It is still a
    // failed connector (counting it as an error would hide a crushed part
    // from the yield), but the reason is worth saying.
    let pitch_px = (if recipe.cols > 1 { px_mm } else { py_mm }) * sim.s;
    if rms.is_finite() && rms > 0.05 * pitch_px {
        warnings.push(format!(
            "the pins do not sit on the recipe's grid (fit RMS {rms:.1} px = {:.0} % of the pitch): a different part, or a crushed one?",
            100.0 * rms / pitch_px
        ));
    }
    let mut mm_per_px = 1.0 / sim.s;
    if fixed.is_none() {
        let from = if one_area.is_some() {
            "the tip's area"
        } else {
            "the pitch"
        };
        warnings.push(format!("mm_per_px estimated from {from}: {mm_per_px:.5}"));
    }
    let tip_px = recipe.tip_area_mm2() * sim.s * sim.s;

    // Assign blobs to positions: nearest first, pin-like blobs preferred.
    let positions = recipe.positions();
    let mut nominal: Vec<(f64, f64)> = positions
        .iter()
        .map(|&(r, c)| {
            let (u, v) = recipe.nominal_uv_mm(r, c);
            sim.apply(u, v)
        })
        .collect();
    let min_pitch_px = if recipe.rows > 1 {
        px_mm.min(py_mm)
    } else {
        px_mm
    } * sim.s;
    let r_assign = 0.4 * min_pitch_px;
    let (mut pos_cand, mut cand_used) = assign_to_positions(&nominal, &cands, tip_px, r_assign);
    // Local levels: every intact tip found tells the tip level and the
    // background level (housing) at its place; vignetting and gradients
    // change both slowly, so the nearest tips say what a tip must look like
    // anywhere on the part.
    let bg_img = cs.coarse.with_data(cs.background.clone());
    let bg_at = |x: f64, y: f64| {
        let (cx, cy) = bg_img.from_full(x, y);
        bg_img.bilinear(cx, cy)
    };
    // Blur comparable to the tip leaves no plateau to take the tip level
    // from, and the coverage area then grows with the blur: the tips'
    // energy (which blur only spreads) is compared with the neighbouring
    // tips' instead, and the note says so.
    let pin_px = recipe.pin_mm * sim.s;
    let assigned: Vec<usize> = pos_cand
        .iter()
        .flatten()
        .copied()
        .filter(|&ci| cands[ci].pinlike)
        .collect();
    let mut sig: Vec<f64> = assigned.iter().map(|&ci| cands[ci].m.edge_sigma).collect();
    let blur_sigma = grid::median(&mut sig).unwrap_or(0.0);
    let blurred = assigned.len() >= 3 && blur_sigma > BLUR_RELATIVE * pin_px;
    if blurred {
        warnings.push(format!(
            "tips blurred (edge σ ≈ {blur_sigma:.1} px on {pin_px:.1} px tips): tip areas judged by their energy against the neighbouring tips'"
        ));
    }
    // Under blur, the centres of intact tips from a model of the tip in
    // its clearance hole (`blur_tip`), then the grid fitted again to them.
    let tip_model = super::blur_tip::TipModel {
        plane,
        sign,
        recipe,
        blur_sigma,
        min_pitch_px,
    };
    let (refined, part_shape) = if blur_sigma > super::blur_tip::MIN_SIGMA_PX {
        let intact: Vec<(usize, usize)> = pos_cand
            .iter()
            .enumerate()
            .filter_map(|(pi, c)| c.map(|ci| (pi, ci)))
            .filter(|&(_, ci)| {
                let a = area_ratio_of(&cands, &assigned, ci, tip_px, blurred);
                // A blurred tip whose coverage blob runs into the housing's
                // blurred light touches its window and so is not `pinlike`;
                // its centroid is the one most pulled outward, and the
                // model (which samples its own window about the hole) is
                // what measures it.
                cands[ci].m.elongation < 3.0 && a >= ta_lo && a <= ta_hi
            })
            .collect();
        tip_model.refine_centres(&sim, &nominal, &intact, &mut cands)
    } else {
        (Vec::new(), None)
    };
    if refined.len() >= 2 {
        let model: Vec<(f64, f64)> = refined
            .iter()
            .map(|&(pi, _)| {
                let (r, c) = positions[pi];
                recipe.nominal_uv_mm(r, c)
            })
            .collect();
        let image: Vec<(f64, f64)> = refined
            .iter()
            .map(|&(_, ci)| (cands[ci].m.x, cands[ci].m.y))
            .collect();
        let tau = recipe.tolerance.position_mm * sim.s;
        if let Some(f) = fit::consensus_similarity(&model, &image, fixed, Some(sim), 0.1, tau) {
            // The housing read once stays the datum if it is not read again.
            let f = match outline
                .for_few_pins(&f.sim, &model, &image)
                .map(|p| p.0)
                .or(by_housing)
            {
                Some(h) => fit::RobustFit { sim: h, ..f },
                None => match outline.consensus(&f.sim, &model, &image) {
                    Some(o) => {
                        if !by_outline {
                            warnings.push(chosen_note(&o));
                        }
                        o
                    }
                    None => f,
                },
            };
            sim = f.sim;
            inliers = f.inlier.iter().filter(|b| **b).count();
            rms = f.rms_px;
            for (pi, &(r, c)) in positions.iter().enumerate() {
                let (u, v) = recipe.nominal_uv_mm(r, c);
                nominal[pi] = sim.apply(u, v);
            }
            if fixed.is_none() {
                mm_per_px = 1.0 / sim.s;
                if let Some(w) = warnings
                    .iter_mut()
                    .find(|w| w.starts_with("mm_per_px estimated"))
                {
                    *w = format!("mm_per_px estimated from the pitch: {mm_per_px:.5}");
                }
            }
        }
    }
    // Under blur, a tip's energy is taken inside a fixed disc around its
    // centre (`tip_disc_radius`) against the housing's level there (the
    // coarse background, holes filled), not the half-level mask's extent or
    // per-tip levels, which noise clumps bias (seventh round, docs/vision.md);
    // a plane through the tips' surrounds where that background was raised
    // toward a bright fixture (`surround`), and the ends' own (`end_level`).
    let disc_r = tip_disc_radius(recipe.pin_shape, pin_px, blur_sigma, min_pitch_px);
    let around: Vec<_> = assigned
        .iter()
        .map(|&ci| &cands[ci].m)
        .map(|m| (m.x, m.y, m.hi, m.lo))
        .collect();
    let at = super::end_level::Positions {
        nominal: &nominal,
        own: pos_cand
            .iter()
            .map(|c| c.map(|ci| cands[ci].m.lo))
            .collect(),
        tips: &around,
        pitch: min_pitch_px,
    };
    let disc_level = DiscLevel::new(blurred, &at, bg_at, r_assign);
    warnings.extend(disc_level.note());
    let level_at = |x, y| disc_level.at(x, y).unwrap_or_else(|| bg_at(x, y));
    if blurred {
        for &ci in pos_cand.iter().flatten() {
            let m = &mut cands[ci].m;
            m.energy = disc_energy(plane, sign, (m.x, m.y), disc_r, level_at(m.x, m.y));
        }
    }
    let area_of =
        |cands: &[Candidate], ci: usize| area_ratio_of(cands, &assigned, ci, tip_px, blurred);
    let refs: Vec<(f64, f64, f32, f32)> = pos_cand
        .iter()
        .flatten()
        .map(|&ci| (ci, &cands[ci]))
        .filter(|(ci, c)| {
            let a = area_of(&cands, *ci);
            c.pinlike && a >= ta_lo && a <= ta_hi
        })
        .map(|(_, c)| (c.m.x, c.m.y, c.m.hi, bg_at(c.m.x, c.m.y)))
        .collect();
    let levels = LocalLevels { refs };
    let (_, dilate) = super::measure::tip_window(pin_px0);
    // Second look at each empty position, with the locally expected
    // contrast: a dim tip the coarse threshold missed (a dark corner, low
    // gain) is found here; what is there otherwise is said in the reason.
    let mut empty_look: Vec<Option<(f64, f64)>> = vec![None; positions.len()];
    let mut dim_tip = vec![false; positions.len()];
    // Energy ratios of whole tips read through noise (`top_noisy`).
    let mut by_energy: Vec<Option<f64>> = vec![None; positions.len()];
    let noisy = super::top_noisy::EmptyLook {
        plane,
        sign,
        recipe,
        sim: &sim,
        blur_sigma,
        min_pitch_px,
        disc_r,
        pin_px,
    };
    let recut = super::top_off_hole::Recut {
        plane,
        sign,
        half: (0.9 * pin_px + 2.0).min(0.5 * min_pitch_px),
        r_assign,
        tip_px,
        levels: &levels,
        loc: opts.localiser,
        dilate,
    };
    let first_look: Vec<bool> = pos_cand.iter().map(Option::is_some).collect();
    for pi in 0..positions.len() {
        if first_look[pi] {
            // A tip measured with the structure it touches, off its hole or
            // of no tip-like area (`top_off_hole`). Where the model
            // measured it (`refined`), the model's measure stands.
            let (nx, ny) = nominal[pi];
            if let Some(ci) = pos_cand[pi].filter(|&ci| {
                let m = &cands[ci].m;
                !cands[ci].pinlike
                    && ((m.x - nx).hypot(m.y - ny) > OFF_HOLE * pin_px
                        || !TIP_LIKE_AREA.contains(&(m.area_px / tip_px)))
            }) && let Some(mut m) = recut.tip(&cands[ci], (nx, ny))
            {
                cands[ci].pinlike = true;
                if !refined.iter().any(|r| r.0 == pi) {
                    if blurred {
                        let e = disc_energy(plane, sign, (m.x, m.y), disc_r, level_at(m.x, m.y));
                        m.energy = e;
                    }
                    cands[ci].m = m;
                }
            }
            continue;
        }
        let (nx, ny) = nominal[pi];
        let Some((t_exp, b_exp)) = levels.expected(nx, ny) else {
            continue;
        };
        let roi = Roi::around(nx, ny, nx, ny, recut.half, plane.w, plane.h);
        // A faint tip's half-level mask runs into the window's border
        // through noise: separated from it as the extras are.
        let look = |apart| {
            measure::measure_blob_split(
                plane,
                sign,
                roi,
                (nx, ny),
                opts.localiser,
                dilate,
                None,
                apart,
            )
        };
        let Some(mut m) = look(false).and_then(|m| {
            if m.touches_border {
                look(true).or(Some(m))
            } else {
                Some(m)
            }
        }) else {
            continue;
        };
        if blurred {
            m.energy = disc_energy(plane, sign, (m.x, m.y), disc_r, level_at(m.x, m.y));
        }
        let rho = contrast_ratio(m.hi, t_exp, b_exp);
        let snr = snr_of(&m);
        let d = (m.x - nx).hypot(m.y - ny);
        empty_look[pi] = Some((rho, snr));
        let tip_bright = rho >= MIN_TIP_CONTRAST
            && snr >= MIN_SNR
            && d < r_assign
            && !m.touches_border
            && m.area_px / tip_px >= 0.15;
        // A damaged tip smaller than the intact ones (and without their
        // dome) peaks under the tip-bright level once blurred; where a
        // missing pin leaves only its clearance hole, a compact blob on
        // the position with a tip-like core is that tip (`dim_tip_on_position`).
        let dim = !tip_bright
            && !m.touches_border
            && m.area_px / tip_px >= 0.15
            && dim_tip_on_position(
                rho,
                core_contrast(plane, sign, (m.x, m.y), 0.15 * tip_px, t_exp, b_exp),
                snr,
                d / pin_px,
                m.elongation,
            );
        // A tip-bright look whose mask noise clumps carried to the window's
        // border: its disc energy and the blurred-tip model decide
        // (`top_noisy`).
        let looks_tip = rho >= MIN_TIP_CONTRAST && snr >= MIN_SNR;
        let whole = (blurred && looks_tip && !tip_bright && !dim && m.touches_border)
            .then(|| neighbour_medians(&cands, &assigned, (nx, ny), None))
            .flatten()
            .and_then(|(me, _)| noisy.whole_tip((nx, ny), m.noise, level_at(nx, ny), me?));
        if let Some(((x, y), ratio)) = whole {
            (m.x, m.y) = (x, y);
            by_energy[pi] = Some(ratio);
        }
        if tip_bright || dim || whole.is_some() {
            dim_tip[pi] = dim;
            use_blobs_at(&cands, &mut cand_used, (m.x, m.y), 0.5 * pin_px);
            let pinlike = m.elongation < 3.0;
            cands.push(Candidate {
                m,
                pinlike,
                roi,
                seed: (nx, ny),
            });
            cand_used.push(true);
            pos_cand[pi] = Some(cands.len() - 1);
        }
    }
    // Every other tip on a position (the second look's finds, tips whose
    // noisy first area kept them from the model) is measured as the intact
    // ones were: by the model, within the shape those gave (`blur_tip`).
    if let Some(shape) = part_shape {
        let later: Vec<_> = (0..positions.len())
            .filter(|&pi| !dim_tip[pi] && !refined.iter().any(|r| r.0 == pi))
            .filter_map(|pi| pos_cand[pi].map(|ci| (pi, ci)))
            .collect();
        tip_model.refine_in_part(&sim, &nominal, &later, &mut cands, shape);
    }

    let tol = &recipe.tolerance;
    let mut pins = Vec::with_capacity(positions.len());
    for (pi, &(row, col)) in positions.iter().enumerate() {
        let (nx, ny) = nominal[pi];
        let mut pr = PinResult::missing(row, col, (nx, ny));
        // A blob that is not tip-like and lies outside the tip's clearance
        // hole is a piece of the housing's edge or chamfer band by an empty
        // position, not this pin (a bent tip is intact, so tip-like).
        let off_hole = |ci: usize| {
            let m = &cands[ci].m;
            !cands[ci].pinlike && (m.x - nx).hypot(m.y - ny) > OFF_HOLE * pin_px
        };
        if let Some(ci) = pos_cand[pi].filter(|&ci| off_hole(ci)) {
            let m = &cands[ci].m;
            pr.reason = Some(format!(
                "no tip at the position: the nearest blob, {:.2} tip widths away, is not tip-like (area {:.2} × nominal, elongation {:.1}) and lies outside the tip's clearance hole",
                (m.x - nx).hypot(m.y - ny) / pin_px,
                m.area_px / tip_px,
                m.elongation
            ));
        } else if let Some((rho, why)) =
            pos_cand[pi].and_then(|ci| housing_not_tip(&cands[ci], &levels, tip_px))
        {
            pr.contrast_ratio = Some(rho);
            pr.reason = Some(why);
        } else if let Some(ci) = pos_cand[pi] {
            let m = &cands[ci].m;
            let (du, dv) = sim.to_part_axes(m.x - nx, m.y - ny);
            let (du, dv) = (du * mm_per_px, dv * mm_per_px);
            let off = du.hypot(dv);
            let ar = by_energy[pi].unwrap_or_else(|| area_of(&cands, ci));
            pr.x_px = Some(m.x);
            pr.y_px = Some(m.y);
            pr.dx_mm = Some(du);
            pr.dy_mm = Some(dv);
            pr.offset_mm = Some(off);
            pr.area_ratio = Some(ar);
            pr.elongation = Some(m.elongation);
            pr.contrast_ratio = levels
                .expected(m.x, m.y)
                .map(|(t, b)| contrast_ratio(m.hi, t, b));
            pr.status = if ar < ta_lo || ar > ta_hi {
                pr.reason = Some(format!(
                    "tip area {ar:.2} × nominal, outside tip_area [{ta_lo}, {ta_hi}]{}{}",
                    pr.contrast_ratio
                        .map(|r| format!("; level {r:.2} of the local tip level"))
                        .unwrap_or_default(),
                    if dim_tip[pi] {
                        " (a dim tip on its position, found by the second look)"
                    } else {
                        ""
                    }
                ));
                PinStatus::Damaged
            } else if off > tol.position_mm {
                pr.reason = Some(format!(
                    "offset {off:.3} mm = {:.2} × position_mm {} (dx {du:+.3}, dy {dv:+.3} mm)",
                    off / tol.position_mm,
                    tol.position_mm
                ));
                PinStatus::Bent
            } else {
                PinStatus::Ok
            };
        } else {
            pr.reason = Some(match empty_look[pi] {
                Some((rho, snr)) => {
                    pr.contrast_ratio = Some(rho);
                    format!(
                        "no tip within {r_assign:.1} px of the position: there the level reaches {rho:.2} of the local tip level ({snr:.1} σ above the noise; a tip needs ≥ {MIN_TIP_CONTRAST} and ≥ {MIN_SNR} σ)"
                    )
                }
                None => format!("no tip within {r_assign:.1} px of the position"),
            });
        }
        pins.push(pr);
    }
    if blurred {
        let u: Vec<Option<f64>> = pos_cand
            .iter()
            .map(|c| c.map(|ci| top_not_proven::centre_sigma_px(&cands[ci].m, pin_px) * mm_per_px))
            .collect();
        let notes = top_not_proven::judge(&mut pins, [ta_lo, ta_hi], tol.position_mm, &u);
        warnings.extend(notes);
    }

    // Housing in the part frame (or the grid's extent as a stand-in).
    let housing = outline.rect(&sim).map(|(corners_px, extent_mm)| Housing {
        corners_px,
        extent_mm,
        edge: None,
    });
    let rect = match &housing {
        Some(h) => h.extent_mm,
        None => {
            warnings.push("housing outline not found: extras are judged against the grid grown by half a pitch".into());
            [
                -u_half - 0.5 * px_mm,
                u_half + 0.5 * px_mm,
                -v_half - 0.5 * py_mm,
                v_half + 0.5 * py_mm,
            ]
        }
    };
    // Debris fainter than the coarse threshold: extras' candidates only.
    add_faint_debris(plane, sign, &cs, pin_px0, opts, &mut cands, &mut cand_used);
    let grown = |g: f64| [-u_half - g, u_half + g, -v_half - g, v_half + g];
    let (extras, ignored) = super::top_extras::judge_extras(
        &super::top_extras::Leftovers {
            plane,
            sign,
            localiser: opts.localiser,
            dilate,
            cands: &cands,
            used: &cand_used,
            tip_px,
            levels: &levels,
            sim: &sim,
            rect,
            pitch_mm: px_mm,
            coarse: &cs,
            grid: grown(0.4 * px_mm.min(py_mm)),
        },
        &recipe.extras,
    );

    let (cx, cy) = sim.apply(0.0, 0.0);
    let grid = GridFit {
        transform: sim,
        centre_px: (cx, cy),
        rotation_deg: sim.theta.to_degrees(),
        mm_per_px,
        mm_per_px_estimated: fixed.is_none(),
        fit_inliers: inliers,
        fit_rms_px: rms,
        anchored_by_housing: placement.ambiguous && !by_evidence && housing_lat.is_some(),
    };
    let found = Findings {
        pins,
        extras,
        ignored,
    };
    Ok(Inspection::judged(
        recipe, info, grid, housing, found, warnings,
    ))
}

#[cfg(test)]
#[path = "top_tests.rs"]
mod tests;
