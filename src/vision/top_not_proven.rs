//! The top view's verdicts on blurred tips read just beyond a limit: a
//! reading beyond the `tip_area` or `position_mm` limit by less than its
//! uncertainty in that image does not prove the tip damaged or bent (the
//! ISO 14253-1 rule for proving nonconformance: the result must lie beyond
//! the specification by the measurement's uncertainty). Where the tips are
//! sharp the readings stand as read.
//!
//! Areas. Under blur comparable to the tip the area ratio is read from the
//! tip's energy against its neighbours' (`tip_levels::area_ratio_of`), and
//! on small, noisy tips that reading spreads: on the tuning sets (Rust
//! 900 000, 1 000 000, 1 020 000 × 1500, top views) the blurred regime
//! called 32 good tips damaged and missed 2 of 301 damaged ones, most of
//! the 32 within one spread of the limit (good tips 6–7 px wide under
//! σ 9–15 DN read 1.51–1.73 × or 0.48–0.59 ×). Sharp tips are measured by
//! their coverage, whose false calls and misses balance (11 and 8 over the
//! same sets).
//!
//! Offsets. Blurred small tips' centres come from the blurred-tip model,
//! a few tenths of a pixel from the truth under σ 10–16 DN; good pins that
//! stand at 0.6–0.85 of a 3 px tolerance then read 0.04–0.8 px past it
//! (34 good pins called bent over Rust 900 000 and 1 000 000, blurred).
//! The uncertainty is each tip's Cramér–Rao bound under the image's noise,
//! blur and the tip's contrast, times the efficiency the envelope measures
//! ([`centre_bound_px`], [`CENTRE_EFFICIENCY`]).

use super::measure::BlobMeasure;
use super::result::{PinResult, PinStatus};

/// Judges a blurred part's tips read just past a limit: first the areas
/// ([`not_proven_damaged`]), then the offsets ([`not_proven_bent`]), so a
/// tip not proven damaged but offset is judged on its offset. Returns the
/// notes for the report.
pub(crate) fn judge(
    pins: &mut [PinResult],
    tip_area: [f64; 2],
    position_mm: f64,
    centre_sigma_mm: &[Option<f64>],
) -> Vec<String> {
    let mut notes = Vec::new();
    let n = not_proven_damaged(pins, tip_area, position_mm);
    if n > 0 {
        notes.push(format!("{n} tip(s) read beyond tip_area by less than the spread of this part's blurred tip areas: not proven damaged"));
    }
    let n = not_proven_bent(pins, position_mm, centre_sigma_mm);
    if n > 0 {
        notes.push(format!("{n} pin(s) read beyond position_mm by less than their centres' uncertainty under this image's noise and blur: not proven bent"));
    }
    notes
}

/// Fewest tips whose readings give a part's spread: under it the spread is
/// not known and every reading stands as read.
pub(crate) const MIN_TIPS_FOR_SPREAD: usize = 5;

/// Largest share of `position_mm` a centre's uncertainty may reach and
/// still forgive an offset past the tolerance: beyond it the gauge cannot
/// judge the pin, and its reading stands.
pub(crate) const MAX_UNCERTAINTY_OF_TOL: f64 = 0.25;

/// The spread of a part's tip-area ratios: the median absolute deviation
/// from their median, as a normal σ (× 1.4826), robust to the damaged
/// tips among them; `None` under [`MIN_TIPS_FOR_SPREAD`] readings.
pub(crate) fn area_spread(ratios: &[f64]) -> Option<f64> {
    let mut v: Vec<f64> = ratios.iter().copied().filter(|r| r.is_finite()).collect();
    if v.len() < MIN_TIPS_FOR_SPREAD {
        return None;
    }
    let med = super::grid::median(&mut v)?;
    let mut dev: Vec<f64> = v.iter().map(|r| (r - med).abs()).collect();
    Some(1.4826 * super::grid::median(&mut dev)?)
}

/// Tips read damaged by an area beyond `[lo, hi]` by no more than the
/// part's spread ([`area_spread`] of every tip read) are not proven
/// damaged: each becomes bent where its offset exceeds `position_mm`,
/// else ok, and its reason says why. Returns how many were changed.
pub(crate) fn not_proven_damaged(
    pins: &mut [PinResult],
    [lo, hi]: [f64; 2],
    position_mm: f64,
) -> usize {
    let ratios: Vec<f64> = pins.iter().filter_map(|p| p.area_ratio).collect();
    let Some(sigma) = area_spread(&ratios) else {
        return 0;
    };
    let mut changed = 0;
    for p in pins.iter_mut().filter(|p| p.status == PinStatus::Damaged) {
        let Some(ar) = p.area_ratio else { continue };
        let beyond = if ar > hi { ar - hi } else { lo - ar };
        if !(beyond > 0.0 && beyond <= sigma) {
            continue;
        }
        let off = p.offset_mm.unwrap_or(0.0);
        p.status = if off > position_mm {
            PinStatus::Bent
        } else {
            PinStatus::Ok
        };
        p.reason = Some(format!(
            "tip area {ar:.2} × nominal lies beyond tip_area [{lo}, {hi}] by {beyond:.2}, within the spread of this part's blurred tip areas (σ {sigma:.2}): not proven damaged{}",
            if p.status == PinStatus::Bent {
                format!(
                    "; offset {off:.3} mm = {:.2} × position_mm {position_mm}",
                    off / position_mm
                )
            } else {
                String::new()
            }
        ));
        changed += 1;
    }
    changed
}

/// How far above its Cramér–Rao bound a blurred tip's centre is read:
/// over the envelope's top views the ok pins' centre RMS within 1 px is
/// 1.45 × the bound (docs/vision.md, "Accuracy"; thirteenth round).
pub(crate) const CENTRE_EFFICIENCY: f64 = 1.45;

/// The Cramér–Rao bound (px, per axis) on the centre of a disc-like tip
/// of radius `radius_px` whose edge, blurred to a normal spread of
/// `edge_sigma_px`, steps by `contrast` under pixel noise `noise` (both in
/// the same units): the Fisher information of a shift along x is
/// (C/σ)² · πR · ∫φ²/s = (C/σ)² · πR / (2√π s), so the bound is
/// (σ/C) · √(2√π s / (πR)). Valid while the spread is under the radius; a
/// sharp edge's spread is the pixel grid's (≈ 0.3 px, `edge_sigma`).
pub(crate) fn centre_bound_px(
    noise: f64,
    contrast: f64,
    edge_sigma_px: f64,
    radius_px: f64,
) -> f64 {
    let s = edge_sigma_px.max(0.3);
    (noise / contrast.abs())
        * (2.0 * std::f64::consts::PI.sqrt() * s / (std::f64::consts::PI * radius_px)).sqrt()
}

/// A tip's centre uncertainty per axis (px): [`CENTRE_EFFICIENCY`] ×
/// [`centre_bound_px`] from its blob's local noise, its level above the
/// surround (a blurred small tip's peak, so the bound errs on the large
/// side), its edge spread and the nominal tip's half width `pin_px / 2`.
pub(crate) fn centre_sigma_px(m: &BlobMeasure, pin_px: f64) -> f64 {
    CENTRE_EFFICIENCY
        * centre_bound_px(
            m.noise as f64,
            (m.hi - m.lo) as f64,
            m.edge_sigma,
            0.5 * pin_px,
        )
}

/// Pins read bent by an offset beyond `position_mm` by no more than their
/// centre's standard uncertainty (`centre_sigma_mm`, per pin:
/// [`CENTRE_EFFICIENCY`] × [`centre_bound_px`] at the image's scale) are
/// not proven bent: each becomes ok, and its reason says why. An
/// uncertainty over [`MAX_UNCERTAINTY_OF_TOL`] of the tolerance forgives
/// nothing (the gauge cannot judge that pin; its reading stands). Returns
/// how many were changed.
///
/// The uncertainty is the image's (noise, blur, the tip's contrast), not
/// the pins' scatter about their grid: a part whose good pins truly
/// scatter (Python 730 202: median offset 0.2 tolerances, noise 5 DN)
/// would otherwise have a bent pin read 0.07 tolerances past the limit
/// forgiven.
pub(crate) fn not_proven_bent(
    pins: &mut [PinResult],
    position_mm: f64,
    centre_sigma_mm: &[Option<f64>],
) -> usize {
    let mut changed = 0;
    for (p, u) in pins.iter_mut().zip(centre_sigma_mm) {
        let (Some(off), Some(u)) = (p.offset_mm, *u) else {
            continue;
        };
        let beyond = off - position_mm;
        if p.status != PinStatus::Bent
            || !(beyond > 0.0 && beyond <= u && u <= MAX_UNCERTAINTY_OF_TOL * position_mm)
        {
            continue;
        }
        p.status = PinStatus::Ok;
        p.reason = Some(format!(
            "offset {off:.3} mm lies beyond position_mm {position_mm} by {beyond:.3} mm, within its centre's uncertainty under this image's noise and blur (σ {u:.3} mm per axis): not proven bent"
        ));
        changed += 1;
    }
    changed
}

#[cfg(test)]
mod tests {
    use super::*;

    fn pin(col: u32, ar: f64, status: PinStatus, off: f64) -> PinResult {
        let mut p = PinResult::missing(0, col, (0.0, 0.0));
        p.status = status;
        p.area_ratio = Some(ar);
        p.offset_mm = Some(off);
        p
    }

    #[test]
    fn the_spread_is_the_median_deviation_as_a_sigma_and_needs_five_tips() {
        assert_eq!(area_spread(&[1.0, 1.1, 0.9, 1.0]), None);
        // Deviations from the median 1.0: 0, 0.1, 0.1, 0.2, 3.0 → median 0.1.
        let s = area_spread(&[1.0, 1.1, 0.9, 1.2, 4.0]).unwrap();
        assert!((s - 0.14826).abs() < 1e-9, "{s}");
    }

    #[test]
    fn a_reading_beyond_the_limit_by_less_than_the_spread_is_not_proven_damaged() {
        // Deviations from the median 1.0: 0, 0.1 × 4, 0.6, 0.7 → σ 0.148.
        let mut pins = vec![
            pin(0, 1.0, PinStatus::Ok, 0.0),
            pin(1, 1.1, PinStatus::Ok, 0.0),
            pin(2, 0.9, PinStatus::Ok, 0.0),
            pin(3, 1.1, PinStatus::Ok, 0.0),
            pin(4, 0.9, PinStatus::Ok, 0.0),
            // 0.1 beyond 1.5: within σ; its offset is past the tolerance.
            pin(5, 1.6, PinStatus::Damaged, 0.2),
            // 0.3 below 0.6: beyond σ, damaged it stays.
            pin(6, 0.3, PinStatus::Damaged, 0.0),
        ];
        let n = not_proven_damaged(&mut pins, [0.6, 1.5], 0.15);
        assert_eq!(n, 1);
        assert_eq!(pins[5].status, PinStatus::Bent);
        assert!(
            pins[5]
                .reason
                .as_deref()
                .unwrap()
                .contains("not proven damaged")
        );
        assert_eq!(pins[6].status, PinStatus::Damaged);
    }

    #[test]
    fn an_offset_past_the_tolerance_by_less_than_its_uncertainty_is_not_proven_bent() {
        let mut pins = vec![
            pin(0, 1.0, PinStatus::Bent, 0.16),
            pin(1, 1.0, PinStatus::Bent, 0.16),
            pin(2, 1.0, PinStatus::Bent, 0.2),
            pin(3, 1.0, PinStatus::Bent, 0.16),
        ];
        // 0.01 past 0.15: forgiven under σ 0.02; not under σ 0.005; 0.05
        // past it stays bent; σ 0.05 is over a quarter tolerance (0.0375).
        let u = [Some(0.02), Some(0.005), Some(0.02), Some(0.05)];
        assert_eq!(not_proven_bent(&mut pins, 0.15, &u), 1);
        assert_eq!(pins[0].status, PinStatus::Ok);
        assert!(
            pins[0]
                .reason
                .as_deref()
                .unwrap()
                .contains("not proven bent")
        );
        for p in &pins[1..] {
            assert_eq!(p.status, PinStatus::Bent, "{}", p.col);
        }
    }

    /// The closed form against the Fisher information summed over the
    /// pixels of a blurred disc (edge profile Φ((R − r)/s), centre moved
    /// by ±0.01 px): within 5 % for a disc of radius 3–8 px blurred by
    /// 0.6–1.5 px.
    #[test]
    fn the_centre_bound_is_the_fisher_information_of_a_blurred_disc() {
        let phi =
            |t: f64| 0.5 * (1.0 + crate::vision::blur_model::erf(t / std::f64::consts::SQRT_2));
        for &(r, s) in &[(3.0, 0.6), (4.0, 1.0), (8.0, 1.5), (5.0, 0.8)] {
            let (c, sigma, d) = (40.0, 10.0, 0.01);
            let n = (2.0 * (r + 6.0 * s)) as i64;
            let mut info = 0.0;
            for y in -n..=n {
                for x in -n..=n {
                    let at = |cx: f64| {
                        let rr = ((x as f64 - cx).powi(2) + (y as f64 - 0.3).powi(2)).sqrt();
                        c * phi((r - rr) / s)
                    };
                    let g = (at(0.2 + d) - at(0.2 - d)) / (2.0 * d);
                    info += g * g / (sigma * sigma);
                }
            }
            let numeric = 1.0 / info.sqrt();
            let closed = centre_bound_px(sigma, c, s, r);
            assert!(
                (closed / numeric - 1.0).abs() < 0.05,
                "R {r}, s {s}: closed {closed:.4} px, numeric {numeric:.4} px"
            );
        }
    }

    #[test]
    fn with_few_tips_every_reading_stands() {
        let mut pins = vec![
            pin(0, 1.0, PinStatus::Ok, 0.0),
            pin(1, 1.0, PinStatus::Ok, 0.0),
            pin(2, 1.51, PinStatus::Damaged, 0.0),
        ];
        assert_eq!(not_proven_damaged(&mut pins, [0.6, 1.5], 0.15), 0);
        assert_eq!(pins[2].status, PinStatus::Damaged);
    }
}
