//! Grey-level opening with a large square window in O(1) per pixel
//! (van Herk / Gil–Werman running min and max), for the white top-hat that
//! separates pin tips from uneven lighting.
//!
//! imageproc's `grayscale_open` visits every mask pixel at every image
//! pixel (O(k²)), and works on `u8` only; the detector runs on the small
//! `f32` block-mean image with windows of 10–20 px, so it needs neither.

/// Running minimum (or maximum when `max` is true) over a window of
/// `2 r + 1` samples, positions beyond the ends ignored.
pub fn running_extreme(
    input: &[f32],
    r: usize,
    max: bool,
    out: &mut [f32],
    scratch: &mut Vec<f32>,
) {
    if max {
        running::<true>(input, r, out, scratch)
    } else {
        running::<false>(input, r, out, scratch)
    }
}

#[inline(always)]
fn pick<const MAX: bool>(a: f32, b: f32) -> f32 {
    if MAX { a.max(b) } else { a.min(b) }
}

fn running<const MAX: bool>(input: &[f32], r: usize, out: &mut [f32], scratch: &mut Vec<f32>) {
    let n = input.len();
    if n == 0 {
        return;
    }
    let w = 2 * r + 1;
    let pad = if MAX {
        f32::NEG_INFINITY
    } else {
        f32::INFINITY
    };
    let m = n + 2 * r;
    scratch.clear();
    scratch.resize(2 * m, pad);
    let (g, h) = scratch.split_at_mut(m);
    g[r..r + n].copy_from_slice(input);
    h[r..r + n].copy_from_slice(input);
    // Prefix extremes (g) and suffix extremes (h) within blocks of w.
    let mut b = 0;
    while b < m {
        let e = (b + w).min(m);
        for i in b + 1..e {
            g[i] = pick::<MAX>(g[i], g[i - 1]);
        }
        for i in (b..e - 1).rev() {
            h[i] = pick::<MAX>(h[i], h[i + 1]);
        }
        b = e;
    }
    // Window [i, i + w − 1] in padded indices is output position i.
    for (i, o) in out.iter_mut().enumerate().take(n) {
        *o = pick::<MAX>(h[i], g[i + w - 1]);
    }
}

/// Running extreme along y (columns) for every column at once: the van
/// Herk recurrences run over whole rows, which the compiler vectorises.
fn pass_vertical<const MAX: bool>(data: &mut [f32], w: usize, h: usize, r: usize) {
    if h == 0 || w == 0 {
        return;
    }
    let win = 2 * r + 1;
    let pad = if MAX {
        f32::NEG_INFINITY
    } else {
        f32::INFINITY
    };
    let m = h + 2 * r;
    // The padded column: r rows of `pad` each side (only the pads are
    // filled; the image's rows are copied once into each buffer).
    let padded = || {
        let mut v = Vec::with_capacity(m * w);
        v.resize(r * w, pad);
        v.extend_from_slice(data);
        v.resize(m * w, pad);
        v
    };
    let mut g = padded();
    let mut hh = padded();
    let mut b = 0;
    while b < m {
        let e = (b + win).min(m);
        for i in b + 1..e {
            let (prev, cur) = g.split_at_mut(i * w);
            let prev = &prev[(i - 1) * w..];
            for (c, p) in cur[..w].iter_mut().zip(prev) {
                *c = pick::<MAX>(*c, *p);
            }
        }
        for i in (b..e - 1).rev() {
            let (cur, next) = hh.split_at_mut((i + 1) * w);
            let cur = &mut cur[i * w..];
            for (c, n) in cur.iter_mut().zip(&next[..w]) {
                *c = pick::<MAX>(*c, *n);
            }
        }
        b = e;
    }
    for y in 0..h {
        let out = &mut data[y * w..(y + 1) * w];
        let hr = &hh[y * w..(y + 1) * w];
        let gr = &g[(y + win - 1) * w..(y + win) * w];
        for ((o, a), c) in out.iter_mut().zip(hr).zip(gr) {
            *o = pick::<MAX>(*a, *c);
        }
    }
}

fn transpose(data: &[f32], w: usize, h: usize) -> Vec<f32> {
    let mut out = vec![0f32; w * h];
    const B: usize = 16;
    for y0 in (0..h).step_by(B) {
        for x0 in (0..w).step_by(B) {
            for y in y0..(y0 + B).min(h) {
                for x in x0..(x0 + B).min(w) {
                    out[x * h + y] = data[y * w + x];
                }
            }
        }
    }
    out
}

/// Grey opening (erosion then dilation) with a (2 r + 1)² square. The
/// passes along y run row-vectorised; the passes along x run the same way
/// on the transposed image.
pub fn open_square(data: &[f32], w: usize, h: usize, r: usize) -> Vec<f32> {
    let mut a = data.to_vec();
    pass_vertical::<false>(&mut a, w, h, r);
    let mut t = transpose(&a, w, h);
    pass_vertical::<false>(&mut t, h, w, r);
    pass_vertical::<true>(&mut t, h, w, r);
    let mut b = transpose(&t, h, w);
    pass_vertical::<true>(&mut b, w, h, r);
    b
}

/// Grey dilation (running maximum) with a (2 r + 1)² square, positions
/// beyond the edges ignored.
pub fn dilate_square(data: &[f32], w: usize, h: usize, r: usize) -> Vec<f32> {
    let mut a = data.to_vec();
    pass_vertical::<true>(&mut a, w, h, r);
    let mut t = transpose(&a, w, h);
    pass_vertical::<true>(&mut t, h, w, r);
    transpose(&t, h, w)
}

/// Mean over a (2 m + 1)² square (edges: the mean of the part inside),
/// separable running sums, O(1) per pixel.
pub fn box_mean(data: &[f32], w: usize, h: usize, m: usize) -> Vec<f32> {
    if m == 0 || w == 0 || h == 0 {
        return data.to_vec();
    }
    box_mean_vertical(&box_mean_horizontal(data, w, h, m), w, h, m)
}

/// The horizontal pass of [`box_mean`]: a running sum along each row. The
/// window's ends depend on the column only, so `ROWS` rows advance together:
/// their sums are independent chains the CPU overlaps, where one row's sum
/// is a chain of dependent additions. Each row's sum sees the same
/// additions in the same order as a walk along that row alone.
fn box_mean_horizontal(data: &[f32], w: usize, h: usize, m: usize) -> Vec<f32> {
    const ROWS: usize = 8;
    let mut out = vec![0f32; data.len()];
    for y0 in (0..h).step_by(ROWS) {
        let rows = (h - y0).min(ROWS);
        let mut acc = [0f64; ROWS];
        let (mut lo, mut hi) = (0usize, 0usize); // columns [lo, hi) in the sums
        for x in 0..w {
            while hi < (x + m + 1).min(w) {
                for (r, s) in acc.iter_mut().enumerate().take(rows) {
                    *s += data[(y0 + r) * w + hi] as f64;
                }
                hi += 1;
            }
            while lo < x.saturating_sub(m) {
                for (r, s) in acc.iter_mut().enumerate().take(rows) {
                    *s -= data[(y0 + r) * w + lo] as f64;
                }
                lo += 1;
            }
            let n = (hi - lo) as f64;
            for (r, s) in acc.iter().enumerate().take(rows) {
                out[(y0 + r) * w + x] = (s / n) as f32;
            }
        }
    }
    out
}

/// The vertical pass of [`box_mean`]: one running sum per column, advanced
/// a whole row at a time (rows are contiguous, so this streams through
/// memory and vectorises; a column at a time strides by the width). Each
/// column's sum sees the same additions in the same order as a column walk.
fn box_mean_vertical(a: &[f32], w: usize, h: usize, m: usize) -> Vec<f32> {
    let mut out = vec![0f32; a.len()];
    let mut acc = vec![0f64; w];
    let row = |y: usize| &a[y * w..(y + 1) * w];
    let (mut lo, mut hi) = (0usize, 0usize); // rows [lo, hi) in the sums
    for y in 0..h {
        while hi < (y + m + 1).min(h) {
            for (s, &v) in acc.iter_mut().zip(row(hi)) {
                *s += v as f64;
            }
            hi += 1;
        }
        while lo < y.saturating_sub(m) {
            for (s, &v) in acc.iter_mut().zip(row(lo)) {
                *s -= v as f64;
            }
            lo += 1;
        }
        let n = (hi - lo) as f64;
        for (o, &s) in out[y * w..(y + 1) * w].iter_mut().zip(&acc) {
            *o = (s / n) as f32;
        }
    }
    out
}

/// Local background: the closing (radius `r`) of the opening (radius `r`).
/// The opening removes bright structures narrower than the window (tips,
/// debris); the closing then fills the dark ones it leaves or that were
/// there (clearance holes, an empty hole's moat, the bright-lit holes of a
/// back-lit part seen in the inverted polarity), so the result follows the
/// housing and the fixture, not the holes around each tip.
///
/// The closing fills dark structure up to `reach` from its edge and no
/// further: the result is capped by the opening's dilation of radius
/// `reach`. A clearance hole is filled (its rim is within reach of every
/// point of it), but a one-row housing narrower than the closing's window,
/// on a fixture beyond the tips' level (a dark part on a black fixture seen
/// in the inverted polarity), is not: unbounded, the closing raised the
/// whole housing band to the fixture's level and the tips on it vanished
/// from the top-hat. With `reach ≥ r` the cap is inactive.
pub fn background_square(data: &[f32], w: usize, h: usize, r: usize, reach: usize) -> Vec<f32> {
    let open = open_square(data, w, h, r);
    let mut b = open.clone();
    pass_vertical::<true>(&mut b, w, h, r);
    let mut t = transpose(&b, w, h);
    pass_vertical::<true>(&mut t, h, w, r);
    pass_vertical::<false>(&mut t, h, w, r);
    let mut c = transpose(&t, h, w);
    pass_vertical::<false>(&mut c, w, h, r);
    if reach < r {
        let cap = dilate_square(&open, w, h, reach);
        for (c, m) in c.iter_mut().zip(cap) {
            *c = c.min(m);
        }
    }
    c
}

/// Height above the local background ([`background_square`]), clamped at
/// zero: a tip's contrast against the housing around it, whatever the
/// level of its clearance hole.
pub fn background_top_hat(data: &[f32], w: usize, h: usize, r: usize) -> Vec<f32> {
    let b = background_square(data, w, h, r, r);
    data.iter().zip(b).map(|(a, b)| (a - b).max(0.0)).collect()
}

/// White top-hat: image minus its opening (bright structures narrower than
/// the window, on whatever background).
pub fn white_top_hat(data: &[f32], w: usize, h: usize, r: usize) -> Vec<f32> {
    let o = open_square(data, w, h, r);
    data.iter().zip(o).map(|(a, b)| a - b).collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    #[test]
    fn dilate_square_spreads_a_point_over_its_square_and_stops_at_the_edges() {
        let (w, h) = (7usize, 5usize);
        let mut d = vec![0f32; w * h];
        d[2 * w + 3] = 1.0;
        d[0] = 2.0;
        let out = dilate_square(&d, w, h, 1);
        for y in 0..h {
            for x in 0..w {
                let want = if x <= 1 && y <= 1 {
                    2.0
                } else if (2..=4).contains(&x) && (1..=3).contains(&y) {
                    1.0
                } else {
                    0.0
                };
                assert_eq!(out[y * w + x], want, "({x}, {y})");
            }
        }
    }

    #[test]
    fn box_mean_matches_a_direct_sum_and_background_ignores_holes() {
        let (w, h) = (7, 5);
        let d: Vec<f32> = (0..w * h).map(|i| ((i * 37) % 11) as f32).collect();
        let b = box_mean(&d, w, h, 1);
        for y in 0..h {
            for x in 0..w {
                let (mut s, mut n) = (0.0, 0.0);
                for yy in y.saturating_sub(1)..=(y + 1).min(h - 1) {
                    for xx in x.saturating_sub(1)..=(x + 1).min(w - 1) {
                        s += d[yy * w + xx];
                        n += 1.0;
                    }
                }
                assert!((b[y * w + x] - s / n).abs() < 1e-4);
            }
        }
        // A bright tip in a dark hole on a mid-grey housing: the background
        // is the housing's level everywhere, the tip stands 50 above it.
        let (w, h) = (40, 40);
        let mut d = vec![100f32; w * h];
        for y in 14..26 {
            for x in 14..26 {
                d[y * w + x] = 20.0;
            }
        }
        for y in 17..23 {
            for x in 17..23 {
                d[y * w + x] = 150.0;
            }
        }
        let bg = background_square(&d, w, h, 8, 8);
        assert!(bg.iter().all(|&v| (v - 100.0).abs() < 1e-4));
        let th = background_top_hat(&d, w, h, 8);
        assert_eq!(th[20 * w + 20], 50.0);
        assert_eq!(th[15 * w + 15], 0.0);
    }

    fn naive(input: &[f32], r: usize, max: bool) -> Vec<f32> {
        (0..input.len())
            .map(|i| {
                let a = i.saturating_sub(r);
                let b = (i + r).min(input.len() - 1);
                let s = &input[a..=b];
                if max {
                    s.iter().cloned().fold(f32::NEG_INFINITY, f32::max)
                } else {
                    s.iter().cloned().fold(f32::INFINITY, f32::min)
                }
            })
            .collect()
    }

    proptest! {
        #[test]
        fn running_extreme_matches_naive(v in proptest::collection::vec(-100f32..100.0, 1..60), r in 0usize..9, max: bool) {
            let mut out = vec![0f32; v.len()];
            let mut s = Vec::new();
            running_extreme(&v, r, max, &mut out, &mut s);
            prop_assert_eq!(out, naive(&v, r, max));
        }
    }

    #[test]
    fn opening_matches_naive_square_window() {
        let (w, h, r) = (23, 17, 3);
        let mut rng = 12345u64;
        let img: Vec<f32> = (0..w * h)
            .map(|_| {
                rng = rng.wrapping_mul(6364136223846793005).wrapping_add(1);
                (rng >> 40) as f32 / 1000.0
            })
            .collect();
        let ext = |src: &[f32], max: bool| -> Vec<f32> {
            let mut o = vec![0f32; w * h];
            for y in 0..h {
                for x in 0..w {
                    let mut v = if max {
                        f32::NEG_INFINITY
                    } else {
                        f32::INFINITY
                    };
                    for yy in y.saturating_sub(r)..=(y + r).min(h - 1) {
                        for xx in x.saturating_sub(r)..=(x + r).min(w - 1) {
                            let s = src[yy * w + xx];
                            v = if max { v.max(s) } else { v.min(s) };
                        }
                    }
                    o[y * w + x] = v;
                }
            }
            o
        };
        let want = ext(&ext(&img, false), true);
        assert_eq!(open_square(&img, w, h, r), want);
    }

    #[test]
    fn top_hat_keeps_small_spot_and_drops_ramp() {
        let (w, h) = (40, 30);
        let mut img: Vec<f32> = (0..w * h).map(|i| (i % w) as f32 * 0.5).collect();
        for y in 10..13 {
            for x in 20..23 {
                img[y * w + x] += 50.0;
            }
        }
        let th = white_top_hat(&img, w, h, 4);
        assert!((th[11 * w + 21] - 50.0).abs() < 1e-3);
        // Background ramp is removed (a monotone ramp survives opening).
        assert!(th[5 * w + 5].abs() < 1e-3);
        assert!(th.iter().all(|&v| v >= -1e-4));
    }
    /// One running sum along a line of `n` samples at `at(i)`, as a single
    /// walk: the reference the row-blocked and row-vectorised passes must
    /// reproduce bit for bit.
    fn walk(n: usize, m: usize, at: impl Fn(usize) -> f32) -> Vec<f32> {
        let (mut acc, mut lo, mut hi) = (0f64, 0usize, 0usize);
        let mut out = Vec::with_capacity(n);
        for i in 0..n {
            while hi < (i + m + 1).min(n) {
                acc += at(hi) as f64;
                hi += 1;
            }
            while lo < i.saturating_sub(m) {
                acc -= at(lo) as f64;
                lo += 1;
            }
            out.push((acc / (hi - lo) as f64) as f32);
        }
        out
    }

    proptest! {
        #[test]
        fn box_mean_is_the_walk_along_rows_then_columns(
            w in 1usize..40, h in 1usize..40, m in 1usize..12, seed in 0u64..1000,
        ) {
            let img: Vec<f32> = (0..w * h)
                .map(|i| (((i as u64 + 1) * (seed + 7919)) % 1009) as f32 * 0.37 - 100.0)
                .collect();
            let mut rows = vec![0f32; w * h];
            for y in 0..h {
                let r = walk(w, m, |x| img[y * w + x]);
                rows[y * w..(y + 1) * w].copy_from_slice(&r);
            }
            let mut want = vec![0f32; w * h];
            for x in 0..w {
                for (y, v) in walk(h, m, |y| rows[y * w + x]).into_iter().enumerate() {
                    want[y * w + x] = v;
                }
            }
            prop_assert_eq!(box_mean(&img, w, h, m), want);
        }
    }
}
