//! From scattered detections to grid indices: the lattice (rotation, pitch
//! in pixels, phase) estimated with medians over neighbour pairs, then the
//! placement of the recipe's rows × cols window on it.
//!
//! Everything here is a median or a vote, so a bent pin, a missing pin or a
//! piece of debris cannot move it; the least-squares refinement
//! ([`super::fit::robust_similarity`]) comes after.

use std::f64::consts::PI;

/// A 2-D lattice in the image: point (a, b) in pitch units maps to
/// origin + R(θ) (a px, b py).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Lattice {
    pub theta: f64,
    pub px: f64,
    pub py: f64,
    pub origin: (f64, f64),
}

impl Lattice {
    pub fn to_lattice(&self, p: (f64, f64)) -> (f64, f64) {
        let (sn, cs) = self.theta.sin_cos();
        let (dx, dy) = (p.0 - self.origin.0, p.1 - self.origin.1);
        (
            (cs * dx + sn * dy) / self.px,
            (-sn * dx + cs * dy) / self.py,
        )
    }
    pub fn to_image(&self, a: f64, b: f64) -> (f64, f64) {
        let (sn, cs) = self.theta.sin_cos();
        let (u, v) = (a * self.px, b * self.py);
        (
            self.origin.0 + cs * u - sn * v,
            self.origin.1 + sn * u + cs * v,
        )
    }
}

pub(crate) fn median(v: &mut [f64]) -> Option<f64> {
    if v.is_empty() {
        return None;
    }
    v.sort_by(|a, b| a.total_cmp(b));
    let n = v.len();
    Some(if n % 2 == 1 {
        v[n / 2]
    } else {
        0.5 * (v[n / 2 - 1] + v[n / 2])
    })
}

fn wrap_angle(a: f64) -> f64 {
    // Fold into (−π/2, π/2]: a row direction and its reverse are the same.
    let mut a = a % PI;
    if a > PI / 2.0 {
        a -= PI;
    } else if a <= -PI / 2.0 {
        a += PI;
    }
    a
}

/// Why no lattice could be estimated.
#[derive(Debug, Clone, PartialEq)]
pub enum LatticeError {
    /// Fewer than one point.
    NoPoints,
    /// No neighbours at the expected pitch (known scale): the measured
    /// nearest-neighbour spacing is given.
    PitchMismatch { expected_px: f64, found_px: f64 },
}

/// Maximum tilt of the part against the image axes that the pair search
/// accepts (the spec promises ±5°).
pub const MAX_TILT_DEG: f64 = 12.0;

/// Estimates the lattice from pin-like points.
///
/// `pitch_px`: the expected (x, y) pitch in pixels when the scale is known;
/// otherwise it is estimated from nearest-neighbour spacings along the
/// rows (or the column, for one-column parts) with `pitch_ratio` = py / px.
pub fn estimate_lattice(
    pts: &[(f64, f64)],
    pitch_px: Option<(f64, f64)>,
    pitch_ratio: f64,
    rows: u32,
    cols: u32,
) -> Result<Lattice, LatticeError> {
    if pts.is_empty() {
        return Err(LatticeError::NoPoints);
    }
    let tilt = MAX_TILT_DEG.to_radians();
    let n = pts.len();
    // Nearest neighbour along each axis direction: (spacing, the pair).
    let nearest_pairs = |horizontal: bool| -> Vec<(f64, (usize, usize))> {
        let mut out = Vec::new();
        for i in 0..n {
            let (mut best, mut with) = (f64::INFINITY, i);
            for j in 0..n {
                if i == j {
                    continue;
                }
                let (dx, dy) = (pts[j].0 - pts[i].0, pts[j].1 - pts[i].1);
                let ang = wrap_angle(dy.atan2(dx));
                let ok = if horizontal {
                    ang.abs() < tilt
                } else {
                    (PI / 2.0 - ang.abs()) < tilt
                };
                let d = (dx * dx + dy * dy).sqrt();
                if ok && d < best {
                    (best, with) = (d, j);
                }
            }
            if best.is_finite() {
                out.push((best, (i.min(with), i.max(with))));
            }
        }
        out
    };
    let nearest =
        |horizontal: bool| -> Vec<f64> { nearest_pairs(horizontal).iter().map(|p| p.0).collect() };
    let (px, py) = match pitch_px {
        Some(p) => p,
        None => {
            if cols > 1 {
                let mut d = nearest(true);
                let px = median(&mut d).ok_or(LatticeError::NoPoints)?;
                (px, px * pitch_ratio)
            } else if rows > 1 {
                let mut d = nearest(false);
                let py = median(&mut d).ok_or(LatticeError::NoPoints)?;
                (py / pitch_ratio, py)
            } else {
                return Err(LatticeError::NoPoints);
            }
        }
    };
    // Rotation: median direction of neighbour pairs at one pitch.
    let mut angles = Vec::new();
    for i in 0..n {
        for j in (i + 1)..n {
            let (dx, dy) = (pts[j].0 - pts[i].0, pts[j].1 - pts[i].1);
            let d = (dx * dx + dy * dy).sqrt();
            let ang = wrap_angle(dy.atan2(dx));
            if cols > 1 && (d / px - 1.0).abs() < 0.2 && ang.abs() < tilt {
                angles.push(ang);
            }
            if rows > 1 && (d / py - 1.0).abs() < 0.2 && (PI / 2.0 - ang.abs()) < tilt {
                let a = if ang > 0.0 {
                    ang - PI / 2.0
                } else {
                    ang + PI / 2.0
                };
                angles.push(a);
            }
        }
    }
    // No two points one pitch apart (pins missing between the ones found):
    // with a known pitch, pairs at a whole number of pitches give the
    // rotation, provided such a pair is some point's nearest neighbour —
    // a part of another pitch has its nearest neighbours at its own pitch.
    if angles.is_empty() && pitch_px.is_some() {
        let whole = |d: f64, p: f64| {
            let k = (d / p).round();
            (k >= 2.0 && (d - k * p).abs() < 0.1 * p).then_some(k)
        };
        let mut near = nearest(true);
        near.extend(nearest(false));
        let nearest_whole = near
            .iter()
            .any(|&d| whole(d, px).is_some() || whole(d, py).is_some());
        if nearest_whole {
            for i in 0..n {
                for j in (i + 1)..n {
                    let (dx, dy) = (pts[j].0 - pts[i].0, pts[j].1 - pts[i].1);
                    let d = (dx * dx + dy * dy).sqrt();
                    let ang = wrap_angle(dy.atan2(dx));
                    if cols > 1 && whole(d, px).is_some() && ang.abs() < tilt {
                        angles.push(ang);
                    }
                    if rows > 1 && whole(d, py).is_some() && (PI / 2.0 - ang.abs()) < tilt {
                        angles.push(if ang > 0.0 {
                            ang - PI / 2.0
                        } else {
                            ang + PI / 2.0
                        });
                    }
                }
            }
        }
    }
    // Still none: diagonal neighbours (a 2 × 2 part with two opposite pins
    // missing) give the rotation as their direction less the diagonal's.
    if angles.is_empty() && pitch_px.is_some() && rows > 1 && cols > 1 {
        let (diag, alpha) = (px.hypot(py), py.atan2(px));
        for i in 0..n {
            for j in (i + 1)..n {
                let (mut dx, mut dy) = (pts[j].0 - pts[i].0, pts[j].1 - pts[i].1);
                if dx < 0.0 {
                    (dx, dy) = (-dx, -dy);
                }
                let ang = dy.atan2(dx);
                if (dx.hypot(dy) / diag - 1.0).abs() < 0.1 && (ang.abs() - alpha).abs() < tilt {
                    angles.push(ang - alpha.copysign(ang));
                }
            }
        }
    }
    // Still none: another part, if its pins stand at a pitch of their own.
    // That takes two pairs of nearest neighbours at one spacing (±10 %); a
    // single pair off the pitch is no lattice, and a bent pin makes one
    // (Rust seed 1 100 279: a 1 × 3 with its middle pin missing and the
    // first bent 0.18 pitch, the two left 1.82 pitches apart, and debris
    // on the housing's corner as the third point).
    if angles.is_empty() && n >= 3 && pitch_px.is_some() {
        let mut pairs = nearest_pairs(true);
        pairs.extend(nearest_pairs(false));
        let mut d: Vec<f64> = pairs.iter().map(|p| p.0).collect();
        let found = median(&mut d).unwrap_or(f64::NAN);
        let mut at_found: Vec<(usize, usize)> = pairs
            .iter()
            .filter(|p| (p.0 / found - 1.0).abs() < 0.1)
            .map(|p| p.1)
            .collect();
        at_found.sort_unstable();
        at_found.dedup();
        let expected = if cols > 1 { px } else { py };
        if found.is_finite() && at_found.len() >= 2 && (found / expected - 1.0).abs() > 0.2 {
            return Err(LatticeError::PitchMismatch {
                expected_px: expected,
                found_px: found,
            });
        }
    }
    let theta = median(&mut angles).unwrap_or(0.0);
    // Phase: circular mean of the lattice coordinates, then refined on the
    // points near the lattice.
    // Origin: the point that puts the most others near lattice nodes (a
    // debris blob off the lattice cannot win this vote).
    let mut lat = Lattice {
        theta,
        px,
        py,
        origin: pts[0],
    };
    let mut best_votes = 0usize;
    for &o in pts.iter().take(64) {
        let l = Lattice { origin: o, ..lat };
        let votes = pts
            .iter()
            .filter(|&&p| {
                let (a, b) = l.to_lattice(p);
                (a - a.round()).abs() < 0.2 && (b - b.round()).abs() < 0.2
            })
            .count();
        if votes > best_votes {
            best_votes = votes;
            lat.origin = o;
        }
    }
    for _ in 0..2 {
        let (mut ca, mut sa, mut cb, mut sb) = (0.0, 0.0, 0.0, 0.0);
        for &p in pts {
            let (a, b) = lat.to_lattice(p);
            let (fa, fb) = (a - a.round(), b - b.round());
            if fa.abs() < 0.3 && fb.abs() < 0.3 {
                ca += (2.0 * PI * a).cos();
                sa += (2.0 * PI * a).sin();
                cb += (2.0 * PI * b).cos();
                sb += (2.0 * PI * b).sin();
            }
        }
        let pa = if ca == 0.0 && sa == 0.0 {
            0.0
        } else {
            sa.atan2(ca) / (2.0 * PI)
        };
        let pb = if cb == 0.0 && sb == 0.0 {
            0.0
        } else {
            sb.atan2(cb) / (2.0 * PI)
        };
        lat.origin = lat.to_image(pa, pb);
    }
    Ok(lat)
}

/// Tolerance (pitch units) within which a point counts as on a node when
/// lattices are compared: the vote in [`estimate_lattice`]'s own.
const NODE_TOL: f64 = 0.2;

/// With the scale estimated, the lattice the points themselves agree on
/// when it explains more of them than `prior` does.
///
/// The prior's pitch comes from the scale estimate, and on parts of two to
/// four pins a bent pin's pair can be the only pair one prior pitch apart.
/// Rust seed 965 725 (a 1 × 6 with one pin missing and one bent, no
/// `mm_per_px`): the estimate gave 26.7 px against a true 31.4; the bent
/// pin and its neighbour, 27.2 px apart, became the lattice and the other
/// two tips fell off it, one set aside 2 mm "from the housing". Here every
/// pair of points along a row (or a column) spaced k = 1 … cols − 1 pitches
/// proposes a lattice (its direction, its spacing / k, its first point as
/// origin), pitches 0.7–1.45 × the prior's only. A proposal counts only
/// if it keeps every point on the prior's nodes on its own (Rust seed
/// 945 437: a dozen noise blobs about a 1 × 10 row fit a lattice tilted
/// 7° by chance, but not with the row's tips). The proposal that puts the
/// most points on its nodes wins (ties: the smaller residual), and only if
/// it puts at least three there and more than the prior does. Two points
/// fit any pair's lattice, so they never overrule the estimate.
pub fn lattice_by_consensus(
    pts: &[(f64, f64)],
    prior: &Lattice,
    rows: u32,
    cols: u32,
) -> Option<Lattice> {
    const MAX_POINTS: usize = 24;
    let n = pts.len();
    if !(3..=MAX_POINTS).contains(&n) {
        return None;
    }
    let on_prior: Vec<bool> = pts
        .iter()
        .map(|&p| index_of(prior, p, NODE_TOL).is_some())
        .collect();
    let prior_n = on_prior.iter().filter(|&&b| b).count();
    if prior_n == n {
        return None;
    }
    let tilt = MAX_TILT_DEG.to_radians();
    let ratio = prior.py / prior.px;
    let mut best: Option<(usize, f64, Lattice)> = None;
    for i in 0..n {
        for j in 0..n {
            if i == j {
                continue;
            }
            let (dx, dy) = (pts[j].0 - pts[i].0, pts[j].1 - pts[i].1);
            let ang = dy.atan2(dx);
            let d = dx.hypot(dy);
            // Along a row: j to the right of i; along a column: j below i
            // (each unordered pair once per direction).
            let along_row = cols > 1 && dx > 0.0 && ang.abs() < tilt;
            let along_col = rows > 1 && dy > 0.0 && (PI / 2.0 - ang).abs() < tilt;
            let (steps, theta) = match (along_row, along_col) {
                (true, _) => (cols - 1, ang),
                (_, true) => (rows - 1, ang - PI / 2.0),
                _ => continue,
            };
            for k in 1..=steps {
                let step = d / k as f64;
                let px = if along_row { step } else { step / ratio };
                if !(0.7..=1.45).contains(&(px / prior.px)) {
                    continue;
                }
                let lat = Lattice {
                    theta,
                    px,
                    py: px * ratio,
                    origin: pts[i],
                };
                let at: Vec<Option<LatticeIndex>> =
                    pts.iter().map(|&p| index_of(&lat, p, NODE_TOL)).collect();
                // It must keep every point the prior explains: noise
                // blobs scattered about a row fit some lattice by chance,
                // never one that also holds the prior's tips.
                if at.iter().zip(&on_prior).any(|(i, &on)| on && i.is_none()) {
                    continue;
                }
                let m = at.iter().flatten().count();
                let r2: f64 = at.iter().flatten().map(|i| i.ra * i.ra + i.rb * i.rb).sum();
                let better = match &best {
                    None => true,
                    Some((bm, br2, _)) => m > *bm || (m == *bm && r2 < *br2),
                };
                if better {
                    best = Some((m, r2, lat));
                }
            }
        }
    }
    let (m, _, lat) = best?;
    (m >= 3 && m > prior_n).then_some(lat)
}

/// A point's place on the lattice.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LatticeIndex {
    pub a: i64,
    pub b: i64,
    /// Residual in pitch units.
    pub ra: f64,
    pub rb: f64,
}

/// Integer lattice index of a point when within `tol` pitch of a node.
pub fn index_of(lat: &Lattice, p: (f64, f64), tol: f64) -> Option<LatticeIndex> {
    let (a, b) = lat.to_lattice(p);
    let (ia, ib) = (a.round(), b.round());
    let (ra, rb) = (a - ia, b - ib);
    (ra.abs() < tol && rb.abs() < tol).then_some(LatticeIndex {
        a: ia as i64,
        b: ib as i64,
        ra,
        rb,
    })
}

/// A point in the image and the lattice node it stands on.
pub type OnNode = ((f64, f64), (i64, i64));

/// The lattice refitted by least squares to points on known nodes
/// (`((x, y), (a, b))`): origin, rotation and pitch, the pitch ratio kept.
///
/// The first estimate takes its pitch from the scale prior and its phase
/// from a vote, so on a long part a prior a few per cent off leaves the
/// end nodes a quarter pitch from their tips (Rust seed 935 067: a 3 × 20
/// whose prior pitch was 19.4 px against 20.1, its nodes 5 px off at
/// either end). Whatever is read at the nodes then misses the tips: the
/// tips' evidence for where the window sits, the housing's profiles that
/// start beside the outermost pins. One pass drops points more than 0.15
/// pitch off the first fit (a bent pin still within the members'
/// tolerance). `None` with fewer than three points on two nodes, or when
/// the fit moves the pitch by more than 15 % or the rotation by more than
/// 3° (the points then do not say more than the estimate did).
pub fn refine_lattice(lat: &Lattice, on_nodes: &[OnNode]) -> Option<Lattice> {
    // The lattice is a similarity from node coordinates (a, b·py/px) to
    // the image, its scale the pitch px: the least-squares similarity fit
    // the grid fit uses, with the dropped points weighted 0.
    let r = lat.py / lat.px;
    let model: Vec<(f64, f64)> = on_nodes
        .iter()
        .map(|&(_, (a, b))| (a as f64, b as f64 * r))
        .collect();
    let image: Vec<(f64, f64)> = on_nodes.iter().map(|&(p, _)| p).collect();
    let fit = |weights: &[f64]| -> Option<Lattice> {
        if weights.iter().filter(|&&w| w > 0.0).count() < 3 {
            return None;
        }
        let sim = super::fit::fit_similarity(&model, &image, weights, None, lat.theta)?;
        Some(Lattice {
            theta: sim.theta,
            px: sim.s,
            py: sim.s * r,
            origin: (sim.tx, sim.ty),
        })
    };
    let first = fit(&vec![1.0; on_nodes.len()])?;
    let close: Vec<f64> = on_nodes
        .iter()
        .map(|&(p, (a, b))| {
            let (fa, fb) = first.to_lattice(p);
            let near = (fa - a as f64).abs() < 0.15 && (fb - b as f64).abs() < 0.15;
            if near { 1.0 } else { 0.0 }
        })
        .collect();
    let l = fit(&close).unwrap_or(first);
    let moved =
        (l.px / lat.px - 1.0).abs() > 0.15 || (l.theta - lat.theta).abs() > 3f64.to_radians();
    (!moved && l.px.is_finite()).then_some(l)
}

/// Lattice indices of `pts` within 0.3 pitch of a node (`None` for the
/// points that may not be members), read again on the lattice refitted to
/// them ([`refine_lattice`]), which is returned with them.
pub fn members_refined(
    lat: Lattice,
    pts: &[Option<(f64, f64)>],
) -> (Lattice, Vec<Option<LatticeIndex>>) {
    let index = |lat: &Lattice| -> Vec<Option<LatticeIndex>> {
        pts.iter()
            .map(|p| p.and_then(|p| index_of(lat, p, 0.3)))
            .collect()
    };
    let idx = index(&lat);
    let on_nodes: Vec<OnNode> = pts
        .iter()
        .zip(&idx)
        .filter_map(|(p, i)| Some(((*p)?, (i.as_ref()?.a, i.as_ref()?.b))))
        .collect();
    match refine_lattice(&lat, &on_nodes) {
        Some(refined) => {
            let idx = index(&refined);
            (refined, idx)
        }
        None => (lat, idx),
    }
}

/// Where the recipe's window sits on the lattice: lattice (a, b) of
/// grid position (row, col) = (col + col0, row + row0).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Placement {
    pub col0: i64,
    pub row0: i64,
    /// Members on valid positions.
    pub score: usize,
    /// More than one placement scored best; the tie was broken by `anchor`
    /// (or, without one, by centring on the members).
    pub ambiguous: bool,
}

/// Chooses the placement of the rows × cols window (minus `skipped`)
/// covering most members; ties go to the placement whose grid centre is
/// nearest `anchor` (the housing centre in lattice units).
pub fn place_window(
    members: &[(i64, i64)],
    rows: u32,
    cols: u32,
    skipped: &dyn Fn(u32, u32) -> bool,
    anchor: Option<(f64, f64)>,
) -> Option<Placement> {
    let (best, ties) = best_placements(members, rows, cols, skipped)?;
    let amin = members.iter().map(|m| m.0).min()?;
    let amax = members.iter().map(|m| m.0).max()?;
    let bmin = members.iter().map(|m| m.1).min()?;
    let bmax = members.iter().map(|m| m.1).max()?;
    let centre_of = |row0: i64, col0: i64| {
        (
            col0 as f64 + (cols as f64 - 1.0) / 2.0,
            row0 as f64 + (rows as f64 - 1.0) / 2.0,
        )
    };
    let target = anchor.unwrap_or(((amin + amax) as f64 / 2.0, (bmin + bmax) as f64 / 2.0));
    let pick = ties.iter().min_by(|x, y| {
        let cx = centre_of(x.0, x.1);
        let cy = centre_of(y.0, y.1);
        let dx = (cx.0 - target.0).powi(2) + (cx.1 - target.1).powi(2);
        let dy = (cy.0 - target.0).powi(2) + (cy.1 - target.1).powi(2);
        dx.total_cmp(&dy)
    })?;
    Some(Placement {
        row0: pick.0,
        col0: pick.1,
        score: best,
        ambiguous: ties.len() > 1,
    })
}

/// The placements `(row0, col0)` of the rows × cols window (minus
/// `skipped`) that cover the most members, with that count.
pub fn best_placements(
    members: &[(i64, i64)],
    rows: u32,
    cols: u32,
    skipped: &dyn Fn(u32, u32) -> bool,
) -> Option<(usize, Vec<(i64, i64)>)> {
    if members.is_empty() {
        return None;
    }
    let amin = members.iter().map(|m| m.0).min()?;
    let amax = members.iter().map(|m| m.0).max()?;
    let bmin = members.iter().map(|m| m.1).min()?;
    let bmax = members.iter().map(|m| m.1).max()?;
    let mut scored = Vec::new();
    for row0 in (bmin - rows as i64 + 1)..=bmax {
        for col0 in (amin - cols as i64 + 1)..=amax {
            let score = members
                .iter()
                .filter(|&&(a, b)| {
                    let (c, r) = (a - col0, b - row0);
                    c >= 0
                        && r >= 0
                        && c < cols as i64
                        && r < rows as i64
                        && !skipped(r as u32, c as u32)
                })
                .count();
            scored.push((row0, col0, score));
        }
    }
    let best = scored.iter().map(|s| s.2).max()?;
    let ties = scored
        .iter()
        .filter(|s| s.2 == best)
        .map(|s| (s.0, s.1))
        .collect();
    Some((best, ties))
}

#[cfg(test)]
mod tests {
    use super::*;

    type Bend = ((i64, i64), (f64, f64));

    fn pts(theta: f64, missing: &[(i64, i64)], bent: &[Bend]) -> Vec<(f64, f64)> {
        let lat = Lattice {
            theta,
            px: 84.7,
            py: 84.7,
            origin: (130.2, 350.9),
        };
        let mut v = Vec::new();
        for b in 0..2 {
            for a in 0..10 {
                if missing.contains(&(a, b)) {
                    continue;
                }
                let mut p = lat.to_image(a as f64, b as f64);
                for ((ba, bb), d) in bent {
                    if (*ba, *bb) == (a, b) {
                        p.0 += d.0;
                        p.1 += d.1;
                    }
                }
                v.push(p);
            }
        }
        v
    }

    #[test]
    fn lattice_from_points_with_defects() {
        let theta = 3f64.to_radians();
        let p = pts(theta, &[(3, 0)], &[((7, 1), (8.0, 3.0))]);
        for pitch in [Some((84.7, 84.7)), None] {
            let lat = estimate_lattice(&p, pitch, 1.0, 2, 10).unwrap();
            assert!((lat.theta - theta).abs() < 1e-9, "{}", lat.theta);
            assert!((lat.px - 84.7).abs() < 1e-6);
            let members: Vec<_> = p.iter().filter_map(|&q| index_of(&lat, q, 0.3)).collect();
            assert_eq!(members.len(), 19);
        }
        // Wrong pitch for the recipe: found spacing reported.
        let e = estimate_lattice(&p, Some((50.0, 50.0)), 1.0, 2, 10).unwrap_err();
        assert!(
            matches!(e, LatticeError::PitchMismatch { found_px, .. } if (found_px - 84.7).abs() < 1.0)
        );
    }

    #[test]
    fn known_pitch_with_the_pins_between_missing() {
        // A 1 × 4 part with its middle pins missing and a piece of debris
        // 2.5 pitches from the first pin (seed 500 279 of the envelope):
        // the pins three pitches apart give the rotation, not an error.
        let theta = 1.4f64.to_radians();
        let (s, c) = theta.sin_cos();
        let at = |a: f64, b: f64| {
            (
                100.0 + 82.3 * (a * c - b * s),
                200.0 + 82.3 * (a * s + b * c),
            )
        };
        let p = vec![at(0.0, 0.0), at(3.0, 0.0), at(2.45, 0.5)];
        let lat = estimate_lattice(&p, Some((82.3, 82.3)), 1.0, 1, 4).unwrap();
        assert!((lat.theta - theta).abs() < 1e-9, "{}", lat.theta);
        // Nearest neighbours at 1.69 pitches: another part, still an error.
        let q = vec![at(0.0, 0.0), at(1.69, 0.0), at(3.38, 0.0)];
        assert!(estimate_lattice(&q, Some((82.3, 82.3)), 1.0, 1, 4).is_err());
    }

    #[test]
    fn one_pair_off_the_pitch_is_no_other_part() {
        // Rust seed 1 100 279: a 1 × 3 without its middle pin, the first
        // pin bent 0.18 pitch toward the last (1.82 pitches apart) and a
        // piece of debris above the last. One spacing off the pitch is a
        // bent pin as much as another part: the lattice is returned, at
        // the known pitch, and the inspection judges the pins on it.
        let at = |a: f64, b: f64| (100.0 + 47.1 * a, 220.0 + 47.1 * b);
        let p = vec![at(0.18, 0.0), at(2.0, 0.0), at(2.55, -0.55)];
        let lat = estimate_lattice(&p, Some((47.1, 47.1)), 1.0, 1, 3).unwrap();
        assert_eq!(lat.px, 47.1);
        // The two pins sit two nodes apart on it, each within 0.2 pitch.
        let (a0, b0) = lat.to_lattice(p[0]);
        let (a1, b1) = lat.to_lattice(p[1]);
        assert_eq!(a1.round() - a0.round(), 2.0, "{a0} {a1}");
        for f in [a0, b0, a1, b1] {
            assert!((f - f.round()).abs() < 0.2, "{a0} {b0} {a1} {b1}");
        }
    }

    #[test]
    fn window_placement_and_housing_anchor() {
        let full: Vec<(i64, i64)> = (0..2)
            .flat_map(|b| (0..10).map(move |a| (a + 5, b - 1)))
            .collect();
        let none = |_: u32, _: u32| false;
        let p = place_window(&full, 2, 10, &none, None).unwrap();
        assert_eq!((p.col0, p.row0, p.score, p.ambiguous), (5, -1, 20, false));
        // Whole end column missing: two placements fit; the anchor decides.
        let cut: Vec<_> = full.iter().copied().filter(|m| m.0 != 14).collect();
        let left = place_window(&cut, 2, 10, &none, Some((9.5, -0.5))).unwrap();
        assert_eq!((left.col0, left.ambiguous), (5, true));
        let right = place_window(&cut, 2, 10, &none, Some((8.5, -0.5))).unwrap();
        assert_eq!(right.col0, 4);
    }

    /// A lattice whose pitch is 3 % short and whose origin is a quarter
    /// pitch off (the scale prior's error on a long part) is refitted onto
    /// the tips of a 3 × 20 from the nodes its members were read at, a
    /// bent tip among them; too few points leave it alone.
    #[test]
    fn a_lattice_from_a_prior_a_few_percent_off_is_refitted_to_its_tips() {
        let truth = Lattice {
            theta: 2.9f64.to_radians(),
            px: 20.1,
            py: 32.16,
            origin: (114.3, 447.2),
        };
        let prior = Lattice {
            theta: 2.5f64.to_radians(),
            px: 19.4,
            py: 19.4 * 1.6,
            origin: (119.7, 448.0),
        };
        let mut on_nodes = Vec::new();
        for b in 0..3 {
            for a in 0..17 {
                let mut p = truth.to_image(a as f64, b as f64);
                if (a, b) == (5, 1) {
                    p.1 += 6.0; // bent: 0.19 pitch, dropped by the second pass
                }
                on_nodes.push((p, (a, b)));
            }
        }
        let l = refine_lattice(&prior, &on_nodes).unwrap();
        for (a, b) in [(0.0, 0.0), (19.0, 2.0), (-1.0, -1.0)] {
            let (p, q) = (l.to_image(a, b), truth.to_image(a, b));
            assert!(
                (p.0 - q.0).hypot(p.1 - q.1) < 1e-6,
                "{a},{b}: {p:?} vs {q:?}"
            );
        }
        assert!(refine_lattice(&prior, &on_nodes[..2]).is_none());
        let same_node = vec![on_nodes[0]; 4];
        assert!(refine_lattice(&prior, &same_node).is_none());
    }

    /// Rust seed 965 725's tips (a 1 × 6 tilted 4.9°, pitch 31.4 px, with
    /// position 1 missing, position 3 bent 3.5 px towards 2 and position 5
    /// skipped) under a scale prior of 26.7 px: only the bent pair is one
    /// prior pitch apart. The tips' own lattice explains all four; a
    /// complete set of tips, two tips, or noise blobs on a line that does
    /// not hold the prior's tips leave the prior alone.
    #[test]
    fn the_tips_own_lattice_overrules_a_prior_only_a_bent_pair_fits() {
        let truth = Lattice {
            theta: 4.9f64.to_radians(),
            px: 31.4,
            py: 31.4,
            origin: (117.7, 128.7),
        };
        let mut tips: Vec<(f64, f64)> = [0.0, 2.0, 3.0, 4.0]
            .iter()
            .map(|&a| truth.to_image(a, 0.0))
            .collect();
        tips[2].0 -= 3.5;
        let prior = estimate_lattice(&tips, Some((26.7, 26.7)), 1.0, 1, 6).unwrap();
        let on_prior = tips.iter().filter(|&&p| index_of(&prior, p, 0.2).is_some());
        assert_eq!(
            on_prior.count(),
            2,
            "the case: the prior fits the bent pair only"
        );
        let l = lattice_by_consensus(&tips, &prior, 1, 6).unwrap();
        assert!((l.px / 31.4 - 1.0).abs() < 0.02, "pitch {}", l.px);
        assert!(
            (l.theta - truth.theta).abs() < 1f64.to_radians(),
            "{}",
            l.theta
        );
        let a: Vec<i64> = tips
            .iter()
            .map(|&p| index_of(&l, p, 0.2).map_or(-99, |i| i.a))
            .collect();
        let a0 = a[0];
        assert_eq!(a.iter().map(|x| x - a0).collect::<Vec<_>>(), [0, 2, 3, 4]);
        // Every tip on the prior's nodes, or two tips only: the prior stays.
        let full: Vec<(f64, f64)> = (0..5).map(|a| prior.to_image(a as f64, 0.0)).collect();
        assert!(lattice_by_consensus(&full, &prior, 1, 6).is_none());
        assert!(lattice_by_consensus(&[tips[0], tips[1]], &prior, 1, 6).is_none());
        // Three noise blobs on a line of their own (7° and 36.8 px) beside
        // two tips on the prior: more points, but not the tips'.
        let prior = Lattice {
            theta: 0.0,
            px: 38.85,
            py: 38.85,
            origin: (0.0, 0.0),
        };
        let mut p = vec![(0.0, 0.0), (38.85, 0.0)];
        p.extend((0..3).map(|k| (100.0 + 36.5 * k as f64, 30.0 + 4.7 * k as f64)));
        assert!(lattice_by_consensus(&p, &prior, 1, 10).is_none());
    }
}
