//! The housing's outline in a top view: its four edges found by edge
//! profiles along the lattice axes, starting just outside the outermost
//! pins. The outline anchors the grid when the pins alone cannot, and
//! bounds where an extra counts ([`rect_distance`]).

use super::gray::Coarse;
use super::grid::{self, Lattice};

/// Housing edges in lattice units [a0, a1, b0, b1], from edge profiles
/// along the lattice axes starting just outside the outermost pins.
pub(crate) fn find_housing(
    coarse: &Coarse,
    lat: &Lattice,
    a_span: (i64, i64),
    b_span: (i64, i64),
    pin_px: f64,
    min_step: f32,
) -> Option<[f64; 4]> {
    let k = coarse.k as f64;
    let sample = |a: f64, b: f64| {
        let (x, y) = lat.to_image(a, b);
        let (cx, cy) = coarse.from_full(x, y);
        coarse.bilinear(cx, cy)
    };
    // Outermost strong step along a line (dir = +1/−1 along a or b).
    let edge_along = |along_a: bool, fixed: f64, start: f64, dir: f64, pitch: f64| -> Option<f64> {
        let step = 0.5 * k / pitch;
        let len = 2.6;
        let n = (len / step) as usize + 3;
        let prof: Vec<f32> = (0..n)
            .map(|i| {
                let t = start + dir * i as f64 * step;
                if along_a {
                    sample(t, fixed)
                } else {
                    sample(fixed, t)
                }
            })
            .collect();
        let g: Vec<f32> = (1..n - 1)
            .map(|i| (prof[i + 1] - prof[i - 1]).abs())
            .collect();
        let gmax = g.iter().cloned().fold(0f32, f32::max);
        if gmax < min_step {
            return None;
        }
        let i = g.iter().rposition(|&v| v >= 0.4 * gmax)?;
        Some(start + dir * (i + 1) as f64 * step)
    };
    let half_pin_a = (0.5 * pin_px + 2.0) / lat.px;
    let half_pin_b = (0.5 * pin_px + 2.0) / lat.py;
    let off_a = 0.9 * pin_px / lat.px;
    let off_b = 0.9 * pin_px / lat.py;
    let mut b_lines: Vec<f64> = vec![b_span.0 as f64 - off_b, b_span.1 as f64 + off_b];
    for b in b_span.0..b_span.1 {
        b_lines.push(b as f64 + 0.5);
    }
    let mut a_lines: Vec<f64> = vec![a_span.0 as f64 - off_a, a_span.1 as f64 + off_a];
    for a in a_span.0..a_span.1 {
        a_lines.push(a as f64 + 0.5);
    }
    let side = |along_a: bool, lines: &[f64], start: f64, dir: f64, pitch: f64| -> Option<f64> {
        let mut v: Vec<f64> = lines
            .iter()
            .filter_map(|&f| edge_along(along_a, f, start, dir, pitch))
            .collect();
        grid::median(&mut v)
    };
    let a1 = side(true, &b_lines, a_span.1 as f64 + half_pin_a, 1.0, lat.px)?;
    let a0 = side(true, &b_lines, a_span.0 as f64 - half_pin_a, -1.0, lat.px)?;
    let b1 = side(false, &a_lines, b_span.1 as f64 + half_pin_b, 1.0, lat.py)?;
    let b0 = side(false, &a_lines, b_span.0 as f64 - half_pin_b, -1.0, lat.py)?;
    Some([a0, a1, b0, b1])
}

/// Distance of (u, v) from the rectangle [u0, u1] × [v0, v1] (0 inside).
pub(crate) fn rect_distance(u: f64, v: f64, r: [f64; 4]) -> f64 {
    let du = (r[0] - u).max(u - r[1]).max(0.0);
    let dv = (r[2] - v).max(v - r[3]).max(0.0);
    du.hypot(dv)
}
