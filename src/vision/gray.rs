//! Grey images at their native precision, and the coarse (block-mean)
//! image the detector searches first.
//!
//! 8-bit data stays `u8` and 16-bit (or colour converted to luma) stays
//! `u16`; the pipeline is generic over [`Px`] so neither is widened to
//! floats over the whole frame (a 5 MP frame of `f32` costs more memory
//! traffic than the whole detection).

use serde::Serialize;

/// A grey sample type the pipeline reads.
pub trait Px: Copy + Send + Sync + 'static {
    fn f(self) -> f32;
    fn u(self) -> u32;
}
/// The two sample types: the same widening for both.
macro_rules! px_for {
    ($($t:ty),*) => {$(
        impl Px for $t {
            #[inline(always)]
            fn f(self) -> f32 {
                self as f32
            }
            #[inline(always)]
            fn u(self) -> u32 {
                self as u32
            }
        }
    )*};
}
px_for!(u8, u16);

/// Block sums of one full-resolution row into `acc` (integer, exact).
#[inline(always)]
fn add_row_blocks<P: Px, const K: usize>(row: &[P], acc: &mut [u32]) {
    for (a, chunk) in acc.iter_mut().zip(row.chunks_exact(K)) {
        let mut s = 0u32;
        for &v in chunk {
            s += v.u();
        }
        *a += s;
    }
}

/// Pixel storage of a [`Gray`] image.
#[derive(Debug, Clone, PartialEq)]
pub enum GrayData {
    U8(Vec<u8>),
    U16(Vec<u16>),
}

/// A grey image: row-major samples, x right, y down, pixel (0, 0)'s centre
/// at (0, 0).
#[derive(Debug, Clone, PartialEq)]
pub struct Gray {
    pub width: u32,
    pub height: u32,
    pub data: GrayData,
}

/// What the source image was (for reports).
#[derive(Debug, Clone, PartialEq, Eq, Serialize, serde::Deserialize, Default)]
pub struct ImageInfo {
    pub width: u32,
    pub height: u32,
    /// 1 grey, 2 grey + alpha, 3 colour, 4 colour + alpha.
    pub channels: u8,
    /// Bits per sample of the source (8 or 16; 32 for float sources).
    pub bit_depth: u8,
    /// Container format ("png", "jpeg", "bmp", "tiff", ...).
    pub format: String,
}

/// A borrowed plane of samples.
#[derive(Debug, Clone, Copy)]
pub struct Plane<'a, P> {
    pub w: usize,
    pub h: usize,
    pub data: &'a [P],
}

impl<'a, P: Px> Plane<'a, P> {
    #[inline(always)]
    pub fn at(&self, x: usize, y: usize) -> f32 {
        self.data[y * self.w + x].f()
    }

    /// Bilinear sample at a sub-pixel position (clamped to the image).
    pub fn bilinear(&self, x: f64, y: f64) -> f32 {
        bilinear((self.w, self.h), x, y, |x, y| self.at(x, y))
    }
}

impl Gray {
    /// An 8-bit image from raw samples (length must be width × height).
    pub fn from_u8(width: u32, height: u32, data: Vec<u8>) -> Option<Gray> {
        (data.len() == width as usize * height as usize).then_some(Gray {
            width,
            height,
            data: GrayData::U8(data),
        })
    }

    /// A 16-bit image from raw samples (length must be width × height).
    pub fn from_u16(width: u32, height: u32, data: Vec<u16>) -> Option<Gray> {
        (data.len() == width as usize * height as usize).then_some(Gray {
            width,
            height,
            data: GrayData::U16(data),
        })
    }

    /// Sample value as f32 (for tests and drawing; hot paths use planes).
    pub fn get(&self, x: u32, y: u32) -> f32 {
        let i = y as usize * self.width as usize + x as usize;
        match &self.data {
            GrayData::U8(d) => d[i] as f32,
            GrayData::U16(d) => d[i] as f32,
        }
    }

    /// Full-scale value of the data: 255 for 8-bit data; for 16-bit
    /// containers the smallest 2^k − 1 (k ≥ 8) holding the largest sample,
    /// so 10-, 12- and 14-bit cameras' data stored in 16 bits is judged
    /// against its own range (a 12-bit image would otherwise look 16 times
    /// flatter than it is to the contrast check).
    pub fn full_scale(&self) -> f32 {
        match &self.data {
            GrayData::U8(_) => 255.0,
            GrayData::U16(d) => {
                let max = d.iter().copied().max().unwrap_or(0);
                let bits = (16 - max.leading_zeros()).max(8);
                ((1u32 << bits) - 1) as f32
            }
        }
    }

    /// An 8-bit copy for display, stretched from the data's own range
    /// (12-bit data in a 16-bit container is shown with full contrast).
    pub fn to_display_u8(&self) -> image::GrayImage {
        let (lo, hi) = match &self.data {
            GrayData::U8(_) => (0.0, 255.0),
            GrayData::U16(d) => {
                let lo = d.iter().copied().min().unwrap_or(0) as f32;
                let hi = d.iter().copied().max().unwrap_or(1) as f32;
                (lo, hi.max(lo + 1.0))
            }
        };
        let scale = 255.0 / (hi - lo);
        let px: Vec<u8> = match &self.data {
            GrayData::U8(d) => d.clone(),
            GrayData::U16(d) => d
                .iter()
                .map(|&v| ((v as f32 - lo) * scale).round().clamp(0.0, 255.0) as u8)
                .collect(),
        };
        image::GrayImage::from_raw(self.width, self.height, px)
            .unwrap_or_else(|| image::GrayImage::new(self.width, self.height))
    }
}

/// The smallest step between neighbouring raw samples, over up to 64 rows
/// spread down the plane: 1 for 8-bit data, 16 for 12-bit data stored in
/// the high bits of 16, and so on; 0 for a flat plane. Below about one
/// step a top-hat holds only quantisation: a noise-free 8-bit background
/// under vignetting is a staircase of one-step terraces, each a blob to a
/// threshold the (zero) noise has left at nothing.
pub fn quantum<P: Px>(p: &Plane<P>) -> f32 {
    let step = (p.h / 64).max(1);
    let mut q = u32::MAX;
    for row in p.data.chunks_exact(p.w.max(1)).step_by(step) {
        for pair in row.windows(2) {
            let d = pair[0].u().abs_diff(pair[1].u());
            if d > 0 && d < q {
                q = d;
            }
        }
        if q == 1 {
            break;
        }
    }
    if q == u32::MAX { 0.0 } else { q as f32 }
}

/// Block-mean image: coarse pixel (i, j) is the mean of the full-resolution
/// block [i k, i k + k) × [j k, j k + k), multiplied by `sign` (−1 turns a
/// dark-on-bright polarity into bright-on-dark). Its centre lies at full
/// resolution (i k + (k − 1)/2, j k + (k − 1)/2).
#[derive(Debug, Clone)]
pub struct Coarse {
    pub w: usize,
    pub h: usize,
    pub k: usize,
    pub data: Vec<f32>,
    /// The raw samples' smallest step ([`quantum`]); 0 when not known
    /// (a coarse image made from something other than a plane).
    pub quantum: f32,
}

impl Coarse {
    /// The same grid (size, step, quantum) holding `data` instead: a map
    /// derived from this image, e.g. its background.
    pub fn with_data(&self, data: Vec<f32>) -> Coarse {
        Coarse { data, ..*self }
    }

    pub fn build<P: Px>(p: &Plane<P>, k: usize, sign: f32) -> Coarse {
        let k = k.clamp(1, 8);
        let w = p.w / k;
        let h = p.h / k;
        let mut data = vec![0f32; w * h];
        let mut acc = vec![0u32; w];
        let norm = sign / (k * k) as f32;
        for j in 0..h {
            acc.iter_mut().for_each(|a| *a = 0);
            for dy in 0..k {
                let start = (j * k + dy) * p.w;
                let row = &p.data[start..start + w * k];
                match k {
                    1 => add_row_blocks::<P, 1>(row, &mut acc),
                    2 => add_row_blocks::<P, 2>(row, &mut acc),
                    3 => add_row_blocks::<P, 3>(row, &mut acc),
                    4 => add_row_blocks::<P, 4>(row, &mut acc),
                    5 => add_row_blocks::<P, 5>(row, &mut acc),
                    6 => add_row_blocks::<P, 6>(row, &mut acc),
                    7 => add_row_blocks::<P, 7>(row, &mut acc),
                    _ => add_row_blocks::<P, 8>(row, &mut acc),
                }
            }
            for (d, a) in data[j * w..(j + 1) * w].iter_mut().zip(&acc) {
                *d = *a as f32 * norm;
            }
        }
        Coarse {
            w,
            h,
            k,
            data,
            quantum: quantum(p),
        }
    }

    #[inline(always)]
    pub fn at(&self, x: usize, y: usize) -> f32 {
        self.data[y * self.w + x]
    }

    /// Full-resolution position of coarse pixel centre (x, y) (fractional ok).
    pub fn to_full(&self, x: f64, y: f64) -> (f64, f64) {
        let k = self.k as f64;
        (x * k + (k - 1.0) / 2.0, y * k + (k - 1.0) / 2.0)
    }

    /// Coarse position of a full-resolution point.
    pub fn from_full(&self, x: f64, y: f64) -> (f64, f64) {
        let k = self.k as f64;
        ((x - (k - 1.0) / 2.0) / k, (y - (k - 1.0) / 2.0) / k)
    }

    /// Bilinear sample (clamped).
    pub fn bilinear(&self, x: f64, y: f64) -> f32 {
        bilinear((self.w, self.h), x, y, |x, y| self.at(x, y))
    }
}

/// The coarse images of one plane, by factor (1–8), each built on first
/// use: the scale's ladders try several tip widths at each factor.
pub struct CoarseCache<'a, P> {
    plane: &'a Plane<'a, P>,
    sign: f32,
    built: Vec<Option<Coarse>>,
}

impl<'a, P: Px> CoarseCache<'a, P> {
    pub fn new(plane: &'a Plane<'a, P>, sign: f32) -> Self {
        CoarseCache {
            plane,
            sign,
            built: vec![None; 9],
        }
    }

    /// The coarse image at factor `k` (clamped to 1–8).
    pub fn get(&mut self, k: usize) -> &Coarse {
        let (plane, sign, k) = (self.plane, self.sign, k.clamp(1, 8));
        self.built[k].get_or_insert_with(|| Coarse::build(plane, k, sign))
    }
}

/// Bilinear sample of a w×h grid read through `at` at a sub-pixel
/// position, clamped to the grid (the one interpolation of full planes
/// and coarse pyramids).
#[inline(always)]
fn bilinear(size: (usize, usize), x: f64, y: f64, at: impl Fn(usize, usize) -> f32) -> f32 {
    let (w, h) = size;
    let x = x.clamp(0.0, (w - 1) as f64);
    let y = y.clamp(0.0, (h - 1) as f64);
    let x0 = x.floor() as usize;
    let y0 = y.floor() as usize;
    let x1 = (x0 + 1).min(w - 1);
    let y1 = (y0 + 1).min(h - 1);
    let fx = (x - x0 as f64) as f32;
    let fy = (y - y0 as f64) as f32;
    let a = at(x0, y0) * (1.0 - fx) + at(x1, y0) * fx;
    let b = at(x0, y1) * (1.0 - fx) + at(x1, y1) * fx;
    a * (1.0 - fy) + b * fy
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The raw data's step: 1 for 8-bit data, 16 for 12 bits in the high
    /// bits of 16, 0 for a flat plane.
    #[test]
    fn quantum_is_the_raw_datas_smallest_step() {
        let (w, h) = (50usize, 20usize);
        let ramp: Vec<u8> = (0..w * h).map(|i| (i % w / 3) as u8).collect();
        let p = Plane { w, h, data: &ramp };
        assert_eq!(quantum(&p), 1.0);
        let high: Vec<u16> = (0..w * h).map(|i| ((i % w) as u16 * 7) << 4).collect();
        let p = Plane { w, h, data: &high };
        assert_eq!(quantum(&p), 112.0);
        let high: Vec<u16> = (0..w * h).map(|i| ((i % w / 2) as u16) << 4).collect();
        let p = Plane { w, h, data: &high };
        assert_eq!(quantum(&p), 16.0);
        let flat = vec![9u8; w * h];
        let p = Plane { w, h, data: &flat };
        assert_eq!(quantum(&p), 0.0);
    }

    #[test]
    fn full_scale_follows_the_significant_bits_of_16_bit_data() {
        let g = |v: Vec<u16>| Gray {
            width: v.len() as u32,
            height: 1,
            data: GrayData::U16(v),
        };
        assert_eq!(g(vec![0, 4095]).full_scale(), 4095.0);
        assert_eq!(g(vec![0, 1000]).full_scale(), 1023.0);
        assert_eq!(g(vec![0, 40000]).full_scale(), 65535.0);
        assert_eq!(g(vec![3, 7]).full_scale(), 255.0);
    }

    #[test]
    fn coarse_block_means_and_centres() {
        let w = 8;
        let h = 6;
        let data: Vec<u8> = (0..w * h).map(|i| (i % w) as u8 * 10).collect();
        let g = Plane { w, h, data: &data };
        let c = Coarse::build(&g, 2, 1.0);
        assert_eq!((c.w, c.h), (4, 3));
        assert!((c.at(0, 0) - 5.0).abs() < 1e-6);
        assert!((c.at(3, 2) - 65.0).abs() < 1e-6);
        let inv = Coarse::build(&g, 2, -1.0);
        assert!((inv.at(1, 1) + 25.0).abs() < 1e-6);
        assert_eq!(c.to_full(1.0, 0.0), (2.5, 0.5));
        assert_eq!(c.from_full(2.5, 0.5), (1.0, 0.0));
        // Bilinear on a linear ramp is exact.
        assert!((g.bilinear(2.25, 3.0) - 22.5).abs() < 1e-4);
    }

    #[test]
    fn display_stretches_12_bit() {
        let g = Gray::from_u16(2, 1, vec![0, 4095]).unwrap();
        let d = g.to_display_u8();
        assert_eq!(d.as_raw(), &vec![0u8, 255]);
        assert!(Gray::from_u8(2, 2, vec![0; 3]).is_none());
    }
}
