//! Top view: the blobs no pin position took, judged one by one as extras
//! (debris) or set aside with the reason (a housing edge, a ripple of a
//! brighter structure, texture, noise lifting a fainter structure, too far
//! from the housing). Split from `top.rs`: the judging reads every blob
//! against the local tip levels the pins established there.

use super::detect::CoarseSearch;
use super::fit::Similarity;
use super::gray::{Plane, Px};
use super::housing::rect_distance;
use super::measure::{self, Localiser};
use super::recipe::ExtrasRule;
use super::result::ExtraResult;
use super::tip_levels::{
    CORE_SIGMAS, Candidate, LocalLevels, MIN_LOCAL_CONTRAST, MIN_PROMINENCE, MIN_SNR,
    MIN_TIP_CONTRAST, contrast_ratio, core_contrast, core_sigma, local_contrast, snr_of,
};
use super::top_fixture::fixture_seeds;
use super::top_ridge::{Probe, ridge_level};
use super::top_shoulder::{Shoulder, measure_shoulder};

/// Where the top view stands when it judges the blobs left over.
pub(super) struct Leftovers<'a, P: Px> {
    pub plane: &'a Plane<'a, P>,
    pub sign: f32,
    pub localiser: Localiser,
    pub dilate: usize,
    /// Every measured blob, and which of them a pin position took.
    pub cands: &'a [Candidate],
    pub used: &'a [bool],
    /// A tip's area in pixels at the fitted scale.
    pub tip_px: f64,
    pub levels: &'a LocalLevels,
    pub sim: &'a Similarity,
    /// The housing (or the grid grown by half a pitch) in the part frame, mm.
    pub rect: [f64; 4],
    pub pitch_mm: f64,
    /// The coarse search, whose image the fixture pass reads.
    pub coarse: &'a CoarseSearch,
    /// The grid's extent grown by 0.4 pitch (part frame, mm): beyond it
    /// the housing's margin and the fixture.
    pub grid: [f64; 4],
}

impl<P: Px> Leftovers<'_, P> {
    /// A tip's width (px): the side of a square of the tip's area.
    fn pin_px(&self) -> f64 {
        (self.tip_px * 4.0 / std::f64::consts::PI).sqrt()
    }

    /// Where a tip is: every candidate a position took and every intact
    /// tip the local levels were read from (a tip placed by the second
    /// look keeps no candidate: Rust 860 498).
    fn tips(&self) -> Vec<(f64, f64)> {
        self.cands
            .iter()
            .zip(self.used)
            .filter(|&(_, &u)| u)
            .map(|(c, _)| (c.m.x, c.m.y))
            .chain(self.levels.refs.iter().map(|r| (r.0, r.1)))
            .collect()
    }

    /// The level of the brightest straight ridge through blob `m`
    /// (`top_ridge`), read beyond its reach (1.3 of its equivalent radius,
    /// half a tip width and 2.5 edge σ) over discs a fifth of a tip wide,
    /// with sides within 0.75 tip widths of a tip unread.
    fn ridge_through(&self, m: &measure::BlobMeasure, tb: (f32, f32)) -> Option<f64> {
        self.ridge_at((m.x, m.y), m.area_px, m.edge_sigma, tb)
    }

    /// [`Self::ridge_through`] for a blob of `area_px` pixels at `c` whose
    /// edges spread by `edge_sigma`.
    fn ridge_at(
        &self,
        c: (f64, f64),
        area_px: f64,
        edge_sigma: f64,
        tb: (f32, f32),
    ) -> Option<f64> {
        let pin_px = self.pin_px();
        let reach = (1.3 * (area_px / std::f64::consts::PI).sqrt()
            + 0.5 * pin_px
            + 2.5 * edge_sigma.clamp(0.3, 3.0))
        .max(pin_px);
        let probe = Probe {
            reach,
            r_disc: (0.2 * pin_px).max(1.0),
            clear: 0.75 * pin_px,
        };
        ridge_level(self.plane, self.sign, c, probe, tb, &self.tips())
    }

    /// Whether a protrusion lies within the distance rule of the housing and
    /// has at least the rule's area.
    fn within_rule(&self, rule: &ExtrasRule, sh: &Shoulder) -> bool {
        let (u, v) = self.sim.inverse(sh.x, sh.y);
        rect_distance(u, v, self.rect) <= rule.max_distance_pitch * self.pitch_mm
            && sh.area_px / self.tip_px >= rule.min_area_ratio
    }
}

/// The blobs no pin took: (extras counted, blobs set aside with why).
pub(super) fn judge_extras<P: Px>(
    lo: &Leftovers<'_, P>,
    rule: &ExtrasRule,
) -> (Vec<ExtraResult>, Vec<ExtraResult>) {
    let Leftovers {
        plane,
        sign,
        localiser,
        dilate,
        cands,
        used: cand_used,
        tip_px,
        levels,
        sim,
        rect,
        pitch_mm: px_mm,
        ..
    } = *lo;
    let mut extras = Vec::new();
    let mut ignored = Vec::new();
    let max_dist = rule.max_distance_pitch * px_mm;
    for (ci, c) in cands.iter().enumerate() {
        if cand_used[ci] {
            continue;
        }
        let ar0 = c.m.area_px / tip_px;
        if ar0 < 0.5 * rule.min_area_ratio {
            continue;
        }
        // The blob against what a tip looks like here: its area counted in
        // tip-bright units (a faint stain weighs little), its level as a
        // fraction of the local tip level, its contrast against the local
        // noise floor.
        // A blob whose half-level mask runs past its window (debris on the
        // housing's edge, joined at half level to a brighter fixture) is
        // cut from that structure where it separates and measured above
        // the saddle (`measure_blob_split`); what never separates stays a
        // housing edge or frame.
        let apart = c.m.touches_border;
        let remeasure = |floor: Option<f32>| {
            measure::measure_blob_split(plane, sign, c.roi, c.seed, localiser, dilate, floor, apart)
        };
        let expected = levels
            .expected(c.m.x, c.m.y)
            .map(|(t, b)| dimmed_levels(t, b, c.m.lo, sign));
        let (m, rho) = match expected {
            Some((t, b)) => {
                let m = remeasure(Some(t)).unwrap_or_else(|| c.m.clone());
                let hi = if apart { m.hi } else { c.m.hi };
                (m, Some(contrast_ratio(hi, t, b)))
            }
            None if apart => (remeasure(None).unwrap_or_else(|| c.m.clone()), None),
            None => (c.m.clone(), None),
        };
        let cut = apart && !m.touches_border;
        // How far a cut blob stands above the saddle where it joins the
        // structure, as a fraction of the local tip contrast: a ripple of a
        // housing rim or a shading corner stands a few hundredths, debris a
        // sizeable part of it.
        let prominence = match expected {
            Some((t, b)) if cut => contrast_ratio(m.hi, t, b) - contrast_ratio(m.lo, t, b),
            _ => 1.0,
        };
        let ar = m.area_px / tip_px;
        let snr = if apart { snr_of(&m) } else { snr_of(&c.m) };
        let (u, v) = sim.inverse(m.x, m.y);
        let dist = rect_distance(u, v, rect);
        let mut e = ExtraResult {
            x_px: m.x,
            y_px: m.y,
            area_ratio: ar,
            distance_mm: Some(dist),
            ignored_because: None,
            contrast_ratio: rho,
            snr: Some(snr),
            reason: None,
        };
        let rho_v = rho.unwrap_or(1.0);
        // The level of its core, not selected by the noise: the mean over
        // a disc of the smallest area the rule counts, at its centre.
        let core_px = rule.min_area_ratio * tip_px;
        let core =
            expected.and_then(|(t, b)| core_contrast(plane, sign, (m.x, m.y), core_px, t, b));
        let core_v = core.unwrap_or(1.0);
        // The core's own noise, and how far the blob stands above its own
        // surround (both as fractions of the local tip contrast).
        let meas = if apart { &m } else { &c.m };
        let (core_sd, local) = match expected {
            Some((t, b)) => (
                core_sigma(meas.noise, core_px, t, b),
                local_contrast(meas, t, b),
            ),
            None => (0.0, 1.0),
        };
        // Debris across the housing's edge that the structure beside it
        // (as bright as the debris) swallows: measured as its protrusion
        // into the housing (`top_shoulder`), and counted when that alone
        // is a tip-bright blob clear of noise.
        // Bright parts only: on a dark part the housing's chamfer band is
        // darker than the housing, a ridge whose noise clumps (Rust
        // 870 261, vignetting 0.45) and a narrow housing narrower than the
        // opening's square (860 498) protrude as well.
        let shoulder = match expected {
            Some((t, b))
                if sign > 0.0
                    && (m.touches_border
                        || (cut && (prominence < MIN_PROMINENCE || snr < MIN_SNR))) =>
            {
                shoulder_extra(
                    lo,
                    c.seed,
                    t,
                    b,
                    core_px,
                    MIN_TIP_CONTRAST,
                    MIN_LOCAL_CONTRAST,
                )
                .map(|p| (p.sh, p.rise, p.level))
            }
            _ => None,
        };
        if let Some((sh, rise, level)) = shoulder.filter(|s| {
            // Two coarse blobs on one piece of debris find one protrusion.
            let new = extras.iter().all(|e: &ExtraResult| {
                (e.x_px - s.0.x).hypot(e.y_px - s.0.y) > 0.5 * tip_px.sqrt()
            });
            new && lo.within_rule(rule, &s.0)
        }) {
            extras.push(shoulder_result(lo, rule, &sh, rise, level, FROM_OUTLINE));
        } else if ar < rule.min_area_ratio {
            if ar >= 0.5 * rule.min_area_ratio {
                e.ignored_because = Some(format!(
                    "area {ar:.2} of a tip (in tip-bright units), below {}",
                    rule.min_area_ratio
                ));
                ignored.push(e);
            }
        } else if m.touches_border {
            if ar0 >= rule.min_area_ratio {
                e.ignored_because = Some(
                    "part of a larger structure (it runs past its measuring window): a housing edge or frame, not a separate blob".into(),
                );
                ignored.push(e);
            }
        } else if prominence < MIN_PROMINENCE {
            e.ignored_because = Some(format!(
                "joined to a larger bright structure, standing {prominence:.2} of the local tip contrast above their saddle (below {MIN_PROMINENCE}): a ripple of that structure"
            ));
            ignored.push(e);
        } else if rho_v < MIN_TIP_CONTRAST {
            if ar0 >= rule.min_area_ratio {
                e.ignored_because = Some(format!(
                    "its level reaches {rho_v:.2} of the local tip level, below {MIN_TIP_CONTRAST}: housing or fixture structure, not a tip-bright blob"
                ));
                ignored.push(e);
            }
        } else if !cut && local < MIN_LOCAL_CONTRAST {
            e.ignored_because = Some(format!(
                "it stands {local:.2} of the local tip contrast above its own surround, below {MIN_LOCAL_CONTRAST}: a bump of a structure as bright as the tips (a bright fixture's texture), not a separate blob"
            ));
            ignored.push(e);
        } else if core_v < MIN_TIP_CONTRAST {
            e.ignored_because = Some(format!(
                "its core (the mean over {} of a tip's area at its centre) reaches {core_v:.2} of the local tip level, below {MIN_TIP_CONTRAST}: its mask's level {rho_v:.2} was noise lifting a fainter structure (a housing rim, shading)",
                rule.min_area_ratio
            ));
            ignored.push(e);
        } else if core_v - CORE_SIGMAS * core_sd < MIN_TIP_CONTRAST {
            e.ignored_because = Some(format!(
                "its core reaches {core_v:.2} ± {core_sd:.2} (noise σ) of the local tip level, not {CORE_SIGMAS} σ above {MIN_TIP_CONTRAST}: noise clumps on a fainter structure (a housing rim, shading) can read that high"
            ));
            ignored.push(e);
        } else if let Some(ridge) = expected
            .and_then(|tb| lo.ridge_through(meas, tb))
            .filter(|&r| core_v - CORE_SIGMAS * core_sd - r < MIN_LOCAL_CONTRAST)
        {
            e.ignored_because = Some(format!(
                "its core reaches {core_v:.2} ± {core_sd:.2} (noise σ) of the local tip level, not {MIN_LOCAL_CONTRAST} beyond {CORE_SIGMAS} σ above the {ridge:.2} of a straight ridge through it: a clump of a band or of a surface that bright (the housing's chamfer, a bright fixture), not a separate blob"
            ));
            ignored.push(e);
        } else if snr < MIN_SNR {
            e.ignored_because = Some(format!(
                "{snr:.1} σ above the local noise floor, below {MIN_SNR}"
            ));
            ignored.push(e);
        } else if dist > max_dist {
            e.ignored_because = Some(format!(
                "{dist:.2} mm from the housing, beyond {} pitch",
                rule.max_distance_pitch
            ));
            ignored.push(e);
        } else {
            e.reason = Some(format!(
                "area {ar:.2} of a tip ≥ {}, level {} of the local tip level, {} σ above the local noise, {dist:.2} mm from the housing (≤ {max_dist:.2})",
                rule.min_area_ratio,
                rho.map_or("n/a".to_string(), |r| format!("{r:.2}")),
                // A noise-free floor (a clean rendering) has no finite SNR.
                if snr.is_finite() {
                    format!("{snr:.0}")
                } else {
                    "∞".to_string()
                },
            ));
            if cut && let Some(r) = e.reason.as_mut() {
                r.push_str(
                    "; cut from the brighter structure it touches, measured above their saddle",
                );
            }
            extras.push(e);
        }
    }
    fixture_extras(lo, rule, &mut extras);
    (extras, ignored)
}

/// How a shoulder extra's reason ends: what it was measured against.
const FROM_OUTLINE: &str = "on the edge of a structure as bright as itself, measured as its protrusion from that structure's outline";
const ON_FIXTURE: &str = "on the fixture beside the housing, found by its rise over the fixture's own noise and measured as its protrusion from the fixture";

/// An extra measured by `top_shoulder` (`rise`, `level` as fractions of the
/// local tip contrast), with the tests it passed in its reason.
fn shoulder_result<P: Px>(
    lo: &Leftovers<'_, P>,
    rule: &ExtrasRule,
    sh: &Shoulder,
    rise: f64,
    level: f64,
    how: &str,
) -> ExtraResult {
    let max_dist = rule.max_distance_pitch * lo.pitch_mm;
    let (u, v) = lo.sim.inverse(sh.x, sh.y);
    let dist = rect_distance(u, v, lo.rect);
    let ar = sh.area_px / lo.tip_px;
    let snr = sh.snr();
    ExtraResult {
        x_px: sh.x,
        y_px: sh.y,
        area_ratio: ar,
        distance_mm: Some(dist),
        ignored_because: None,
        contrast_ratio: Some(level),
        snr: Some(snr),
        reason: Some(format!(
            "area {ar:.2} of a tip ≥ {}, level {level:.2} of the local tip level, {snr:.0} σ above the local noise, {dist:.2} mm from the housing (≤ {max_dist:.2}); {how} ({rise:.2} of the local tip contrast above it)",
            rule.min_area_ratio
        )),
    }
}

/// How far the fixture pass's debris must rise over the fixture, in the
/// pixel noise σ (mean over its mask). A bright fixture can be as bright as
/// the tips (Python 590 052: fixture 90.7, tips 85.8), so reaching the tip
/// level says nothing there, and 0.25 of a low tip contrast can lie under
/// the noise (590 052, 590 105: contrast 0.33–0.37, noise 10–14 DN, large
/// tips): noise clumps on the fixture passed. A texture clump after JPEG
/// smoothing passes even this (590 341); `top_fixture::SEED_SIGMAS`,
/// measured at the blob's scale, is what refuses it.
/// Debris met rises 4.5 σ (Rust 840 916) to over 10 σ (Python 620 154).
const FIXTURE_SIGMAS: f32 = 3.0;

/// The level (fraction of the local tip level) the fixture pass's debris
/// must reach, where blobs on the housing must reach `MIN_TIP_CONTRAST`.
/// Debris is drawn at a tip's rim level, 0.6–0.8 of its peak on a bright
/// part, and on a bright fixture beside a gradient and vignetting it read
/// 0.48 while rising 0.44 of the tip contrast over the fixture with its
/// core 20 σ clear (Rust 945 439); a fixture clump that bright is refused
/// by its rise (`MIN_LOCAL_CONTRAST`, `FIXTURE_SIGMAS`) and by the seed's
/// own test at its scale (`top_fixture::SEED_SIGMAS`). Measured: on the
/// tuning sets (Rust 910/925/935/945 000, Python 590/640 000) this finds
/// 945 439's debris and changes no other verdict.
const FIXTURE_MIN_LEVEL: f64 = 0.4;

/// How far above the fixture's median top-hat, in robust σ of it at the
/// blob's scale (`top_fixture::FixtureSeed::z`), a compact blob on a bright
/// part's fixture must rise to be counted without `FIXTURE_SIGMAS` of the
/// pixel noise. Under heavy pixel noise, debris of a few tips' area rises
/// one to two pixel σ over a bright fixture (Rust 1 300 923: 2.0 σ, the
/// blob 13 σ at its scale; 1 300 922, 1 301 040: 0.9–1.3 σ) and was never
/// counted: a per-pixel test asks of a blob what only its mean can show.
/// The blob-scale σ holds the fixture's texture as well as the noise, so
/// it is what tells a texture clump from debris. Measured (every
/// fixture-pass protrusion on bright parts of Rust 900 000–930 000 and
/// 1 300 000, 1 500 images each, and Python 590 000, 720 000 and
/// 730 000, 400 each): texture and noise clumps that pass every other
/// test stand 5.2–6.3 σ (Python 590 105 5.6, 730 107 6.3; Rust 910 676
/// 5.2), debris found this way 7.8–83 σ.
const FIXTURE_COMPACT_SIGMAS: f32 = 7.0;

/// The largest area (in tips, tip-bright units) a blob may have to be
/// counted by its blob-scale rise (`FIXTURE_COMPACT_SIGMAS`). A bright
/// fixture's texture swells broad and low: on Python 590 290 (contrast
/// 0.30, texture beside a low tip contrast) and 730 145 its clumps
/// stood 7.1–7.7 σ at the blob's scale over 3.7–5.5 tips. Debris at least
/// that large and that faint has to show `FIXTURE_SIGMAS` per pixel; the
/// debris both renderers draw is 0.33–2.5 tips.
const FIXTURE_COMPACT_AREA: f64 = 2.5;

/// The rise over the fixture (and the core's, `CORE_SIGMAS` σ below its
/// mean), as a fraction of the local tip contrast, a compact blob counted
/// by its blob-scale rise must reach, where other protrusions must reach
/// `MIN_LOCAL_CONTRAST`. Debris drawn at a tip's rim level over a bright
/// fixture can rise as little as 0.18 of the tip contrast (Rust: rim
/// 175 DN over a 140 DN fixture against 243 DN tips on a 50 DN housing);
/// met at 0.184–0.247 (1 290 204, 1 301 391, 1 300 546). In
/// the measured sets the clumps that stand `FIXTURE_COMPACT_SIGMAS` rise
/// at most 0.12 (Rust 930 873: 53–55 σ over a flat fixture).
const FIXTURE_COMPACT_MIN_RISE: f64 = 0.15;

/// Debris on the fixture that never became a candidate
/// (`top_fixture` says where to look): each place measured as a
/// protrusion (`shoulder_extra`, the same tests as debris across the
/// housing's edge), counted when it is new, lies within the distance rule,
/// has at least the rule's area and shows itself over the fixture: it
/// rises `MIN_LOCAL_CONTRAST` and `FIXTURE_SIGMAS` of the pixel noise
/// above it, or, on a bright part, it is compact
/// (`FIXTURE_COMPACT_AREA`), its seed stands `FIXTURE_COMPACT_SIGMAS` at
/// its scale and it rises `FIXTURE_COMPACT_MIN_RISE`.
fn fixture_extras<P: Px>(lo: &Leftovers<'_, P>, rule: &ExtrasRule, extras: &mut Vec<ExtraResult>) {
    let pin_px = lo.pin_px();
    let core_px = rule.min_area_ratio * lo.tip_px;
    let bright = lo.sign > 0.0;
    let seeds = fixture_seeds(lo.coarse, lo.sim, lo.grid, pin_px, !bright);
    let min_rise = if bright {
        FIXTURE_COMPACT_MIN_RISE
    } else {
        MIN_LOCAL_CONTRAST
    };
    for seed in seeds {
        let far = |x: f64, y: f64| {
            extras
                .iter()
                .all(|e| (e.x_px - x).hypot(e.y_px - y) > 0.5 * pin_px)
        };
        if !far(seed.at.0, seed.at.1) {
            continue;
        }
        let Some((t, b)) = lo.levels.expected(seed.at.0, seed.at.1) else {
            continue;
        };
        let Some(p) = shoulder_extra(lo, seed.at, t, b, core_px, FIXTURE_MIN_LEVEL, min_rise)
        else {
            continue;
        };
        let sh = &p.sh;
        if !bright && on_dark_band(lo, sh, (t, b), core_px) {
            continue;
        }
        let per_pixel = sh.rise >= FIXTURE_SIGMAS * sh.noise && p.clear >= MIN_LOCAL_CONTRAST;
        let compact = bright
            && seed.z >= FIXTURE_COMPACT_SIGMAS
            && sh.area_px / lo.tip_px <= FIXTURE_COMPACT_AREA;
        if far(sh.x, sh.y) && (per_pixel || compact) && lo.within_rule(rule, sh) {
            extras.push(shoulder_result(lo, rule, sh, p.rise, p.level, ON_FIXTURE));
        }
    }
}

/// A protrusion `shoulder_extra` accepted, with its rise and level as
/// fractions of the local tip contrast.
struct Protrusion {
    sh: Shoulder,
    rise: f64,
    level: f64,
    /// The lesser of the rise and the core's mean less `CORE_SIGMAS` σ.
    clear: f64,
}

/// Whether a protrusion the fixture pass found on a dark part is a piece of
/// the housing's chamfer band: its core does not stand `MIN_LOCAL_CONTRAST`
/// beyond `CORE_SIGMAS` σ above the straight ridge through it
/// ([`Leftovers::ridge_at`]), the test a candidate blob already passes.
/// The chamfer band, darker than the housing, is a ridge in sign space
/// narrower than the fixture pass's opening, so the opening leaves it in
/// the residual whole; where JPEG blocks and noise make one stretch of it
/// darker, the half-level mask holds that stretch alone, clear of the
/// window, and it was counted (Rust 1 080 683: two "extras" of 3.5 and 5
/// tips along a 3 × 18's lower edge, JPEG 79, contrast 0.43, their cores
/// 0.03–0.08 of the tip contrast above the band). Debris, as dark as a
/// tip's rim, stands far above a band it lies on.
fn on_dark_band<P: Px>(
    lo: &Leftovers<'_, P>,
    sh: &Shoulder,
    (t, b): (f32, f32),
    core_px: f64,
) -> bool {
    let core = contrast_ratio(sh.base + sh.core, t, b);
    let core_sd = core_sigma(sh.noise, core_px, t, b);
    // The shoulder's edge spread is not measured; a pixel's worth is the
    // envelope's middle and only sets how far out the ridge is read.
    lo.ridge_at((sh.x, sh.y), sh.area_px, 1.0, (t, b))
        .is_some_and(|r| core - CORE_SIGMAS * core_sd - r < MIN_LOCAL_CONTRAST)
}

/// A blob set aside as part of, or a ripple of, a brighter structure,
/// measured again as its protrusion from that structure's outline
/// (`top_shoulder`), when the protrusion is separate (its mask clear of
/// the window), off every pin, stands `min_rise` (a fraction of the local
/// tip contrast, `t`, `b`) above the outline with its core `CORE_SIGMAS` σ
/// above that too, reaches `min_level` of the tip level, and `MIN_SNR`
/// above the noise. Area and distance are left to the caller.
fn shoulder_extra<P: Px>(
    lo: &Leftovers<'_, P>,
    seed: (f64, f64),
    t: f32,
    b: f32,
    core_px: f64,
    min_level: f64,
    min_rise: f64,
) -> Option<Protrusion> {
    let pin_px = lo.pin_px();
    let sh = measure_shoulder(lo.plane, lo.sign, seed, pin_px, t, core_px)?;
    let tipc = (t - b) as f64;
    if sh.touches_border || tipc <= 0.0 {
        return None;
    }
    // A tip is a protrusion too: none within 0.75 tip widths of a tip a
    // position took, nor of an intact tip the local levels were read from
    // (a tip placed by the second look keeps no candidate: Rust 860 498).
    let on_pin = lo
        .tips()
        .iter()
        .any(|&(x, y)| (x - sh.x).hypot(y - sh.y) < 0.75 * pin_px);
    let rise = sh.rise as f64 / tipc;
    let level = contrast_ratio(sh.base + sh.rise, t, b);
    let core_sd = sh.noise as f64 / core_px.max(1.0).sqrt() / tipc;
    let core = sh.core as f64 / tipc;
    let clear = rise.min(core - CORE_SIGMAS * core_sd);
    (!on_pin && clear >= min_rise && level >= min_level && sh.snr() >= MIN_SNR).then_some(
        Protrusion {
            sh,
            rise,
            level,
            clear,
        },
    )
}

/// The tip and background levels the nearest tips establish (`t`, `b`, in
/// `sign` space), carried to a blob whose own surround (`lo`, the median of
/// its window's border) is darker than the tips' surround: vignetting and a
/// gradient scale the light, so where the housing reads a fraction g of its
/// level at the tips, a tip there would read g of its level too. Only a
/// dark part needs it: there the dimming moves every housing structure
/// toward the tips' (dark) level, and the housing's chamfer band in a
/// vignetted corner read 0.57–0.87 of the tip level against the tips'
/// levels (Rust 840 224, 840 554), 0.2–0.3 against its own place's. On a
/// bright part dimming takes structures away from the tip level, and a
/// surround brighter than the tips' (a bright fixture beside the housing) is
/// no illumination to correct for, so the levels stay as they are.
pub(super) fn dimmed_levels(t: f32, b: f32, lo: f32, sign: f32) -> (f32, f32) {
    if sign >= 0.0 || b >= 0.0 || lo >= 0.0 {
        return (t, b);
    }
    // In sign space a dark part's levels are negative: g = lo / b is the
    // ratio of the real (positive) levels.
    let g = lo / b;
    if g < 1.0 && g > 0.0 {
        (t * g, b * g)
    } else {
        (t, b)
    }
}
