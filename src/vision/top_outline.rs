//! The housing's outline as a second ruler for the grid, one the pins do
//! not move. Two or three pins do not over-determine a similarity: its
//! rotation, centre (and free scale) follow one pin's bend, which then
//! shows as a share or not at all; where the outline is measured cleanly,
//! the grid's rotation and centre are taken from it (the scale from the
//! recipe's `mm_per_px` or the pins) and every pin shows its own
//! deviation. From four pins on the pins place the grid, but with a few
//! of them and one or two bent, which are bent is a choice the pins alone
//! may make badly; the outline then chooses the pins the grid is fitted
//! to. Kept apart from `top.rs` (the pipeline).

use super::fit::{self, RobustFit, Similarity};
use super::gray::{Plane, Px};
use super::grid::Lattice;
use super::housing_pose::{HousingPose, measure_pose};

/// Up to this many pins the similarity fit cannot tell one pin's bend from
/// the grid's pose (four parameters, or three with mm_per_px known): the
/// housing's outline then places the grid ([`measure_pose`]).
pub(super) const FEW_PINS: usize = 3;

/// The most the housing's outline may be turned against the pins' fit
/// and still be the part's: one pin of two bent across their line by 0.3
/// pitch (the most the assignment accepts) turns their fit by ≈ 0.3 rad.
const MAX_HOUSING_TURN: f64 = 0.3;

/// Frames turned from the pins' fit (rad) in which the outline is
/// measured again where it is not found in the fit's own: two bent pins
/// of a 2 × 2 turned the fit 0.1 rad off the part (Rust 1 211 377), and
/// a side's profiles, laid across the fit's axes, then run along the
/// edge. Of the frames that find it, the one nearest the outline's own
/// axes (the least turn left) is kept.
const TURNS: [f64; 4] = [-0.05, 0.05, -0.1, 0.1];

/// How many times further off its grid than any pin it keeps each pin must
/// stand that a consensus seeded by the long sides alone leaves out,
/// where it leaves out more than the pins' own fit ([`Outline::consensus`]).
const STANDS_APART: f64 = 2.0;

/// The coarse outline's corners (px) and its extent in a fit's frame
/// ([u0, u1, v0, v1], mm).
pub(super) type Rect = ([(f64, f64); 4], [f64; 4]);

/// What the outline is measured from: the coarse outline in lattice units
/// (`find_housing`) and the part's geometry.
pub(super) struct Outline<'a, P: Px> {
    pub plane: &'a Plane<'a, P>,
    pub lat: &'a Lattice,
    /// Coarse outline [a0, a1, b0, b1] in lattice units.
    pub housing_lat: Option<[f64; 4]>,
    /// Half the pins' field along u and v, mm.
    pub half_mm: (f64, f64),
    /// The smallest pitch between neighbouring pins, mm.
    pub pin_pitch_min: f64,
    /// The recipe's position tolerance, mm.
    pub position_mm: f64,
    /// The recipe's scale (px per mm), when it gives `mm_per_px`.
    pub fixed: Option<f64>,
}

impl<P: Px> Outline<'_, P> {
    /// The coarse outline in the frame of `sim`.
    pub fn rect(&self, sim: &Similarity) -> Option<Rect> {
        let h = self.housing_lat?;
        let corners_lat = [(h[0], h[2]), (h[1], h[2]), (h[1], h[3]), (h[0], h[3])];
        let corners_px = corners_lat.map(|(a, b)| self.lat.to_image(a, b));
        let uv: Vec<(f64, f64)> = corners_px.iter().map(|p| sim.inverse(p.0, p.1)).collect();
        let extent_mm = [
            0.5 * (uv[0].0 + uv[3].0),
            0.5 * (uv[1].0 + uv[2].0),
            0.5 * (uv[0].1 + uv[1].1),
            0.5 * (uv[2].1 + uv[3].1),
        ];
        Some((corners_px, extent_mm))
    }

    /// The outline's pose, where it is measured cleanly and is the part's:
    /// turned and shifted no more than a bend could move the pins' fit.
    /// Its `frame` is the grid on the outline (the fit's scale kept).
    fn pose(&self, sim: &Similarity) -> Option<HousingPose> {
        let pose = self.pose_in(sim).or_else(|| {
            let turned = |d: f64| Similarity {
                theta: sim.theta + d,
                ..*sim
            };
            TURNS
                .iter()
                .filter_map(|&d| {
                    let f = turned(d);
                    let p = self.pose_in(&f)?;
                    let h = p.frame(&f);
                    let back = HousingPose {
                        dtheta: h.theta - sim.theta,
                        centre_mm: sim.inverse(h.tx, h.ty),
                        ..p
                    };
                    // The outline must stand turned the frame's way: one
                    // found nearer the fit's own axes had been found there
                    // but for its sides, which a turned frame measures no
                    // better (Rust 911 392: a 1 × 3's long sides, not found
                    // in the fit's frame, found 0.05 rad off it 5.5 px
                    // apart from the truth's centre).
                    (back.dtheta * d >= 0.5 * d * d).then_some((p.dtheta.abs(), back))
                })
                .min_by(|a, b| a.0.total_cmp(&b.0))
                .map(|(_, p)| p)
                .filter(|p| self.holds_in_own_frame(&p.frame(sim)))
        })?;
        let (cu, cv) = pose.centre_mm;
        (pose.dtheta.abs() <= MAX_HOUSING_TURN && cu.hypot(cv) <= 0.3 * self.pin_pitch_min)
            .then_some(pose)
    }

    /// Whether the outline, measured again in the frame it was found to
    /// stand in (`h`), stands there: turned less than 0.01 rad and its
    /// centre within a pixel. A pose found in a turned frame may be a side
    /// taken at the wrong step (a narrow housing beside a brighter
    /// fixture: Rust 1 001 291, found 1.9° the wrong way); the part's own
    /// outline measures square in its own frame.
    fn holds_in_own_frame(&self, h: &Similarity) -> bool {
        self.pose_in(h).is_some_and(|q| {
            let (cu, cv) = q.centre_mm;
            q.dtheta.abs() <= 0.01 && cu.hypot(cv) * h.s <= 1.0
        })
    }

    /// The outline's pose measured in the frame of `sim` as it stands.
    fn pose_in(&self, sim: &Similarity) -> Option<HousingPose> {
        let (_, rect) = self.rect(sim)?;
        measure_pose(self.plane, sim, rect, self.half_mm)
    }

    /// For two or three fit points: the grid on the outline, where every
    /// pin stands near its place on it, and the note that says so.
    pub fn for_few_pins(
        &self,
        sim: &Similarity,
        model: &[(f64, f64)],
        image: &[(f64, f64)],
    ) -> Option<(Similarity, String)> {
        if !(2..=FEW_PINS).contains(&model.len()) {
            return None;
        }
        let pose = self.pose(sim)?;
        let h = pose.frame(sim);
        let far = fit::residuals(model, image, &h)
            .iter()
            .any(|&r| r > 0.35 * self.pin_pitch_min * h.s);
        if far {
            return None;
        }
        let taken = if pose.long_sides_only {
            "its rotation and centre across the row taken from the housing's outline \
             (its long sides; along the row, the pins' centre)"
        } else {
            "its rotation and centre taken from the housing's outline"
        };
        let note = format!(
            "{} pins do not over-determine the grid: {taken}",
            model.len()
        );
        Some((h, note))
    }

    /// For 4–16 fit points: the fit to the pins the outline agrees with
    /// (`fit::consensus_from_seed`). A bent end pin turns the pins' own fit
    /// towards it and a good pin beside it reads bent (Rust 925 154,
    /// 945 284, 955 848). The outline's pose from four sides, or from its
    /// two long sides where an end is lost (then under a stricter rule,
    /// below). `None` where the outline keeps the pins `sim` already keeps,
    /// or is not measured.
    pub fn consensus(
        &self,
        sim: &Similarity,
        model: &[(f64, f64)],
        image: &[(f64, f64)],
    ) -> Option<RobustFit> {
        if !(FEW_PINS + 1..=fit::CONSENSUS_MAX_POINTS).contains(&model.len()) {
            return None;
        }
        let tau = self.position_mm * sim.s;
        let pose = self.pose(sim)?;
        let f = fit::consensus_from_seed(model, image, self.fixed, pose.frame(sim), tau)?;
        let kept: Vec<bool> = fit::residuals(model, image, sim)
            .iter()
            .map(|&r| r < tau)
            .collect();
        if f.inlier == kept {
            return None;
        }
        let count = |v: &[bool]| v.iter().filter(|b| **b).count();
        if pose.long_sides_only && count(&f.inlier) < count(&kept) {
            // A pose from the long sides alone is looser than one from four
            // sides: its centre along the row is the pins', and its two
            // edges may take different steps of a chamfer band. Seeded by
            // it, the consensus kept 4 of 6 good pins each 0.8 of the
            // tolerance off centre (the two left out 1.41 and 1.56 ×
            // tolerance off its grid, one kept 0.86 ×), and the grid
            // refitted to them misplaced the blurred tips' holes by 0.6 px
            // (`synth_envelope::tests`, seed 7). Where it leaves out more
            // pins than the pins' own fit, each must stand clearly apart
            // from those it keeps; a bend the pins' fit absorbed does (a
            // 1 × 4's bent end pin 1.39 × off, the others within 0.03 ×:
            // Rust 1 171 372).
            let r = fit::residuals(model, image, &f.sim);
            let split = |keep: bool| r.iter().zip(&f.inlier).filter(move |p| *p.1 == keep);
            let worst_kept = split(true).map(|p| *p.0).fold(0.0, f64::max);
            let least_left = split(false).map(|p| *p.0).fold(f64::INFINITY, f64::min);
            if least_left < STANDS_APART * worst_kept {
                return None;
            }
        }
        Some(f)
    }
}

/// The note for a fit whose pins the outline chose.
pub(super) fn chosen_note(f: &RobustFit) -> String {
    format!(
        "the housing's outline chose the pins the grid is fitted to: {} of {}",
        f.inlier.iter().filter(|b| **b).count(),
        f.inlier.len()
    )
}
