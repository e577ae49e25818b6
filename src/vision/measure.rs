//! Sub-pixel measurement of one bright blob (a pin tip, or debris) in a
//! small region of interest at full resolution: local levels, threshold,
//! area and centre.
//!
//! Several localisers are offered (the methods lab compares them):
//! - [`Localiser::Centroid`]: mean position of the pixels above the
//!   half-contrast threshold (binary centroid; quantised by the pixel grid).
//! - [`Localiser::Weighted`]: intensity-weighted centroid, weights
//!   `v − threshold` over the thresholded blob (the classic OpenCV recipe).
//! - [`Localiser::Coverage`]: the default. Each pixel's weight is its
//!   estimated coverage by the tip, `clamp((v − lo) / (hi − lo), 0, 1)`,
//!   with `lo` the surrounding level and `hi` the level at the tip's rim,
//!   over the blob dilated by the blur's reach. Inside the tip the weight
//!   saturates at 1, so the specular dome and shading gradients of the tip
//!   carry no weight, and at the rim it is the pixel's area fraction: the
//!   result is the area centroid (the spec's definition of a damaged tip's
//!   centre, and the geometric centre of an intact one).
//!
//! Values are read through `sign` (+1 bright tips, −1 dark tips), so dark
//! polarity needs no inverted copy of the image.

use super::gray::{Plane, Px};
use super::label;
use serde::{Deserialize, Serialize};

/// How a blob's centre is estimated.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize, Default)]
#[serde(rename_all = "snake_case")]
pub enum Localiser {
    Centroid,
    Weighted,
    #[default]
    Coverage,
}

impl Localiser {
    pub const ALL: [Localiser; 3] = [
        Localiser::Centroid,
        Localiser::Weighted,
        Localiser::Coverage,
    ];
    pub fn name(&self) -> &'static str {
        match self {
            Localiser::Centroid => "binary centroid",
            Localiser::Weighted => "intensity-weighted centroid",
            Localiser::Coverage => "coverage (area) centroid",
        }
    }
}

/// Inclusive-exclusive pixel rectangle [x0, x1) × [y0, y1).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Roi {
    pub x0: usize,
    pub y0: usize,
    pub x1: usize,
    pub y1: usize,
}

impl Roi {
    /// Rectangle around (x0..=x1, y0..=y1) grown by `m`, clipped to w × h.
    pub fn around(x0: f64, y0: f64, x1: f64, y1: f64, m: f64, w: usize, h: usize) -> Roi {
        let cl = |v: f64, hi: usize| v.clamp(0.0, hi as f64) as usize;
        Roi {
            x0: cl((x0 - m).floor(), w),
            y0: cl((y0 - m).floor(), h),
            x1: cl((x1 + m).ceil() + 1.0, w),
            y1: cl((y1 + m).ceil() + 1.0, h),
        }
    }
    /// The full-resolution window under a blob of a `k`× smaller image, grown by `m`.
    pub fn around_coarse(b: &super::label::Blob, k: f64, m: f64, w: usize, h: usize) -> Roi {
        let (x0, y0) = (b.x_min as f64 * k, b.y_min as f64 * k);
        let (x1, y1) = (
            (b.x_max + 1) as f64 * k - 1.0,
            (b.y_max + 1) as f64 * k - 1.0,
        );
        Roi::around(x0, y0, x1, y1, m, w, h)
    }
    pub fn w(&self) -> usize {
        self.x1.saturating_sub(self.x0)
    }
    pub fn h(&self) -> usize {
        self.y1.saturating_sub(self.y0)
    }
}

/// One measured blob.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct BlobMeasure {
    /// Centre, full-resolution pixels.
    pub x: f64,
    pub y: f64,
    /// Area, pixels² (coverage sum).
    pub area_px: f64,
    /// Surrounding level and tip level (in `sign` space).
    pub lo: f32,
    pub hi: f32,
    pub peak: f32,
    /// Threshold used for the blob mask.
    pub threshold: f32,
    /// sqrt(λmax / λmin) of the mask's second moments.
    pub elongation: f64,
    /// Pixels in the blob mask.
    pub mask_px: usize,
    /// True when the mask reaches the ROI border (the blob may be cut).
    pub touches_border: bool,
    /// Local noise σ (sample units): robust spread of the differences of
    /// neighbouring pixels in the ROI's border ring, / √2.
    pub noise: f32,
    /// Σ (v − local level) over the coverage window: the blob's energy,
    /// which blur only spreads (sample units × px²). The top view replaces
    /// it, for tips on grid positions under blur, by [`super::disc::disc_energy`] inside
    /// a fixed disc.
    pub energy: f64,
    /// Edge spread, px: √π Σ w(1 − w) / perimeter (≈ the blur σ; about
    /// 0.3 for a sharp edge cut by the pixel grid).
    pub edge_sigma: f64,
}

/// A monotone stand-in for the angle of (dx, dy) in [0, 4) ("diamond
/// angle"): no trigonometry, good enough to split a blob's surroundings
/// into sectors.
#[inline]
fn diamond_angle(dy: f32, dx: f32) -> f32 {
    let s = dx.abs() + dy.abs();
    if s == 0.0 {
        return 0.0;
    }
    if dy >= 0.0 {
        if dx >= 0.0 { dy / s } else { 1.0 - dx / s }
    } else if dx < 0.0 {
        2.0 - dy / s
    } else {
        3.0 + dx / s
    }
}

/// The `q` quantile (nearest rank) of `v`, reordering it; 0 when empty.
pub(super) fn percentile(v: &mut [f32], q: f64) -> f32 {
    if v.is_empty() {
        return 0.0;
    }
    let i = ((v.len() - 1) as f64 * q).round() as usize;
    let (_, x, _) = v.select_nth_unstable_by(i, |a, b| a.total_cmp(b));
    *x
}

/// Where, from the local background (0) to the tip's rim level (1), the
/// coverage that locates a tip's centre starts (see `measure_blob`).
pub const CENTRE_LEVEL: f32 = 0.5;
/// Edge spread (px, `BlobMeasure::edge_sigma`) below which a tip's centre
/// is the full-range coverage centroid, and above which it is the
/// upper-part one; blended linearly between.
pub const CENTRE_BLUR: (f64, f64) = (0.6, 1.5);

/// The window margin (px beyond a blob's box) and the mask dilation (px)
/// every tip measurement uses for tips `pin_px` wide: 0.45 of a tip (at
/// least 4 px) and 0.12 of a tip (at least 2 px), so that the scale
/// search, the top view and the side view's dust measure a blob alike.
pub fn tip_window(pin_px: f64) -> (f64, usize) {
    (
        (0.45 * pin_px).max(4.0),
        ((0.12 * pin_px).round() as usize).max(2),
    )
}

/// Measures the blob nearest `seed` inside `roi`.
///
/// `dilate` is how far (px) beyond the half-level mask the coverage window
/// reaches (≈ 2 σ of the blur + 1). With a floor under the full-coverage
/// level (`hi_floor`), a blob fainter than it (the level a tip has at that
/// place) is measured as the area a tip-bright blob of the same energy
/// would have, so a faint stain does not count as a large extra.
pub fn measure_blob<P: Px>(
    plane: &Plane<P>,
    sign: f32,
    roi: Roi,
    seed: (f64, f64),
    loc: Localiser,
    dilate: usize,
    hi_floor: Option<f32>,
) -> Option<BlobMeasure> {
    measure_blob_split(plane, sign, roi, seed, loc, dilate, hi_floor, false)
}

/// The blob whose bounding box is nearest `p` (0 inside it; squared
/// distance at most `max_d2`), the larger of equally near ones.
fn nearest_blob(blobs: &[label::Blob], p: (f64, f64), max_d2: f64) -> Option<usize> {
    blobs
        .iter()
        .enumerate()
        .map(|(i, b)| {
            let dx = (b.x_min as f64 - p.0).max(p.0 - b.x_max as f64).max(0.0);
            let dy = (b.y_min as f64 - p.1).max(p.1 - b.y_max as f64).max(0.0);
            (i, dx * dx + dy * dy, b.area)
        })
        .filter(|t| t.1 <= max_d2)
        .min_by(|a, b| a.1.total_cmp(&b.1).then(b.2.cmp(&a.2)))
        .map(|t| t.0)
}

/// Steps from the half level to the blob's top in which the separation
/// from a larger structure is looked for (`measure_blob_split`).
const APART_STEPS: usize = 10;
/// How far (σ of the 3 × 3 mean) a blob cut from a larger structure must
/// stand above the saddle where they join.
const APART_SIGMA: f32 = 4.0;

/// As [`measure_blob`]; with `apart`, a blob whose half-level mask runs into a
/// larger bright structure (it reaches the window's border: debris lying
/// on the housing's edge against a brighter fixture) is cut from it where
/// it separates: the level is raised step by step, as in a component
/// tree, on a 3 × 3 mean, until the component at the seed is clear of the
/// border (and still stands `APART_SIGMA` σ of that mean above the level).
/// `lo` is then the saddle level, so `hi − lo` is the blob's prominence;
/// its coverage on each side is counted from the level beside it, but never
/// from above the saddle. A blob that never separates keeps
/// `touches_border`.
#[allow(clippy::too_many_arguments)]
pub fn measure_blob_split<P: Px>(
    plane: &Plane<P>,
    sign: f32,
    roi: Roi,
    seed: (f64, f64),
    loc: Localiser,
    dilate: usize,
    hi_floor: Option<f32>,
    apart: bool,
) -> Option<BlobMeasure> {
    let (rw, rh) = (roi.w(), roi.h());
    if rw < 3 || rh < 3 {
        return None;
    }
    let mut v = vec![0f32; rw * rh];
    for y in 0..rh {
        let row = &plane.data[(roi.y0 + y) * plane.w + roi.x0..(roi.y0 + y) * plane.w + roi.x1];
        for (o, s) in v[y * rw..(y + 1) * rw].iter_mut().zip(row) {
            *o = sign * s.f();
        }
    }
    // Surrounding level: median of the ROI's border ring (2 px).
    let mut ring = Vec::with_capacity(4 * (rw + rh));
    for y in 0..rh {
        for x in 0..rw {
            if x < 2 || y < 2 || x + 2 >= rw || y + 2 >= rh {
                ring.push(v[y * rw + x]);
            }
        }
    }
    let lo0 = percentile(&mut ring, 0.5);
    // Local noise: neighbouring-pixel differences along the border ring.
    let mut diffs: Vec<f32> = Vec::with_capacity(2 * (rw + rh));
    for y in [0, 1, rh - 2, rh - 1] {
        for x in 1..rw {
            diffs.push((v[y * rw + x] - v[y * rw + x - 1]).abs());
        }
    }
    for x in [0, 1, rw - 2, rw - 1] {
        for y in 2..rh - 2 {
            diffs.push((v[y * rw + x] - v[(y - 1) * rw + x]).abs());
        }
    }
    let noise = percentile(&mut diffs, 0.5) * 1.4826 / std::f32::consts::SQRT_2;
    let mut all = v.clone();
    let peak = percentile(&mut all, 0.995);
    if !(peak > lo0) {
        return None;
    }
    let mut thr = 0.5 * (lo0 + peak);
    // Pick the component nearest the seed; iterate the threshold once on the
    // tip's own plateau (median inside the first mask), which is robust to a
    // glint or a saturated specular spot.
    let (sx, sy) = (seed.0 - roi.x0 as f64, seed.1 - roi.y0 as f64);
    let mut comp: Option<(label::Labelling, usize)> = None;
    let mut hi = peak;
    for pass in 0..2 {
        let lab = label::label(rw, rh, |x, y| v[y * rw + x] > thr);
        let best = nearest_blob(&lab.blobs, (sx, sy), f64::INFINITY)?;
        if pass == 0 {
            let b = &lab.blobs[best];
            let mut inside: Vec<f32> = Vec::with_capacity(b.area as usize);
            for &ri in &b.runs {
                let r = lab.runs[ri as usize];
                inside.extend_from_slice(
                    &v[r.y as usize * rw + r.x0 as usize..r.y as usize * rw + r.x1 as usize],
                );
            }
            hi = percentile(&mut inside, 0.5);
            thr = 0.5 * (lo0 + hi);
        }
        comp = Some((lab, best));
    }
    let (mut lab, mut bi) = comp?;
    let at_border = |b: &label::Blob| {
        b.x_min == 0 || b.y_min == 0 || b.x_max as usize + 1 == rw || b.y_max as usize + 1 == rh
    };
    let mut saddle: Option<f32> = None;
    let mut smoothed: Option<Vec<f32>> = None;
    if apart && at_border(&lab.blobs[bi]) {
        // On a 3 × 3 mean (noise σ / 3: a noise bump on a ridge is not a
        // blob, debris of 0.4 tips still is): the component's top, then the
        // lowest level below it at which the component holding the seed no
        // longer reaches the border. The blob must stand clear of the
        // structure it touches by `APART_SIGMA` σ of that mean.
        let vs = smoothed.insert(box3(&v, rw, rh));
        let b = &lab.blobs[bi];
        let mut top = f32::NEG_INFINITY;
        for &ri in &b.runs {
            let r = lab.runs[ri as usize];
            for x in r.x0..r.x1 {
                top = top.max(vs[r.y as usize * rw + x as usize]);
            }
        }
        let (sxi, syi) = (sx.round(), sy.round());
        for step in 1..APART_STEPS {
            let level = thr + (top - thr) * step as f32 / APART_STEPS as f32;
            if top - level < APART_SIGMA * noise / 3.0 {
                break;
            }
            let l2 = label::label(rw, rh, |x, y| vs[y * rw + x] > level);
            // The component under (or within 1.5 px of) the seed.
            let near = nearest_blob(&l2.blobs, (sxi, syi), 2.25);
            let Some(i) = near else { break };
            if !at_border(&l2.blobs[i]) {
                saddle = Some(level);
                lab = l2;
                bi = i;
                break;
            }
        }
    }
    let b = &lab.blobs[bi];
    let touches_border = at_border(b);
    if let (Some(s), Some(vs)) = (saddle, smoothed.as_ref()) {
        // The blob's own level: the median inside its separated mask, on
        // the same 3 × 3 mean as the saddle (so `hi − lo` is a prominence
        // in one currency, even for a ridge thinner than the mean).
        let mut inside: Vec<f32> = Vec::with_capacity(b.area as usize);
        for &ri in &b.runs {
            let r = lab.runs[ri as usize];
            inside.extend_from_slice(
                &vs[r.y as usize * rw + r.x0 as usize..r.y as usize * rw + r.x1 as usize],
            );
        }
        hi = percentile(&mut inside, 0.5).max(s);
        thr = s;
    }

    // Mask and its dilation (square, radius `dilate`).
    let mut mask = vec![0u8; rw * rh];
    for &ri in &b.runs {
        let r = lab.runs[ri as usize];
        for x in r.x0..r.x1 {
            mask[r.y as usize * rw + x as usize] = 1;
        }
    }
    // Second moments of the mask (shape).
    let (mut sxx, mut syy, mut sxy) = (0.0, 0.0, 0.0);
    for &ri in &b.runs {
        let r = lab.runs[ri as usize];
        let dy = r.y as f64 - b.cy;
        for x in r.x0..r.x1 {
            let dx = x as f64 - b.cx;
            sxx += dx * dx;
            syy += dy * dy;
            sxy += dx * dy;
        }
    }
    let n = b.area as f64;
    let (a, c, d) = (sxx / n + 1.0 / 12.0, syy / n + 1.0 / 12.0, sxy / n);
    let tr = a + c;
    let disc = ((a - c) * (a - c) / 4.0 + d * d).sqrt();
    let elongation = ((tr / 2.0 + disc) / (tr / 2.0 - disc).max(1e-9)).sqrt();

    // Window: the mask grown ring by ring (8-neighbours) `dilate` times.
    // Each outside pixel gets an effective value min(own, brightest inner
    // neighbour's effective value): the profile may only fall going
    // outward, so beyond the dark clearance gap the brighter housing takes
    // the gap's level and carries no weight, and background noise is
    // biased down (clamped to zero weight) instead of adding up.
    let mut win = mask.clone();
    let mut veff = v.clone();
    // Only mask pixels with an outside 4-neighbour can grow the window.
    let mut frontier: Vec<usize> = (0..rw * rh)
        .filter(|&i| {
            if mask[i] == 0 {
                return false;
            }
            let (x, y) = (i % rw, i / rw);
            x == 0
                || y == 0
                || x + 1 == rw
                || y + 1 == rh
                || mask[i - 1] == 0
                || mask[i + 1] == 0
                || mask[i - rw] == 0
                || mask[i + rw] == 0
        })
        .collect();
    for _ in 0..dilate {
        let mut next: Vec<usize> = Vec::new();
        for &i in &frontier {
            for j in block3x3(i, rw, rh) {
                if win[j] == 0 {
                    win[j] = 2;
                    veff[j] = f32::NEG_INFINITY;
                    next.push(j);
                }
            }
        }
        // Effective values of the new ring from the previous ring.
        for &j in &next {
            let mut inner = f32::NEG_INFINITY;
            for k in block3x3(j, rw, rh) {
                if win[k] == 1 {
                    inner = inner.max(veff[k]);
                }
            }
            veff[j] = v[j].min(inner);
        }
        for &j in &next {
            win[j] = 1;
        }
        frontier = next;
    }

    // Coverage levels. hi: the tip's rim level, a low percentile of the
    // pixels at least 2 px inside the mask (the dome above it saturates).
    // lo: per angular sector around the blob, a low percentile of the
    // window pixels outside the mask, so a tip sitting off-centre in its
    // clearance hole (dark gap on one side, housing on the other) is
    // measured against the level actually beside each stretch of its rim.
    let mut interior: Vec<f32> = Vec::new();
    for y in 2..rh.saturating_sub(2) {
        for x in 2..rw.saturating_sub(2) {
            let i = y * rw + x;
            if mask[i] != 0
                && mask[i - 2] != 0
                && mask[i + 2] != 0
                && mask[i - 2 * rw] != 0
                && mask[i + 2 * rw] != 0
                && mask[i - rw - 1] != 0
                && mask[i - rw + 1] != 0
                && mask[i + rw - 1] != 0
                && mask[i + rw + 1] != 0
            {
                interior.push(v[i]);
            }
        }
    }
    let hi = if interior.len() >= 4 {
        percentile(&mut interior, 0.1)
    } else {
        hi
    };
    let hi_cov = hi_floor.map_or(hi, |f| hi.max(f));
    const SECTORS: usize = 16;
    let sector_of = |x: usize, y: usize| -> usize {
        let d = diamond_angle((y as f64 - b.cy) as f32, (x as f64 - b.cx) as f32);
        ((d * (SECTORS / 4) as f32) as usize).min(SECTORS - 1)
    };
    // Each window pixel's sector, taken once (it is read three times more
    // per pixel below).
    let mut sector = vec![0u8; rw * rh];
    let mut outside: Vec<Vec<f32>> = vec![Vec::new(); SECTORS];
    for y in 0..rh {
        for x in 0..rw {
            let i = y * rw + x;
            if win[i] != 0 {
                let s = sector_of(x, y);
                sector[i] = s as u8;
                if mask[i] == 0 {
                    outside[s].push(veff[i]);
                }
            }
        }
    }
    let lo_s: Vec<f32> = outside
        .iter_mut()
        .map(|o| {
            if let Some(s) = saddle {
                // Cut from a larger structure: each side measured from the
                // level beside it (the housing's, the fixture's), never
                // from above the saddle where the two join.
                if o.len() >= 3 {
                    percentile(o, 0.1).min(s)
                } else {
                    s
                }
            } else if o.len() >= 3 {
                percentile(o, 0.1).min(lo0)
            } else {
                lo0
            }
        })
        .collect();
    let lo = saddle.unwrap_or(lo0);
    // Coverage of pixel i counted from `from` of the way between the local
    // background and `hi_cov` (0: the full range).
    let coverage = |i: usize, from: f32| -> f64 {
        if mask[i] != 0 && v[i] >= hi_cov {
            return 1.0;
        }
        let l = lo_s[sector[i] as usize];
        let l = l + from * (hi_cov - l);
        ((veff[i] - l) / (hi_cov - l).max(1e-6)).clamp(0.0, 1.0) as f64
    };
    // The centre is taken from the upper part of the edge (coverage from
    // CENTRE_LEVEL of the way up): under blur, the housing beside a tip
    // that sits off-centre in its clearance hole spills light onto the
    // near edge's foot and pulls a full-range coverage centroid outward;
    // the upper part of a symmetric tip's edge is symmetric still and
    // sees less of that spill (`coverage(.., CENTRE_LEVEL)` below).
    let (mut sw, mut swx, mut swy) = (0f64, 0f64, 0f64);
    let (mut hw, mut hwx, mut hwy) = (0f64, 0f64, 0f64);
    let mut area = 0f64;
    let (mut energy, mut edge) = (0f64, 0f64);
    for y in 0..rh {
        for x in 0..rw {
            let i = y * rw + x;
            if win[i] != 0 {
                let wgt = coverage(i, 0.0);
                area += wgt;
                edge += wgt * (1.0 - wgt);
                let val = if mask[i] != 0 { v[i] } else { veff[i] };
                energy += (val - lo_s[sector[i] as usize]).max(0.0) as f64;
                if loc == Localiser::Coverage {
                    sw += wgt;
                    swx += wgt * x as f64;
                    swy += wgt * y as f64;
                    let cw = coverage(i, CENTRE_LEVEL);
                    hw += cw;
                    hwx += cw * x as f64;
                    hwy += cw * y as f64;
                }
            }
        }
    }
    match loc {
        Localiser::Centroid => {
            sw = n;
            swx = b.cx * n;
            swy = b.cy * n;
        }
        Localiser::Weighted => {
            for y in 0..rh {
                for x in 0..rw {
                    let i = y * rw + x;
                    if mask[i] != 0 {
                        let wgt = (v[i] - thr) as f64;
                        if wgt > 0.0 {
                            sw += wgt;
                            swx += wgt * x as f64;
                            swy += wgt * y as f64;
                        }
                    }
                }
            }
        }
        Localiser::Coverage => {}
    }
    if !(sw > 0.0) {
        return None;
    }
    let edge_sigma =
        std::f64::consts::PI.sqrt() * edge / (2.0 * (std::f64::consts::PI * area.max(1.0)).sqrt());
    let (mut cx, mut cy) = (swx / sw, swy / sw);
    if loc == Localiser::Coverage && hw > 0.0 {
        // A sharp edge: full-range coverage is exact (each edge pixel's
        // value is linear in the area it covers) and the upper-part centre
        // would only add pixel-grid error; a blurred edge: the upper part
        // (`coverage` from `CENTRE_LEVEL`). In between, a blend.
        let t = ((edge_sigma - CENTRE_BLUR.0) / (CENTRE_BLUR.1 - CENTRE_BLUR.0)).clamp(0.0, 1.0);
        cx = (1.0 - t) * cx + t * hwx / hw;
        cy = (1.0 - t) * cy + t * hwy / hw;
    }
    Some(BlobMeasure {
        x: roi.x0 as f64 + cx,
        y: roi.y0 as f64 + cy,
        area_px: area,
        lo,
        hi,
        peak,
        threshold: thr,
        elongation,
        mask_px: b.area as usize,
        touches_border,
        noise,
        energy,
        edge_sigma,
    })
}

/// 3 × 3 mean of a `rw` × `rh` window (cut at its edges).
fn box3(v: &[f32], rw: usize, rh: usize) -> Vec<f32> {
    (0..rw * rh)
        .map(|i| {
            let (mut s, mut n) = (0f32, 0f32);
            for j in block3x3(i, rw, rh) {
                s += v[j];
                n += 1.0;
            }
            s / n
        })
        .collect()
}

/// The indices of the 3×3 block around pixel `i` of a `rw`×`rh` window
/// (the pixel itself included; cut at the window's edges), row by row.
fn block3x3(i: usize, rw: usize, rh: usize) -> impl Iterator<Item = usize> {
    // The indices in row order, gathered on the stack: the ring growth
    // above visits 9 neighbours of every frontier pixel, and a chain of
    // iterator adapters there cost more than the work it feeds.
    let (x, y) = (i % rw, i / rw);
    let mut out = [0usize; 9];
    let mut n = 0;
    for ny in y.saturating_sub(1)..=(y + 1).min(rh - 1) {
        for nx in x.saturating_sub(1)..=(x + 1).min(rw - 1) {
            out[n] = ny * rw + nx;
            n += 1;
        }
    }
    out.into_iter().take(n)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::vision::disc::disc_energy;

    /// A 40 × 40 window: housing (level 40) below y = 20, a brighter
    /// fixture (150) above; `blob` adds a 6 × 6 square of level 220
    /// straddling the edge at x 17..23, y 17..23, and `ripple` a ridge of
    /// level 200 along the edge with a bump of 210 instead.
    fn scene(blob: bool, ripple: bool) -> Vec<u16> {
        let mut d = vec![0u16; 40 * 40];
        for y in 0..40 {
            for x in 0..40 {
                let mut v = if y < 20 { 150 } else { 40 };
                if ripple && (19..21).contains(&y) {
                    v = if (18..22).contains(&x) { 210 } else { 200 };
                }
                if blob && (17..23).contains(&x) && (17..23).contains(&y) {
                    v = 220;
                }
                d[y * 40 + x] = v;
            }
        }
        d
    }

    fn measure(d: &[u16], apart: bool) -> BlobMeasure {
        let plane = Plane {
            w: 40,
            h: 40,
            data: d,
        };
        let roi = Roi::around(20.0, 20.0, 20.0, 20.0, 9.0, 40, 40);
        measure_blob_split(
            &plane,
            1.0,
            roi,
            (19.5, 19.5),
            Localiser::Coverage,
            2,
            None,
            apart,
        )
        .expect("a blob")
    }

    #[test]
    fn debris_on_an_edge_is_cut_from_the_brighter_fixture_at_their_saddle() {
        let d = scene(true, false);
        // At half level the debris runs into the fixture.
        assert!(measure(&d, false).touches_border);
        let m = measure(&d, true);
        assert!(!m.touches_border);
        assert!(
            (m.x - 19.5).abs() < 0.3 && (m.y - 19.5).abs() < 0.3,
            "{m:?}"
        );
        // 36 px² of debris, measured above the saddle: most of it, no more.
        assert!(m.area_px > 25.0 && m.area_px < 40.0, "{m:?}");
        assert!(m.lo >= 150.0 && m.lo < 220.0, "{m:?}");
    }

    #[test]
    fn a_faint_ripple_on_a_ridge_is_not_cut() {
        // A bump of 10 on a ridge 50 above the fixture, no noise: at half
        // level it is the ridge; cut from it, it stands less above the
        // saddle than the 0.05 of the tip contrast (here 170 over the
        // housing) that `top` asks of a cut blob.
        let d = scene(false, true);
        assert!(measure(&d, false).touches_border);
        let m = measure(&d, true);
        assert!(m.touches_border || m.hi - m.lo < 0.05 * 170.0, "{m:?}");
    }

    /// A 40 × 40 image at level 60 with a disc of radius 4 at level 120
    /// centred at (20.3, 19.6), each pixel painted with its coverage
    /// (8 × 8 sub-samples); `clump` adds +40 on a 2 × 2 patch touching the
    /// tip's rim on the right and −40 on a 2 × 2 patch beyond the rim on
    /// the left (zero sum, as noise).
    fn tip(clump: bool) -> Vec<u16> {
        let (cx, cy, r) = (20.3, 19.6, 4.0);
        let mut d = vec![0u16; 40 * 40];
        for y in 0..40 {
            for x in 0..40 {
                let mut inside = 0;
                for sy in 0..8 {
                    for sx in 0..8 {
                        let px = x as f64 + (sx as f64 + 0.5) / 8.0 - 0.5;
                        let py = y as f64 + (sy as f64 + 0.5) / 8.0 - 0.5;
                        if (px - cx).hypot(py - cy) <= r {
                            inside += 1;
                        }
                    }
                }
                let mut v = 60.0 + 60.0 * inside as f64 / 64.0;
                if clump && (19..=20).contains(&y) {
                    if (25..=26).contains(&x) {
                        v += 40.0;
                    } else if (14..=15).contains(&x) {
                        v -= 40.0;
                    }
                }
                d[y * 40 + x] = v.round() as u16;
            }
        }
        d
    }

    #[test]
    fn disc_energy_is_the_tips_contrast_times_its_area() {
        let d = tip(false);
        let plane = Plane {
            w: 40,
            h: 40,
            data: &d[..],
        };
        let e = disc_energy(&plane, 1.0, (20.3, 19.6), 7.0, 60.0);
        let want = 60.0 * std::f64::consts::PI * 16.0;
        assert!((e / want - 1.0).abs() < 0.01, "{e} against {want}");
    }

    #[test]
    fn disc_energy_is_not_moved_by_a_zero_sum_clump_that_the_mask_takes_in() {
        let (clean, clumped) = (tip(false), tip(true));
        let plane = |d: &[u16]| -> (f64, f64) {
            let p = Plane {
                w: 40,
                h: 40,
                data: d,
            };
            let roi = Roi::around(20.0, 20.0, 20.0, 20.0, 12.0, 40, 40);
            let m = measure_blob(&p, 1.0, roi, (20.3, 19.6), Localiser::Coverage, 2, None)
                .expect("a tip");
            (m.energy, disc_energy(&p, 1.0, (20.3, 19.6), 7.0, 60.0))
        };
        let (mask0, disc0) = plane(&clean);
        let (mask1, disc1) = plane(&clumped);
        // The half-level mask takes the bright half of the clump in and
        // clamps the dark half away: its energy grows by most of 4 × 40.
        assert!(mask1 / mask0 > 1.04, "mask energy {mask0} → {mask1}");
        // The fixed disc counts both halves: unchanged.
        assert!(
            (disc1 / disc0 - 1.0).abs() < 0.005,
            "disc energy {disc0} → {disc1}"
        );
    }
}
