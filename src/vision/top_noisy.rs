//! Top view: tips under pixel noise comparable to their contrast (dark,
//! low-contrast parts: 25–35 DN of tip contrast under 11–16 DN of noise,
//! blurred, 6–7 px tips).
//!
//! Everything that reads a tip through its half-level mask fails there: the
//! mask's threshold stands barely a σ above the background, so noise clumps
//! join it. A good tip's coverage area then reads up to 2.3 × its
//! neighbours' (read damaged), and on an empty grid position the second
//! look's mask runs into its window's border and the tip is read missing
//! although its light is all there. The tip's energy inside a fixed disc
//! ([`super::disc::disc_energy`]) is linear in the image: noise adds
//! zero-mean scatter to it (σ ≈ 0.05–0.09 of a tip's energy there) and no
//! bias, so it is what decides in both cases.

use super::blur_tip;
use super::fit::Similarity;
use super::gray::{Plane, Px};
use super::recipe::Recipe;

/// The least disc energy, as a fraction of the neighbouring tips' median,
/// that makes an empty position's look a whole tip: a missing pin leaves
/// its clearance hole, on the far side of the housing from the tips, whose
/// energy is negative; good tips whose mask ran into the border read
/// 0.87–1.12.
pub(crate) const WHOLE_TIP_ENERGY: f64 = 0.5;
/// ... and the least disc energy in σ of its noise (the pixel noise summed
/// over the disc).
pub(crate) const WHOLE_TIP_SIGMAS: f64 = 5.0;

/// What the second look at an empty position knows under blur.
pub(crate) struct EmptyLook<'a, P: Px> {
    pub plane: &'a Plane<'a, P>,
    pub sign: f32,
    pub recipe: &'a Recipe,
    pub sim: &'a Similarity,
    pub blur_sigma: f64,
    pub min_pitch_px: f64,
    /// Radius of the energy disc (`tip_levels::tip_disc_radius`), px.
    pub disc_r: f64,
    /// The tip width at the fitted scale, px.
    pub pin_px: f64,
}

impl<P: Px> EmptyLook<'_, P> {
    /// A whole tip on the empty position `hole` (px) whose half-level mask
    /// ran into the window's border through noise (`noise`: the look's
    /// pixel σ; `level`: the housing's level there; `energy`: the median
    /// disc energy of the neighbouring tips): its disc energy at the
    /// position is at least [`WHOLE_TIP_ENERGY`] of the neighbours' and
    /// [`WHOLE_TIP_SIGMAS`] σ, and the blurred-tip model
    /// ([`blur_tip::fit_tip`], started at the hole) settles on a tip
    /// brighter than its hole within `OFF_HOLE` tip widths of it. Returns
    /// the model's centre (the mask's centroid is the noise clumps') and the
    /// disc energy there over the neighbours'.
    pub fn whole_tip(
        &self,
        hole: (f64, f64),
        noise: f32,
        level: f32,
        energy: f64,
    ) -> Option<((f64, f64), f64)> {
        if !(energy > 0.0) {
            return None;
        }
        let e0 = super::disc::disc_energy(self.plane, self.sign, hole, self.disc_r, level);
        let sigma = noise as f64 * (std::f64::consts::PI * self.disc_r * self.disc_r).sqrt();
        if e0 < WHOLE_TIP_ENERGY * energy || e0 < WHOLE_TIP_SIGMAS * sigma {
            return None;
        }
        let prior = blur_tip::prior_at(
            self.recipe,
            self.sim,
            hole,
            self.blur_sigma,
            self.min_pitch_px,
        );
        let f = blur_tip::fit_tip(self.plane, self.sign, hole, &prior)?;
        if (f.x - hole.0).hypot(f.y - hole.1) > super::tip_levels::OFF_HOLE * self.pin_px {
            return None;
        }
        let e = super::disc::disc_energy(self.plane, self.sign, (f.x, f.y), self.disc_r, level);
        Some(((f.x, f.y), e / energy))
    }
}
