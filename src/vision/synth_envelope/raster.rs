//! Raster helpers of the envelope generator: shapes as signed distances,
//! coverage, painting, value noise, blur, a JPEG round trip.

use super::*;

pub(super) fn jpeg_roundtrip(
    img: &image::DynamicImage,
    q: u8,
) -> Result<(Gray, ImageInfo), String> {
    let mut bytes = Vec::new();
    let enc = image::codecs::jpeg::JpegEncoder::new_with_quality(&mut bytes, q);
    img.write_with_encoder(enc).map_err(|e| e.to_string())?;
    crate::vision::image_io::decode_bytes(&bytes).map_err(|e| e.to_string())
}

/// Signed distance to a rectangle [−hu, hu] × [−hv, hv] with corners
/// rounded by `r` (negative inside).
pub(super) fn rounded_rect_sd(u: f64, v: f64, hu: f64, hv: f64, r: f64) -> f64 {
    let qx = u.abs() - (hu - r);
    let qy = v.abs() - (hv - r);
    qx.max(0.0).hypot(qy.max(0.0)) + qx.max(qy).min(0.0) - r
}

pub(super) fn housing_bbox(sim: &Similarity, hu: f64, hv: f64) -> (f64, f64, f64, f64) {
    let pts = [
        sim.apply(-hu, -hv),
        sim.apply(hu, -hv),
        sim.apply(hu, hv),
        sim.apply(-hu, hv),
    ];
    pts.iter().fold(
        (
            f64::INFINITY,
            f64::INFINITY,
            f64::NEG_INFINITY,
            f64::NEG_INFINITY,
        ),
        |b, p| (b.0.min(p.0), b.1.min(p.1), b.2.max(p.0), b.3.max(p.1)),
    )
}

/// Pixel coverage of a shape given by its signed distance (px), with a
/// linear ramp of `ramp` px across the edge (0: a hard edge), integrated
/// over `n` × `n` sub-samples where the edge is near.
#[inline]
pub(super) fn coverage(sd: &dyn Fn(f64, f64) -> f64, x: f64, y: f64, ramp: f64, n: usize) -> f32 {
    let d = sd(x, y);
    let reach = 0.75 + 0.5 * ramp;
    if d > reach {
        return 0.0;
    }
    if d < -reach {
        return 1.0;
    }
    let mut acc = 0.0;
    for j in 0..n {
        for i in 0..n {
            let sx = x - 0.5 + (i as f64 + 0.5) / n as f64;
            let sy = y - 0.5 + (j as f64 + 0.5) / n as f64;
            let ds = sd(sx, sy);
            acc += if ramp > 1e-3 {
                (0.5 - ds / ramp).clamp(0.0, 1.0)
            } else if ds < 0.0 {
                1.0
            } else {
                0.0
            };
        }
    }
    (acc / (n * n) as f64) as f32
}

#[allow(clippy::too_many_arguments)]
pub(super) fn paint(
    img: &mut [f32],
    w: usize,
    h: usize,
    bbox: (f64, f64, f64, f64),
    sd: &dyn Fn(f64, f64) -> f64,
    ramp: f64,
    n: usize,
    alpha: f32,
    level: impl Fn(usize, usize) -> f32,
) {
    let pad = 2.0 + ramp;
    let xa = ((bbox.0 - pad).floor().max(0.0)) as usize;
    let ya = ((bbox.1 - pad).floor().max(0.0)) as usize;
    let xb = ((bbox.2 + pad).ceil().max(0.0) as usize).min(w.saturating_sub(1));
    let yb = ((bbox.3 + pad).ceil().max(0.0) as usize).min(h.saturating_sub(1));
    for y in ya..=yb {
        for x in xa..=xb {
            let c = coverage(sd, x as f64, y as f64, ramp, n) * alpha;
            if c > 0.0 {
                let i = y * w + x;
                img[i] = img[i] * (1.0 - c) + level(x, y) * c;
            }
        }
    }
}

#[allow(clippy::too_many_arguments)]
pub(super) fn paint_shape(
    img: &mut [f32],
    w: usize,
    h: usize,
    shape: &Shape,
    ramp: f64,
    n: usize,
    alpha: f32,
    level: impl Fn(usize, usize) -> f32,
) {
    let sd = |x: f64, y: f64| shape.signed_distance((x, y));
    paint(img, w, h, shape.bbox(), &sd, ramp, n, alpha, level);
}

/// Smooth value noise in [−1, 1]: random values on a lattice of `cell` px,
/// interpolated bilinearly.
pub(super) struct ValueNoise {
    cell: f64,
    gw: usize,
    vals: Vec<f32>,
}

impl ValueNoise {
    pub(super) fn new(w: usize, h: usize, cell: f64, seed: u64) -> ValueNoise {
        let cell = cell.max(1.0);
        let gw = (w as f64 / cell) as usize + 3;
        let gh = (h as f64 / cell) as usize + 3;
        let mut rng = Rng::new(seed);
        let vals = (0..gw * gh)
            .map(|_| (2.0 * rng.uniform() - 1.0) as f32)
            .collect();
        ValueNoise { cell, gw, vals }
    }

    #[inline]
    pub(super) fn at(&self, x: usize, y: usize) -> f32 {
        let fx = x as f64 / self.cell;
        let fy = y as f64 / self.cell;
        let (ix, iy) = (fx as usize, fy as usize);
        let (tx, ty) = ((fx - ix as f64) as f32, (fy - iy as f64) as f32);
        let i = iy * self.gw + ix;
        let a = self.vals[i] + (self.vals[i + 1] - self.vals[i]) * tx;
        let b = self.vals[i + self.gw] + (self.vals[i + self.gw + 1] - self.vals[i + self.gw]) * tx;
        a + (b - a) * ty
    }
}

/// Separable Gaussian blur (σ px), edges clamped.
pub(super) fn blur(img: &mut [f32], w: usize, h: usize, sigma: f64) {
    let rad = (3.0 * sigma).ceil() as usize;
    let k: Vec<f32> = (0..=2 * rad)
        .map(|i| {
            let d = i as f64 - rad as f64;
            (-(d * d) / (2.0 * sigma * sigma)).exp() as f32
        })
        .collect();
    let sum: f32 = k.iter().sum();
    let k: Vec<f32> = k.iter().map(|v| v / sum).collect();
    let mut line = vec![0f32; w.max(h) + 2 * rad];
    for y in 0..h {
        let row = &mut img[y * w..(y + 1) * w];
        for (i, l) in line[..w + 2 * rad].iter_mut().enumerate() {
            *l = row[(i as i64 - rad as i64).clamp(0, w as i64 - 1) as usize];
        }
        for (x, o) in row.iter_mut().enumerate() {
            *o = k
                .iter()
                .zip(&line[x..x + 2 * rad + 1])
                .map(|(a, b)| a * b)
                .sum();
        }
    }
    let mut col = vec![0f32; h];
    for x in 0..w {
        for (i, l) in line[..h + 2 * rad].iter_mut().enumerate() {
            *l = img[(i as i64 - rad as i64).clamp(0, h as i64 - 1) as usize * w + x];
        }
        for (y, o) in col.iter_mut().enumerate() {
            *o = k
                .iter()
                .zip(&line[y..y + 2 * rad + 1])
                .map(|(a, b)| a * b)
                .sum();
        }
        for (y, v) in col.iter().enumerate() {
            img[y * w + x] = *v;
        }
    }
}
