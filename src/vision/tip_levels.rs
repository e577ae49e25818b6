//! What a tip looks like where it stands: the measured candidate blobs,
//! the tip and background levels expected at a place from the nearest
//! intact tips, a blob's contrast against them and against the local noise,
//! and a tip's area ratio that survives blur. The top view's verdicts on
//! damaged tips and extras are made from these.

use super::grid;
use super::measure::{BlobMeasure, Roi};
use super::recipe::PinShape;

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
/// comparable to the tip) its energy over the median of the four nearest
/// other tips' (`assigned`: the pin-like tips on grid positions).
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
    let mut d: Vec<(f64, f64)> = assigned
        .iter()
        .filter(|&&o| o != ci)
        .map(|&o| {
            let q = &cands[o].m;
            ((q.x - m.x).hypot(q.y - m.y), q.energy)
        })
        .collect();
    if d.len() < 2 {
        return abs;
    }
    d.sort_by(|a, b| a.0.total_cmp(&b.0));
    let mut e: Vec<f64> = d.iter().take(4).map(|p| p.1).collect();
    match grid::median(&mut e) {
        Some(med) if med > 0.0 => m.energy / med,
        _ => abs,
    }
}

/// Blur (edge σ) beyond this fraction of the tip width: tip areas are
/// judged against the neighbouring tips' energy.
pub(crate) const BLUR_RELATIVE: f64 = 0.08;

/// Blur σ beyond the tip's outer radius that the fixed disc of a tip's
/// energy reaches (`tip_disc_radius`): 2 σ holds all but about 2 % of a
/// blurred edge's light.
pub(crate) const DISC_BLUR_SIGMAS: f64 = 2.0;

/// Radius (px) of the fixed disc in which a blurred tip's energy is summed
/// ([`super::measure::disc_energy`]): the nominal tip's outer radius (a
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

#[cfg(test)]
mod tests {
    use super::*;

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
