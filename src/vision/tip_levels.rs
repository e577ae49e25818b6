//! What a tip looks like where it stands: the measured candidate blobs,
//! the tip and background levels expected at a place from the nearest
//! intact tips, a blob's contrast against them and against the local noise,
//! and a tip's area ratio that survives blur. The top view's verdicts on
//! damaged tips and extras are made from these.

use super::gray::{Plane, Px};
use super::grid;
use super::measure::{BlobMeasure, Roi};
use super::recipe::PinShape;

/// A blob's area, in nominal tips, that the first look calls tip-like
/// (with an elongation under 3 and a mask clear of its window).
pub(crate) const TIP_LIKE_AREA: std::ops::Range<f64> = 0.3..3.0;

/// A measured blob and what it looks like.
#[derive(Debug, Clone)]
pub(crate) struct Candidate {
    pub m: BlobMeasure,
    pub pinlike: bool,
    /// Where it was measured (for a second look with other levels).
    pub roi: Roi,
    pub seed: (f64, f64),
}

/// A tip's area ratio: its coverage area over the nominal tip, or (blur
/// comparable to the tip) measured against the four nearest other tips
/// (`assigned`: the pin-like tips on grid positions) by two means, averaged:
/// its energy over the median of theirs, and its coverage area over the
/// median of theirs. Each is biased where the other is not. The energy is
/// taken against the housing's level, so the clearance hole around a tip
/// (darker than the housing on a bright part, brighter on a dark one) counts
/// against it by the part of the hole the tip leaves bare inside the disc:
/// a tip off-centre in its hole, or a bent one, reads larger than its
/// neighbours (1.6–1.9 ×), a small tip far smaller (even negative), and
/// where the background estimate is off by a few DN a good small tip reads
/// 0.6 ×. The half-level coverage, taken against the level beside the tip
/// (hole or housing), has no such bias; blur grows it, but alike for every
/// tip of the part, so against the neighbours' it stays near the area
/// ratio (within 0.1–0.3 of it for intact, bent and damaged tips alike) —
/// unless the pixel noise is comparable to the tip's contrast: then the
/// half-level mask takes in noise clumps and the coverage reads good tips
/// up to 2.3 × their neighbours'. Noise clumps only add to the coverage,
/// so there a coverage above the energy is not believed and the energy
/// alone is the ratio ([`coverage_is_noise`]); one below
/// it still counts, as the energy has its own bias (the background's error
/// over the disc).
pub(crate) fn area_ratio_of(
    cands: &[Candidate],
    assigned: &[usize],
    ci: usize,
    tip_px: f64,
    blurred: bool,
) -> f64 {
    let m = &cands[ci].m;
    let abs = m.area_px / tip_px;
    if !blurred {
        return abs;
    }
    let Some((me, mc)) = neighbour_medians(cands, assigned, (m.x, m.y), Some(ci)) else {
        return abs;
    };
    match (me, mc) {
        (Some(me), Some(mc)) if me > 0.0 && mc > 0.0 => {
            let (e, c) = (m.energy / me, m.area_px / mc);
            if c > e && coverage_is_noise(m) {
                e
            } else {
                0.5 * (e + c)
            }
        }
        (Some(me), _) if me > 0.0 => m.energy / me,
        _ => abs,
    }
}

/// The medians of the energy and of the coverage area of the four tips of
/// `assigned` nearest `at` (leaving out `except`); `None` under two tips.
pub(crate) fn neighbour_medians(
    cands: &[Candidate],
    assigned: &[usize],
    at: (f64, f64),
    except: Option<usize>,
) -> Option<(Option<f64>, Option<f64>)> {
    let mut d: Vec<(f64, (f64, f64))> = assigned
        .iter()
        .filter(|&&o| Some(o) != except)
        .map(|&o| {
            let q = &cands[o].m;
            ((q.x - at.0).hypot(q.y - at.1), (q.energy, q.area_px))
        })
        .collect();
    if d.len() < 2 {
        return None;
    }
    d.sort_by(|a, b| a.0.total_cmp(&b.0));
    let mut e: Vec<f64> = d.iter().take(4).map(|p| p.1.0).collect();
    let mut c: Vec<f64> = d.iter().take(4).map(|p| p.1.1).collect();
    Some((grid::median(&mut e), grid::median(&mut c)))
}

/// A blob the second look finds on an empty grid position, under the
/// tip-bright level ([`MIN_TIP_CONTRAST`]), is still the pin's tip — a
/// damaged one, smaller than the intact tips and flat where they are domed,
/// whose peak blur lowers — when it is what only a tip can be there: a
/// missing pin leaves its clearance hole, which stands on the far side of
/// the housing from the tips (darker on a bright part, brighter on a dark
/// one), so nothing tip-ward sits on the position. It must lie on the
/// position (`d_pin`, its distance in tip widths, at most
/// [`DIM_TIP_ON_POSITION`]: a damaged tip's area centroid stays within its
/// own outline), be compact (`elongation` under [`DIM_TIP_MAX_ELONGATION`]),
/// reach [`DIM_TIP_MIN_LEVEL`] of the local tip level, stand
/// [`DIM_TIP_MIN_SNR`] σ over the noise, and be filled (`core`, its disc
/// mean at its centre, at least half its level: a ring, such as a hole's
/// rim, has a low core).
pub(crate) fn dim_tip_on_position(
    rho: f64,
    core: Option<f64>,
    snr: f64,
    d_pin: f64,
    elongation: f64,
) -> bool {
    rho >= DIM_TIP_MIN_LEVEL
        && core.is_some_and(|c| c >= 0.5 * rho)
        && snr >= DIM_TIP_MIN_SNR
        && d_pin <= DIM_TIP_ON_POSITION
        && elongation < DIM_TIP_MAX_ELONGATION
}

/// [`dim_tip_on_position`]: the least level, a fraction of the local tip
/// level (a tip of a third of the area, flat and blurred, reads 0.25–0.5).
pub(crate) const DIM_TIP_MIN_LEVEL: f64 = 0.2;
/// ... the least contrast over the noise, summed over its mask: a fifth
/// above a tip-bright blob's ([`MIN_SNR`]). Twice that (10 σ) left small
/// damaged tips under blur 2–2.3 px, at 5.5–8 σ, read missing: 6–8 of the
/// 50–60 status errors a set on the held-out sets of 2026-12-07 (the
/// largest class on two of the three). At 6 σ, five more statuses are
/// right on the ten Rust top sets and five on the top views of
/// 1 220 000–1 240 000, and no status is lost on either (no empty
/// position reads damaged).
pub(crate) const DIM_TIP_MIN_SNR: f64 = 1.2 * MIN_SNR;
/// ... the farthest from the position, in tip widths.
pub(crate) const DIM_TIP_ON_POSITION: f64 = 0.5;
/// ... the most elongated: a chipped or burred tip of a third of the area,
/// blurred, reads 2.0–2.4 (Rust 960 826, 970 927, 940 450, 930 346, read
/// missing under 2.0); kept under the first look's 3.0 for a tip-like
/// blob, past which a housing strip by an empty position reads.
pub(crate) const DIM_TIP_MAX_ELONGATION: f64 = 2.5;

/// A blob on a position that is not tip-like and whose brightest part
/// stays at the housing's level is no tip, wherever it lies. An empty
/// clearance hole stands on the far side of the housing from the tips, so
/// the housing around it stands out of the coarse top-hat as a ring (under
/// noise, a mask many tips large that runs into its window), and its disc
/// energy, taken against the coarse background that the hole's light
/// shifts, can read a good fraction of a tip's (Rust 820 574: 0.60 of the
/// neighbours', its level 0.14 of the local tip level; Python 650 356: a
/// bright part, read damaged). A tip, even a damaged one, must reach
/// [`DIM_TIP_MIN_LEVEL`] of that level ([`dim_tip_on_position`]); the
/// damaged tips read near the area limit on the tuning sets (Rust 840 621,
/// 840 921, 860 326, 900 019, 900 286) stand 0.54–0.89. Returns the level
/// and the reason the pin reads missing.
pub(crate) fn housing_not_tip(
    c: &Candidate,
    levels: &LocalLevels,
    tip_px: f64,
) -> Option<(f64, String)> {
    let m = &c.m;
    let rho = levels
        .expected(m.x, m.y)
        .map(|(t, b)| contrast_ratio(m.hi, t, b))?;
    let area = m.area_px / tip_px;
    let floor = if area > HOUSING_RING_AREA {
        MIN_TIP_CONTRAST
    } else {
        DIM_TIP_MIN_LEVEL
    };
    (!c.pinlike && rho < floor).then(|| {
        (
            rho,
            format!(
                "no tip at the position: the blob there is not tip-like (area {area:.2} × nominal, elongation {:.1}) and reaches only {rho:.2} of the local tip level (a tip, even a damaged one, reaches ≥ {floor}): the housing around an empty hole",
                m.elongation
            ),
        )
    })
}

/// [`housing_not_tip`]: a blob of more than this many nominal tip areas is
/// held to the tip-bright level ([`MIN_TIP_CONTRAST`]) rather than
/// [`DIM_TIP_MIN_LEVEL`]. Blur lowers the peak of a tip smaller than the
/// blur, not of one larger than nominal: a damaged tip drawn large (at
/// most 2.25 × the area) keeps a tip's level, while the housing ring
/// around an empty hole at its true scale runs to many tip areas (Rust
/// 955 323 at a 29.7 px tip: 8.8 × the area, 0.23 of the tip level).
pub(crate) const HOUSING_RING_AREA: f64 = 3.0;

/// A blob assigned to a position that is not tip-like (area, elongation)
/// and lies more than this many tip widths from it is outside the tip's
/// clearance hole (≈ 0.6–0.7 tip widths in radius): not the pin, which
/// reads missing.
pub(crate) const OFF_HOLE: f64 = 0.75;

/// Blur (edge σ) beyond this fraction of the tip width: tip areas are
/// judged against the neighbouring tips' energy.
pub(crate) const BLUR_RELATIVE: f64 = 0.08;

/// Blur σ beyond the tip's outer radius that the fixed disc of a tip's
/// energy reaches (`tip_disc_radius`): 2 σ holds all but about 2 % of a
/// blurred edge's light.
pub(crate) const DISC_BLUR_SIGMAS: f64 = 2.0;

/// Radius (px) of the fixed disc in which a blurred tip's energy is summed
/// ([`super::disc::disc_energy`]): the nominal tip's outer radius (a
/// square's half-diagonal) plus `DISC_BLUR_SIGMAS` blur σ, at most half
/// the smallest pitch so that no neighbour's light is counted.
pub(crate) fn tip_disc_radius(
    shape: PinShape,
    pin_px: f64,
    blur_sigma: f64,
    min_pitch_px: f64,
) -> f64 {
    let outer = match shape {
        PinShape::Round => 0.5 * pin_px,
        PinShape::Square => 0.5 * std::f64::consts::SQRT_2 * pin_px,
    };
    (outer + DISC_BLUR_SIGMAS * blur_sigma).min(0.5 * min_pitch_px)
}

/// A blob counts as tip-bright when its level stands at least this
/// fraction of the way from the local background to the local tip level.
pub(crate) const MIN_TIP_CONTRAST: f64 = 0.5;
/// ... and its contrast, summed over its pixels, at least this many local
/// noise σ.
pub(crate) const MIN_SNR: f64 = 5.0;
/// A blob cut from a larger bright structure it touches (debris on the
/// housing's edge against a brighter fixture) must stand at least this
/// fraction of the local tip contrast above the saddle where they join.
pub(crate) const MIN_PROMINENCE: f64 = 0.05;

/// An extra's core (its disc mean, [`core_contrast`]) must stand this many
/// of its own noise σ ([`core_sigma`]) above `MIN_TIP_CONTRAST`. The blob
/// is where the noise lifted a structure above the coarse threshold, so
/// its disc mean is itself biased up by about one σ; a housing rim's ridge
/// at 0.3 of the tip contrast under σ ≈ 14 DN reads 0.50–0.65 there, while
/// debris (opaque, at a tip's level) stands well clear of the limit.
pub(crate) const CORE_SIGMAS: f64 = 2.0;
/// A blob that is not cut from a larger structure must stand at least this
/// fraction of the local tip contrast above its own surround (the median of
/// its window's border): half the tip-bright limit. Its level says how
/// bright it is against the housing; a bump of a fixture that is itself as
/// bright as the tips (a bright fixture's texture) is tip-bright by level
/// but stands a few hundredths above what lies around it. (A cut blob's
/// height above its saddle is `MIN_PROMINENCE`'s to judge.)
pub(crate) const MIN_LOCAL_CONTRAST: f64 = 0.5 * MIN_TIP_CONTRAST;

/// The noise σ of [`core_contrast`] in the same units (fractions of the
/// local tip contrast `t − b`): pixel noise `noise` averaged over the
/// disc's `min_area_px` pixels.
pub(crate) fn core_sigma(noise: f32, min_area_px: f64, t: f32, b: f32) -> f64 {
    noise as f64 / min_area_px.max(1.0).sqrt() / ((t - b) as f64).max(1e-6)
}

/// How far a measured blob stands above its own surround (its level over
/// the median of its window's border), as a fraction of the local tip
/// contrast `t − b`.
pub(crate) fn local_contrast(m: &BlobMeasure, t: f32, b: f32) -> f64 {
    contrast_ratio(m.hi, t, b) - contrast_ratio(m.lo, t, b)
}

/// Tip level and background level expected at a place, from the nearest
/// intact tips.
pub(crate) struct LocalLevels {
    /// (x, y, tip level, background level) per intact tip, `sign` space.
    pub refs: Vec<(f64, f64, f32, f32)>,
}

impl LocalLevels {
    /// Medians over the four nearest intact tips.
    pub fn expected(&self, x: f64, y: f64) -> Option<(f32, f32)> {
        if self.refs.is_empty() {
            return None;
        }
        let mut d: Vec<(f64, usize)> = self
            .refs
            .iter()
            .enumerate()
            .map(|(i, r)| ((r.0 - x).hypot(r.1 - y), i))
            .collect();
        let k = d.len().min(4);
        d.select_nth_unstable_by(k - 1, |a, b| a.0.total_cmp(&b.0));
        let mut t: Vec<f64> = d[..k].iter().map(|p| self.refs[p.1].2 as f64).collect();
        let mut b: Vec<f64> = d[..k].iter().map(|p| self.refs[p.1].3 as f64).collect();
        Some((grid::median(&mut t)? as f32, grid::median(&mut b)? as f32))
    }
}

/// Level `hi` as a fraction of the way from background `b` to tip level `t`.
pub(crate) fn contrast_ratio(hi: f32, t: f32, b: f32) -> f64 {
    ((hi - b) / (t - b).max(1e-6)) as f64
}

/// A blob's contrast summed over its mask against the local noise.
pub(crate) fn snr_of(m: &BlobMeasure) -> f64 {
    let c = (m.hi - m.lo).max(0.0) as f64;
    if m.noise > 0.0 {
        c * (m.mask_px as f64).sqrt() / m.noise as f64
    } else {
        f64::INFINITY
    }
}

/// Mean level (`sign` space) inside a disc of radius `r` around `c`, each
/// pixel weighted by how much of it lies within `r` (a 1 px ramp across
/// the rim); pixels beyond the image are left out. `None` when the disc
/// holds no pixel.
pub(crate) fn disc_mean<P: Px>(plane: &Plane<P>, sign: f32, c: (f64, f64), r: f64) -> Option<f64> {
    let (mut sw, mut sv) = (0f64, 0f64);
    super::disc::for_each_in_disc(plane, sign, c, r, |w, v| {
        sw += w;
        sv += w * v as f64;
    });
    (sw > 0.0).then(|| sv / sw)
}

/// An extra candidate's core level as a fraction of the way from the local
/// background `b` to the local tip level `t`: the mean over a disc of the
/// smallest area the extras rule counts (`min_area_px`), at the blob's
/// centre. Unlike the median of the blob's own mask (the pixels that noise
/// lifted above a threshold, which in a noisy image stands one or two σ
/// above the level of what is there), this mean is not selected by the
/// noise: a ridge of the housing's rim or a shading dip that noise clumps
/// make look tip-bright keeps its own, low level, while debris (opaque, at
/// a tip's level) fills the disc.
pub(crate) fn core_contrast<P: Px>(
    plane: &Plane<P>,
    sign: f32,
    c: (f64, f64),
    min_area_px: f64,
    t: f32,
    b: f32,
) -> Option<f64> {
    let r = (min_area_px.max(1.0) / std::f64::consts::PI).sqrt();
    let mean = disc_mean(plane, sign, c, r)?;
    Some(contrast_ratio(mean as f32, t, b))
}

/// Pixel noise σ above this fraction of a tip's own contrast (`hi − lo`)
/// makes its coverage area noise: the half-level threshold then stands
/// under 1.25 σ above the background, so over a tenth of the background's
/// pixels cross it and join the mask in clumps. Among the good tips of the
/// Rust 820 000 set, the coverage ratio's spread is that of the energy
/// ratio (≈ 0.06–0.1) below 0.4 and three times it above.
pub(crate) const NOISY_COVERAGE: f32 = 0.4;

/// Whether a blob's coverage area is noise ([`NOISY_COVERAGE`]).
pub(crate) fn coverage_is_noise(m: &BlobMeasure) -> bool {
    m.noise > NOISY_COVERAGE * (m.hi - m.lo)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A 40 × 40 image at the housing's level 100 (tip level 200 here)
    /// with, inside radius 3.5 of (20, 20), either debris at the tip's
    /// level or a faint structure (mean 0.2 of the tip contrast) whose
    /// pixels noise has split into +0.9 and −0.5 (a checkerboard: the
    /// bright half is connected, as a threshold picks noise peaks).
    fn patch(debris: bool) -> Vec<u16> {
        let mut d = vec![100u16; 40 * 40];
        for y in 0..40 {
            for x in 0..40 {
                if (x as f64 - 20.0).hypot(y as f64 - 20.0) <= 3.5 {
                    d[y * 40 + x] = if debris {
                        200
                    } else if (x + y) % 2 == 0 {
                        190
                    } else {
                        50
                    };
                }
            }
        }
        d
    }

    /// The blob at (20, 20) of a 40 × 40 patch, measured as the top view
    /// measures a candidate.
    fn measured(plane: &Plane<'_, u16>) -> super::super::measure::BlobMeasure {
        let roi = Roi::around(20.0, 20.0, 20.0, 20.0, 7.0, 40, 40);
        super::super::measure::measure_blob(
            plane,
            1.0,
            roi,
            (20.0, 20.0),
            super::super::measure::Localiser::Coverage,
            2,
            None,
        )
        .expect("a blob")
    }

    fn levels_of(d: &[u16]) -> (f64, f64) {
        let plane = Plane {
            w: 40,
            h: 40,
            data: d,
        };
        let m = measured(&plane);
        // The smallest extra the default rule counts: 0.25 of a 120 px² tip.
        let core =
            core_contrast(&plane, 1.0, (m.x, m.y), 0.25 * 120.0, 200.0, 100.0).expect("a core");
        (contrast_ratio(m.hi, 200.0, 100.0), core)
    }

    #[test]
    fn a_noise_lifted_faint_structure_is_tip_bright_by_its_mask_but_not_by_its_core() {
        let (mask_level, core) = levels_of(&patch(false));
        // The mask's level (the pixels above the half level) reads tip-bright...
        assert!(mask_level >= MIN_TIP_CONTRAST, "{mask_level}");
        // ... its core says what is there: about 0.2 of the tip contrast.
        assert!(core < MIN_TIP_CONTRAST && core > 0.0, "{core}");
    }

    #[test]
    fn debris_at_the_tip_level_fills_its_core() {
        let (mask_level, core) = levels_of(&patch(true));
        assert!((mask_level - 1.0).abs() < 0.05, "{mask_level}");
        assert!((core - 1.0).abs() < 0.05, "{core}");
    }

    /// Deterministic noise in [−a, a] (an LCG), for the noisy patches.
    fn noisy(base: &mut [u16], a: f64, seed: u64) {
        let mut s = seed;
        for v in base.iter_mut() {
            s = s
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            let u = ((s >> 33) as f64 / (1u64 << 31) as f64) * 2.0 - 1.0;
            *v = (*v as f64 + a * u).round().clamp(0.0, 65535.0) as u16;
        }
    }

    /// Measures the blob at (20, 20) of a 40 × 40 patch; its core level,
    /// core noise σ and contrast over its own surround, against a tip
    /// level 200 over a housing at 100 (a 120 px² tip, the default rule's
    /// quarter-tip core).
    fn judged(d: &[u16]) -> (f64, f64, f64) {
        let plane = Plane {
            w: 40,
            h: 40,
            data: d,
        };
        let m = measured(&plane);
        let core_px = 0.25 * 120.0;
        let core = core_contrast(&plane, 1.0, (m.x, m.y), core_px, 200.0, 100.0).expect("a core");
        let sd = core_sigma(m.noise, core_px, 200.0, 100.0);
        (core, sd, local_contrast(&m, 200.0, 100.0))
    }

    fn disc_patch(bg: u16, inside: u16, r: f64) -> Vec<u16> {
        let mut d = vec![bg; 40 * 40];
        for y in 0..40 {
            for x in 0..40 {
                if (x as f64 - 20.0).hypot(y as f64 - 20.0) <= r {
                    d[y * 40 + x] = inside;
                }
            }
        }
        d
    }

    /// A rim ridge at 0.55 of the tip contrast under heavy noise (±45 DN,
    /// σ ≈ 26 DN): its core clears the tip-bright limit by less than its
    /// own noise allows (it was an extra before the margin); debris at the
    /// tip's level under the same noise clears it by far.
    #[test]
    fn a_core_within_its_noise_of_the_limit_is_not_tip_bright() {
        let mut ridge = disc_patch(100, 155, 4.0);
        noisy(&mut ridge, 45.0, 7);
        let (core, sd, _) = judged(&ridge);
        assert!(core >= MIN_TIP_CONTRAST, "{core}");
        assert!(core - CORE_SIGMAS * sd < MIN_TIP_CONTRAST, "{core} {sd}");
        let mut debris = disc_patch(100, 200, 4.0);
        noisy(&mut debris, 45.0, 7);
        let (core, sd, local) = judged(&debris);
        assert!(core - CORE_SIGMAS * sd >= MIN_TIP_CONTRAST, "{core} {sd}");
        assert!(local >= MIN_LOCAL_CONTRAST, "{local}");
    }

    /// A bump of 0.07 of the tip contrast on a fixture brighter than the
    /// tips (level 1.1): tip-bright by level and by core, but it stands a
    /// few hundredths above its own surround — the fixture's texture.
    #[test]
    fn a_bump_on_a_fixture_as_bright_as_the_tips_is_not_debris() {
        let bump = disc_patch(210, 217, 6.0);
        let (core, _, local) = judged(&bump);
        assert!(core >= MIN_TIP_CONTRAST, "{core}");
        assert!(local < MIN_LOCAL_CONTRAST, "{local}");
        let (_, _, local) = judged(&disc_patch(100, 200, 6.0));
        assert!((local - 1.0).abs() < 0.05, "{local}");
    }

    #[test]
    fn the_disc_mean_leaves_out_what_lies_beyond_the_image() {
        let d = [100u16; 16];
        let plane = Plane {
            w: 4,
            h: 4,
            data: &d[..],
        };
        let m = disc_mean(&plane, 1.0, (0.0, 0.0), 2.0).expect("pixels");
        assert!((m - 100.0).abs() < 1e-9, "{m}");
    }

    #[test]
    fn the_energy_disc_holds_the_tip_and_two_blur_sigma_within_half_a_pitch() {
        // Round 8 px tip, σ 1.5 px: 4 + 2 × 1.5.
        assert!((tip_disc_radius(PinShape::Round, 8.0, 1.5, 40.0) - 7.0).abs() < 1e-12);
        // Square: its half-diagonal, 4 √2, + 3.
        let sq = tip_disc_radius(PinShape::Square, 8.0, 1.5, 40.0);
        assert!((sq - (4.0 * std::f64::consts::SQRT_2 + 3.0)).abs() < 1e-12);
        // Never beyond half the pitch (a neighbour's light).
        assert!((tip_disc_radius(PinShape::Round, 8.0, 1.5, 10.0) - 5.0).abs() < 1e-12);
    }
}
