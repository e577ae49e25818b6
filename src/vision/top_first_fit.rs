//! The grid's first fit to the tips on the recipe's window: which tips
//! enter it, and what a single tip can give when it is the only one.

use super::fit::{self, Similarity};
use super::grid;
use super::recipe::Recipe;
use super::tip_levels::Candidate;
use super::top_outline::FEW_PINS;

/// The fewest tips in the window whose median area is the reference for a
/// whole tip: on a 2 × 2 with one tip damaged and one bent (Rust 960 554)
/// the median of four let the damaged tip in, and the fit of three turned
/// by 6.5° to absorb the bend (read ok); a few tips keep the nominal.
const MIN_PEERS: usize = 5;

/// The pins the first fit uses: nominal part-frame points (mm) and the
/// tips' image points (px), and the one tip's area when only one is found
/// on a part of a few positions (the scale's last resort).
pub(super) struct FitPoints {
    pub model: Vec<(f64, f64)>,
    pub image: Vec<(f64, f64)>,
    pub one_area: Option<f64>,
}

impl FitPoints {
    /// The tips in the window (`in_win`: candidate index and position)
    /// whose area is a whole tip's, or all of them when fewer than two are.
    ///
    /// A damaged tip is told by its area against its peers' median (or
    /// `tip_px0` with fewer than [`MIN_PEERS`]): blur grows every coverage area
    /// alike (Rust 955 085, blur 2.4 px on 5.8 px tips: 1.46–1.87 ×
    /// nominal), and against the nominal only two tips of 25 were kept,
    /// whose exact fit stood 8 % off in scale and 2° off in rotation, so
    /// that three tips fell outside their positions' reach and were
    /// counted as debris.
    ///
    /// One tip found is the scale's last resort (`one_tip`) only on a part
    /// of at most [`FEW_PINS`] + 1 positions: one tip of many found says the others went unseen
    /// more likely than missing (Rust 925 446, a 2 × 17 under σ 16 DN
    /// noise, stays an error that says so).
    pub fn of(
        cands: &[Candidate],
        in_win: &[(usize, (u32, u32))],
        recipe: &Recipe,
        tip_px0: f64,
        one_tip: bool,
    ) -> Self {
        let [ta_lo, ta_hi] = recipe.tip_area();
        let mut areas: Vec<f64> = in_win.iter().map(|&(ci, _)| cands[ci].m.area_px).collect();
        let area_ref = match grid::median(&mut areas) {
            Some(m) if in_win.len() >= MIN_PEERS && m > 0.0 => m,
            _ => tip_px0,
        };
        let (mut model, mut image, mut area) = (Vec::new(), Vec::new(), Vec::new());
        let (mut model_all, mut image_all, mut area_all) = (Vec::new(), Vec::new(), Vec::new());
        for &(ci, (r, col)) in in_win {
            let m = &cands[ci].m;
            let uv = recipe.nominal_uv_mm(r, col);
            model_all.push(uv);
            image_all.push((m.x, m.y));
            area_all.push(m.area_px);
            let a = m.area_px / area_ref;
            if a >= ta_lo && a <= ta_hi {
                model.push(uv);
                image.push((m.x, m.y));
                area.push(m.area_px);
            }
        }
        if model.len() < 2 {
            (model, image, area) = (model_all, image_all, area_all);
        }
        let few_positions = one_tip && recipe.positions().len() <= FEW_PINS + 1;
        let one_area = (area.len() == 1 && few_positions).then(|| area[0]);
        FitPoints {
            model,
            image,
            one_area,
        }
    }

    /// The first similarity from `init` (the lattice's): the consensus fit
    /// of two or more pins, or one pin's translation; with (inliers, RMS px).
    pub fn first_fit(
        &self,
        recipe: &Recipe,
        init: Similarity,
        fixed: Option<f64>,
        warnings: &mut Vec<String>,
    ) -> (Similarity, usize, f64) {
        let (model, image) = (&self.model, &self.image);
        if model.len() >= 2 {
            let tau = recipe.tolerance.position_mm * init.s;
            return match fit::consensus_similarity(model, image, fixed, Some(init), 0.1, tau) {
                Some(f) => {
                    let n = f.inlier.iter().filter(|b| **b).count();
                    (f.sim, n, f.rms_px)
                }
                None => (init, 0, f64::NAN),
            };
        }
        if model.len() != 1 {
            return (init, 0, f64::NAN);
        }
        // One pin: translation from it, rotation from the lattice (0
        // without neighbours).
        let mut s = init;
        if fixed.is_none()
            && let Some(a) = self.one_area
        {
            // No pitch to measure and no mm_per_px: the scale from the
            // tip's own measured area, as `scale_one_tip` takes it when the
            // scale search has only one tip (a 1 × 3 with both end pins
            // missing, Rust 955 323: an error before, though the two empty
            // positions make it a plain Fail).
            s.s = (a / recipe.tip_area_mm2()).sqrt();
            warnings.push("only one pin found and no mm_per_px: the scale taken from its tip's area (so that area is not judged)".into());
        }
        let q = s.apply(model[0].0, model[0].1);
        s.tx += image[0].0 - q.0;
        s.ty += image[0].1 - q.1;
        warnings.push("only one pin found: grid rotation taken as the image axes'".into());
        (s, 1, 0.0)
    }
}
