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
    let n = input.len();
    if n == 0 {
        return;
    }
    let w = 2 * r + 1;
    let pad = if max {
        f32::NEG_INFINITY
    } else {
        f32::INFINITY
    };
    let m = n + 2 * r;
    // scratch holds: padded input g (prefix extreme per block), then h (suffix).
    scratch.clear();
    scratch.resize(2 * m, pad);
    let (g, h) = scratch.split_at_mut(m);
    g[r..r + n].copy_from_slice(input);
    h.copy_from_slice(g);
    let pick = |a: f32, b: f32| if max { a.max(b) } else { a.min(b) };
    // Prefix extremes within blocks of length w.
    for i in 1..m {
        if i % w != 0 {
            g[i] = pick(g[i], g[i - 1]);
        }
    }
    // Suffix extremes within blocks.
    for i in (0..m - 1).rev() {
        if (i + 1) % w != 0 {
            h[i] = pick(h[i], h[i + 1]);
        }
    }
    // Window [i, i + w − 1] in padded indices = output position i.
    for (i, o) in out.iter_mut().enumerate().take(n) {
        let j = i + w - 1;
        *o = pick(h[i], if j < m { g[j] } else { pad });
    }
}

fn pass_rows(data: &mut [f32], w: usize, r: usize, max: bool) {
    let mut line = vec![0f32; w];
    let mut scratch = Vec::new();
    for row in data.chunks_exact_mut(w) {
        running_extreme(row, r, max, &mut line, &mut scratch);
        row.copy_from_slice(&line);
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

/// Grey opening (erosion then dilation) with a (2 r + 1)² square.
pub fn open_square(data: &[f32], w: usize, h: usize, r: usize) -> Vec<f32> {
    let mut a = data.to_vec();
    pass_rows(&mut a, w, r, false);
    let mut t = transpose(&a, w, h);
    pass_rows(&mut t, h, r, false);
    pass_rows(&mut t, h, r, true);
    let mut b = transpose(&t, h, w);
    pass_rows(&mut b, w, r, true);
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
