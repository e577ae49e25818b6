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
//! against a plane through its neighbours' within a few pitches.
//!
//! On a part of few positions that plane is an extrapolation from two or
//! three noisy neighbours (a 1 × 7 under σ 12.8 DN at gain 0.63 missed
//! its end's level by a quarter of the contrast, Rust 960 196), so a
//! position is replaced only when the plane is out of the background's
//! own scatter about such planes (scaled by each plane's spread at its
//! position), or when a second witness agrees: the position's own blob's
//! surround, plus the part's median offset between background and
//! surrounds, standing off the same way (`EndLevels::new`).

use super::grid;
use super::surround::SurroundPlane;

/// A position's background may stand this share of the tips' contrast off
/// the plane through its neighbours' before it is in doubt. Inside
/// a housing the neighbours agree to a few hundredths (the coarse
/// background's ripple); at a pulled end they differ by 0.25–0.35.
const LEVEL_OFF: f64 = 0.1;

/// The plane alone replaces a position's level only beyond this many times
/// the background's own scatter about its neighbours' planes, times the
/// position's plane's spread: along a noisy one-row part an end's plane,
/// extrapolated from two neighbours, missed the end's level by a quarter
/// of the tips' contrast (Rust 960 196, a dark 1 × 7 under σ 12.8 DN at
/// gain 0.63).
const SIGMAS: f64 = 3.0;

/// The second witness, for a position off its neighbours' plane by less
/// than [`SIGMAS`]: its background less its own blob's surround may stand
/// this share of the tips' contrast (or [`OFFSET_SIGMAS`] of that
/// offset's spread over the tips, if more) off the offset's median over
/// the tips. A lone surround is no level to trust (a low percentile of
/// the tip's window, which reaches a darker chamfer or a hole's rim), but
/// one agreeing with the plane in direction is a second witness.
const OFFSET_OFF: f64 = 0.08;
const OFFSET_SIGMAS: f64 = 2.5;

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

/// The level a blurred tip's disc energy is taken against, where the
/// coarse background's is not: a plane through the tips' surrounds where
/// that background was raised toward a bright fixture
/// ([`SurroundPlane::if_background_raised`]), else the part's ends'
/// levels ([`EndLevels`]).
#[derive(Debug, Clone)]
pub(crate) enum DiscLevel {
    Raised(SurroundPlane),
    Ends(EndLevels),
}

impl DiscLevel {
    /// Both are for blurred tips only: nothing replaced unless `blurred`.
    pub fn new(
        blurred: bool,
        at: &Positions,
        bg_at: impl Fn(f64, f64) -> f32 + Copy,
        reach: f64,
    ) -> DiscLevel {
        match blurred
            .then(|| SurroundPlane::if_background_raised(at.tips, bg_at))
            .flatten()
        {
            Some(p) => DiscLevel::Raised(p),
            None if blurred => DiscLevel::Ends(EndLevels::new(at, bg_at, reach)),
            None => DiscLevel::Ends(EndLevels::default()),
        }
    }

    /// The report's note where the surrounds' plane was taken.
    pub fn note(&self) -> Option<String> {
        matches!(self, DiscLevel::Raised(_)).then(super::surround::raised_note)
    }

    /// The level at (x, y) where it replaces the coarse background's.
    pub fn at(&self, x: f64, y: f64) -> Option<f32> {
        match self {
            DiscLevel::Raised(p) => Some(p.at(x, y)),
            DiscLevel::Ends(e) => e.at(x, y),
        }
    }
}

/// What the grid's positions tell of the housing's level: the `nominal`
/// positions (full-resolution px), the surround of the blob measured at
/// each (`own`, `sign` space) and the tips found ((x, y, level over the
/// surround, surround)), whose median contrast scales the tests.
pub(crate) struct Positions<'a> {
    pub nominal: &'a [(f64, f64)],
    pub own: Vec<Option<f32>>,
    pub tips: &'a [(f64, f64, f32, f32)],
    /// The smallest pitch (px).
    pub pitch: f64,
}

impl EndLevels {
    /// Checks the background `bg_at` at every position. A position's background is replaced when it stands more than
    /// [`LEVEL_OFF`] of the tips' contrast off the plane through its
    /// neighbours' and either that is beyond [`SIGMAS`] of the
    /// background's own scatter about such planes (the plane's level
    /// taken), or its own blob's surround plus the background's median
    /// offset over the tips' surrounds stands off the same way by more
    /// than [`OFFSET_OFF`] (that level taken: it needs no neighbour beyond
    /// the end). Nothing is replaced with fewer than three tips or no
    /// contrast.
    pub fn new(at: &Positions, bg_at: impl Fn(f64, f64) -> f32, reach: f64) -> EndLevels {
        let mut out = EndLevels {
            replaced: Vec::new(),
            reach,
        };
        let (tips, pitch) = (at.tips, at.pitch);
        let mut contrast: Vec<f64> = tips.iter().map(|t| (t.2 - t.3) as f64).collect();
        let contrast = grid::median(&mut contrast).unwrap_or(0.0);
        if tips.len() < 3 || !(contrast > 0.0) || !(pitch > 0.0) {
            return out;
        }
        let mut pts: Vec<(f64, f64, f64)> = at
            .nominal
            .iter()
            .map(|&(x, y)| (x, y, bg_at(x, y) as f64))
            .collect();
        let by_own = own_levels(at, &pts, &bg_at, contrast);
        // The background's own scatter about its neighbours' planes, each
        // residual scaled by its prediction's spread (an end's plane is an
        // extrapolation, noisier than an interior one's).
        let mut z: Vec<f64> = (0..pts.len())
            .filter_map(|i| {
                let (plane, spread) = neighbours_level(&pts, i, pitch)?;
                Some((pts[i].2 - plane).abs() / spread)
            })
            .collect();
        let Some(sigma) = grid::median(&mut z).map(|m| 1.4826 * m) else {
            return out;
        };
        // The worst first, and again: a pulled end's level bends its
        // neighbour's plane until it is replaced itself.
        let mut done = vec![false; pts.len()];
        loop {
            let worst = (0..pts.len())
                .filter(|&i| !done[i])
                .filter_map(|i| {
                    let (plane, spread) = neighbours_level(&pts, i, pitch)?;
                    let off = pts[i].2 - plane;
                    if off.abs() <= LEVEL_OFF * contrast {
                        return None;
                    }
                    let level = if off.abs() > SIGMAS * sigma * spread {
                        plane
                    } else {
                        by_own[i].filter(|own| (pts[i].2 - own) * off > 0.0)?
                    };
                    Some((i, level, off.abs()))
                })
                .max_by(|a, b| a.2.total_cmp(&b.2));
            let Some((i, level, _)) = worst else {
                break;
            };
            done[i] = true;
            pts[i].2 = level;
            out.replaced.push((pts[i].0, pts[i].1, level as f32));
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

/// Each position's level by its own blob's surround plus the
/// background's median offset over the tips' surrounds, where that stands
/// off the background by more than [`OFFSET_OFF`] of the tips' contrast
/// (or [`OFFSET_SIGMAS`] of the offset's spread over the tips, if more).
fn own_levels(
    at: &Positions,
    pts: &[(f64, f64, f64)],
    bg_at: impl Fn(f64, f64) -> f32,
    contrast: f64,
) -> Vec<Option<f64>> {
    let offs: Vec<f64> = at
        .tips
        .iter()
        .map(|t| (bg_at(t.0, t.1) - t.3) as f64)
        .collect();
    let Some(offset) = grid::median(&mut offs.clone()) else {
        return vec![None; pts.len()];
    };
    let mut dev: Vec<f64> = offs.iter().map(|o| (o - offset).abs()).collect();
    let spread = 1.4826 * grid::median(&mut dev).unwrap_or(0.0);
    let gate = (OFFSET_OFF * contrast).max(OFFSET_SIGMAS * spread);
    pts.iter()
        .zip(&at.own)
        .map(|(p, lo)| {
            let l = (*lo)? as f64 + offset;
            ((p.2 - l).abs() > gate).then_some(l)
        })
        .collect()
}

/// The level at position `i` of the plane through its neighbours' within
/// [`REACH_PITCHES`] (at least two of them), and the spread of the
/// difference between that level and position `i`'s own for a unit noise
/// on every position: √(1 + Σ w²), `w` each neighbour's weight in the
/// plane's level at `i` (the plane is linear in the levels: its weights
/// are its levels at `i` through each neighbour's unit impulse).
fn neighbours_level(pts: &[(f64, f64, f64)], i: usize, pitch: f64) -> Option<(f64, f64)> {
    let p = pts[i];
    let mut near: Vec<(f64, f64, f64)> = pts
        .iter()
        .enumerate()
        .filter(|&(j, q)| j != i && (q.0 - p.0).hypot(q.1 - p.1) <= REACH_PITCHES * pitch)
        .map(|(_, q)| *q)
        .collect();
    if near.len() < 2 {
        return None;
    }
    let level = SurroundPlane::fit(&near)?.at(p.0, p.1) as f64;
    let mut w2 = 0.0;
    for j in 0..near.len() {
        for (k, q) in near.iter_mut().enumerate() {
            q.2 = if k == j { 1.0 } else { 0.0 };
        }
        w2 += (SurroundPlane::fit(&near)?.at(p.0, p.1) as f64).powi(2);
    }
    Some((level, (1.0 + w2).sqrt()))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Tips at `nominal` whose surrounds read `surround` (contrast 100
    /// over them), pitch 20 px.
    fn levels(
        nominal: &[(f64, f64)],
        surround: impl Fn(f64, f64) -> f32,
        bg: impl Fn(f64, f64) -> f32,
    ) -> EndLevels {
        let own: Vec<Option<f32>> = nominal.iter().map(|&(x, y)| Some(surround(x, y))).collect();
        let tips: Vec<(f64, f64, f32, f32)> = nominal
            .iter()
            .map(|&(x, y)| (x, y, surround(x, y) + 100.0, surround(x, y)))
            .collect();
        let at = Positions {
            nominal,
            own,
            tips: &tips,
            pitch: 20.0,
        };
        EndLevels::new(&at, bg, 8.0)
    }

    fn row(n: usize) -> Vec<(f64, f64)> {
        (0..n).map(|i| (20.0 * i as f64, 50.0)).collect()
    }

    /// A 1 × 8 row on a background sloping 1 level a pitch, the surrounds
    /// 5 under it; the last position's background pulled 30 down (the
    /// fixture beyond the end).
    #[test]
    fn a_pulled_end_takes_its_neighbours_level_and_the_rest_keep_theirs() {
        let bg = |x: f64, _y: f64| (x / 20.0 - if x > 130.0 { 30.0 } else { 0.0 }) as f32;
        let e = levels(&row(8), |x, _| (x / 20.0 - 5.0) as f32, bg);
        assert_eq!(e.replaced.len(), 1);
        let l = e.at(141.0, 51.0).expect("the end replaced");
        assert!((l - 7.0).abs() < 0.01, "end level {l}");
        assert!(e.at(120.0, 50.0).is_none());
    }

    /// The background along a 1 × 6 row, `end` the last position's.
    fn noisy_row(end: f32) -> impl Fn(f64, f64) -> f32 {
        move |x: f64, _y: f64| [0.0, 8.0, -6.0, 7.0, -9.0, end][(x / 20.0).round() as usize]
    }

    /// Rust 960 196's pattern: along a noisy one-row part (the background
    /// scattering by about 8 of the contrast 100) the neighbours' line,
    /// extrapolated to the end, stands 25 off the end's background, and
    /// the end's own surround agrees with its background: nothing is
    /// replaced. Where the end stands as far off a quiet row, it is.
    #[test]
    fn an_end_off_its_neighbours_line_by_their_noise_is_left_alone() {
        let e = levels(&row(6), |x, y| noisy_row(0.0)(x, y) - 5.0, noisy_row(0.0));
        assert!(e.replaced.is_empty(), "{:?}", e.replaced);
        let quiet = |x: f64, _y: f64| if x > 90.0 { 25.0 } else { 0.0 };
        let e = levels(&row(6), |_, _| -5.0, quiet);
        assert_eq!(e.replaced.len(), 1, "{:?}", e.replaced);
    }

    /// A tip whose surround reads 30 low (debris beside it) on a smooth
    /// background: its neighbours agree with the background, nothing is
    /// replaced.
    #[test]
    fn a_tip_with_a_spoilt_surround_keeps_the_background() {
        let spoilt = |x: f64, _y: f64| if x == 60.0 { -35.0 } else { -5.0 };
        let e = levels(&row(8), spoilt, |_, _| 0.0);
        assert!(e.replaced.is_empty(), "{:?}", e.replaced);
    }

    /// A slow quadratic (vignetting) across a 4 × 6 grid replaces nothing.
    #[test]
    fn vignetting_across_the_grid_is_left_alone() {
        let nominal: Vec<(f64, f64)> = (0..24)
            .map(|k| (20.0 * (k % 6) as f64, 20.0 * (k / 6) as f64))
            .collect();
        let bg =
            |x: f64, y: f64| (100.0 - 0.002 * ((x - 50.0).powi(2) + (y - 30.0).powi(2))) as f32;
        let e = levels(&nominal, |x, y| bg(x, y) - 5.0, bg);
        assert!(e.replaced.is_empty());
    }
}
