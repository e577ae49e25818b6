//! The housing's level at the part's end and corner positions, where the
//! coarse background is pulled toward the fixture.
//!
//! A blurred tip's energy is taken inside a disc against the housing's
//! level there (`top`, [`super::disc::disc_energy`]). The coarse
//! background gives that level (an opening then a closing over a window
//! of about a pitch), and within half its window of the housing's end the
//! window reaches the fixture beyond: on a dark part on a brighter fixture
//! the level at an end tip read 26 DN (0.29 of the tips' contrast) under
//! its neighbours' (Rust 941 226, a 2 × 20), the disc's 140 px turned that
//! into 1.7 tips' energy, and a good end tip read damaged. The same pull
//! made 8 of the ten Rust top tuning sets' good-read-damaged verdicts and
//! 6 of the held-out sets' 1 130 000–1 160 000, every one an end or corner
//! position of a dark part. Across the housing the background changes
//! slowly (vignetting, gradient): each position's level is checked
//! against a plane through its neighbours' within a few pitches, and one
//! standing off it by more than [`LEVEL_OFF`] of the tips' contrast takes
//! the plane's.

use super::grid;
use super::surround::SurroundPlane;

/// A position's background may stand this share of the tips' contrast off
/// the plane through its neighbours' before the plane replaces it. Inside
/// a housing the neighbours agree to a few hundredths (the coarse
/// background's ripple); at a pulled end they differ by 0.25–0.35.
pub(crate) const LEVEL_OFF: f64 = 0.1;

/// Neighbours within this many of the smallest pitch make a position's
/// plane: two positions along a row each way, the next row's beside.
const REACH_PITCHES: f64 = 2.2;

/// Levels at the grid's positions that replace the coarse background's.
#[derive(Debug, Clone, Default)]
pub(crate) struct EndLevels {
    /// (x, y, level) of each replaced position, full-resolution px.
    replaced: Vec<(f64, f64, f32)>,
    /// A point within this distance (px) of a replaced position takes its
    /// level.
    reach: f64,
}

impl EndLevels {
    /// Checks the background `bg_at` at every position `nominal` against
    /// its neighbours' plane, where `on`; `tips` are the tips found ((x,
    /// y, level over the surround, surround), `sign` space), whose median
    /// contrast scales the test, and `pitch` the smallest pitch (px).
    /// Nothing is replaced with fewer than three positions or no contrast.
    pub fn new(
        on: bool,
        nominal: &[(f64, f64)],
        bg_at: impl Fn(f64, f64) -> f32,
        tips: &[(f64, f64, f32, f32)],
        pitch: f64,
        reach: f64,
    ) -> EndLevels {
        let mut out = EndLevels {
            replaced: Vec::new(),
            reach,
        };
        let mut contrast: Vec<f64> = tips.iter().map(|t| (t.2 - t.3) as f64).collect();
        let contrast = grid::median(&mut contrast).unwrap_or(0.0);
        if !on || nominal.len() < 3 || !(contrast > 0.0) || !(pitch > 0.0) {
            return out;
        }
        let mut pts: Vec<(f64, f64, f64)> = nominal
            .iter()
            .map(|&(x, y)| (x, y, bg_at(x, y) as f64))
            .collect();
        // The worst first, and again: a pulled end's level bends its
        // neighbour's plane until it is replaced itself.
        let mut done = vec![false; pts.len()];
        loop {
            let worst = (0..pts.len())
                .filter(|&i| !done[i])
                .filter_map(|i| Some((i, neighbours_level(&pts, i, pitch)?)))
                .map(|(i, e)| (i, e, (pts[i].2 - e).abs()))
                .filter(|w| w.2 > LEVEL_OFF * contrast)
                .max_by(|a, b| a.2.total_cmp(&b.2));
            let Some((i, expect, _)) = worst else {
                break;
            };
            done[i] = true;
            pts[i].2 = expect;
            out.replaced.push((pts[i].0, pts[i].1, expect as f32));
        }
        out
    }

    /// The replaced level at (x, y), where a replaced position lies within
    /// the reach.
    pub fn at(&self, x: f64, y: f64) -> Option<f32> {
        self.replaced
            .iter()
            .filter(|r| (r.0 - x).hypot(r.1 - y) <= self.reach)
            .min_by(|a, b| {
                (a.0 - x)
                    .hypot(a.1 - y)
                    .total_cmp(&(b.0 - x).hypot(b.1 - y))
            })
            .map(|r| r.2)
    }
}

/// The level at position `i` of the plane through its neighbours' within
/// [`REACH_PITCHES`] (at least two of them).
fn neighbours_level(pts: &[(f64, f64, f64)], i: usize, pitch: f64) -> Option<f64> {
    let p = pts[i];
    let near: Vec<(f64, f64, f64)> = pts
        .iter()
        .enumerate()
        .filter(|&(j, q)| j != i && (q.0 - p.0).hypot(q.1 - p.1) <= REACH_PITCHES * pitch)
        .map(|(_, q)| *q)
        .collect();
    if near.len() < 2 {
        return None;
    }
    Some(SurroundPlane::fit(&near)?.at(p.0, p.1) as f64)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A 1 × 8 row on a background sloping 1 level a pitch, its last
    /// position pulled 30 levels down (the fixture beyond the end), tips
    /// of contrast 100.
    #[test]
    fn a_pulled_end_takes_its_neighbours_level_and_the_rest_keep_theirs() {
        let nominal: Vec<(f64, f64)> = (0..8).map(|i| (20.0 * i as f64, 50.0)).collect();
        let bg = |x: f64, _y: f64| (x / 20.0 - if x > 130.0 { 30.0 } else { 0.0 }) as f32;
        let tips = [(0.0, 0.0, 100.0, 0.0)];
        let e = EndLevels::new(true, &nominal, bg, &tips, 20.0, 8.0);
        assert_eq!(e.replaced.len(), 1);
        let l = e.at(141.0, 51.0).expect("the end replaced");
        assert!((l - 7.0).abs() < 0.01, "end level {l}");
        assert!(e.at(120.0, 50.0).is_none());
    }

    /// A slow quadratic (vignetting) across a 4 × 6 grid replaces nothing.
    #[test]
    fn vignetting_across_the_grid_is_left_alone() {
        let nominal: Vec<(f64, f64)> = (0..24)
            .map(|k| (20.0 * (k % 6) as f64, 20.0 * (k / 6) as f64))
            .collect();
        let bg =
            |x: f64, y: f64| (100.0 - 0.002 * ((x - 50.0).powi(2) + (y - 30.0).powi(2))) as f32;
        let tips = [(0.0, 0.0, 60.0, 0.0)];
        let e = EndLevels::new(true, &nominal, bg, &tips, 20.0, 8.0);
        assert!(e.replaced.is_empty());
    }
}
