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
    let mut g = vec![pad; m * w];
    g[r * w..(r + h) * w].copy_from_slice(data);
    let mut hh = g.clone();
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
}
