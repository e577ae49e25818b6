//! The scale from the pins' periodicity, for tips too faint for any blob
//! search to find them one by one (contrast 0.3–0.5 at gain 0.7–0.8, σ
//! 14–16 DN, 6–7 px tips blurred by 2.5 px: Rust seeds 965 105, 925 446).
//!
//! The blob searches of [`super::scale`] need each tip to clear a noise
//! floor on its own. A row of tips is also a periodic signal, and its
//! evidence adds up over every tip at once: the top-hat at a trial tip
//! width, correlated with itself shifted by the pitch that width implies,
//! is high when tips land on tips. The statistic is that correlation less
//! the larger of the correlations at 1.5 and 4/3 of the shift: a lattice
//! of every other (every third) tip also correlates at its own shift, and
//! at 1.5 (4/3) of it too, where a true pitch lands on the housing between
//! tips. Structure that does not repeat at the pitch (an edge of the
//! housing along the row, a gradient, texture) correlates alike at every
//! shift along the row and cancels. It is taken over the band of lines
//! across the row that holds the part, and counted in standard deviations
//! of its value on noise alone. The best width's pitch is then refined by
//! scanning the shift around it, and again at several pitches.
//!
//! The pass is a fallback ([`super::scale::estimate`] runs it only when
//! its blob passes find no lattice whose tips hold): images read before
//! are read the same.

use super::detect::{self, Smoothing};
use super::gray::{Coarse, CoarseCache, Plane, Px};
use super::recipe::Recipe;
use super::scale::{ScaleEstimate, W_MIN};

/// Least periodicity statistic, in standard deviations of its value on
/// noise alone ([`z_at`]), for a pitch to count: on noise alone, the best
/// band of every width of the ladder stays below 2.5
/// (`tests::noise_alone_shows_no_period`).
const MIN_Z: f64 = 5.0;

/// The steepest row looked along, degrees: the envelope's rotation and a
/// degree more (each offset across is a correlation over the frame; the
/// grid's 12° would double the work for parts outside the envelope).
const TILT: f64 = super::envelope::ROTATION_DEG + 1.0;

/// The pitch along a row (or down the column of a one-column part) from
/// the periodicity of the top-hat, with the tip width it implies; `None`
/// when no width on the ladder shows a lattice.
pub(super) fn estimate<P: Px>(
    plane: &Plane<P>,
    sign: f32,
    recipe: &Recipe,
) -> Option<ScaleEstimate> {
    let along_x = recipe.cols >= 2;
    if !along_x && recipe.rows < 2 {
        return None;
    }
    let n_along = if along_x { recipe.cols } else { recipe.rows } as f64;
    let pitch_mm = if along_x {
        recipe.pitch_mm[0]
    } else {
        recipe.pitch_mm[1]
    };
    let ratio = pitch_mm / recipe.pin_mm;
    let (wd, ht) = (plane.w as f64, plane.h as f64);
    // The row fits in the frame (with its end tips whole).
    let w_max = ((wd.max(ht)) / (n_along * ratio)).min(wd.min(ht) / 3.0);
    let mut cache = CoarseCache::new(plane, sign);
    // (z, w, k, band, top-hat) of the best width so far.
    let mut best: Option<(f64, f64, usize, usize, Vec<f32>)> = None;
    let mut w = w_max;
    while w >= W_MIN {
        let k = detect::coarse_factor(w);
        let coarse = cache.get(k);
        let t = centred_tophat(coarse, w);
        let p = w * ratio / k as f64;
        let band = band_lines(recipe, w / k as f64, p, along_x);
        let s = z_at(
            &t,
            coarse.w,
            coarse.h,
            p,
            band,
            along_x,
            smoothing_box(w, k),
        );
        if let Some((s, b)) = s
            && best.as_ref().is_none_or(|c| s > c.0)
        {
            best = Some((s, w, k, b, t));
        }
        w /= 1.2;
    }
    let (s, w, k, b, t) = best?;
    if s < MIN_Z {
        return None;
    }
    let coarse = cache.get(k);
    let p = w * ratio / k as f64;
    let lines = b..b + band_lines(recipe, w / k as f64, p, along_x);
    let n_along_u = if along_x { recipe.cols } else { recipe.rows };
    let pitch_c = refine(&t, (coarse.w, coarse.h), along_x, p, n_along_u, lines)?;
    let pitch_along = pitch_c * k as f64;
    let pitch_x = if along_x {
        pitch_along
    } else {
        pitch_along * recipe.pitch_mm[0] / recipe.pitch_mm[1]
    };
    Some(ScaleEstimate {
        pin_px: pitch_along / ratio,
        pitch_px: pitch_x,
        support: 0,
        size_ratio: 1.0,
        from_period: true,
    })
}

/// What an inspection that finds too few tips adds to its error when the
/// scale came from the periodicity: the part is there, its tips too faint
/// to be read one by one (Rust seeds 965 105, 925 446). Empty otherwise.
pub(super) fn too_faint(estimate: Option<&ScaleEstimate>) -> String {
    match estimate {
        Some(e) if e.from_period => format!(
            "; the pins' periodicity shows a lattice at a pitch of {:.1} px, but no tip stands out from the noise on its own: too faint to judge each pin",
            e.pitch_px
        ),
        _ => String::new(),
    }
}

/// The top-hat's smoothing box for tips `w` px wide at coarse factor `k`
/// ([`Smoothing::Faint`]'s, `2m + 1` coarse px across).
fn smoothing_box(w: f64, k: usize) -> f64 {
    (2 * detect::smoothing_half_width(w / k as f64, Smoothing::Faint) + 1) as f64
}

/// How many lines across the row a band holding the part's tips spans
/// (coarse px): the rows (or columns) across, a tip, and the drift of a
/// row tilted by the envelope's rotation along its length.
fn band_lines(recipe: &Recipe, tip_c: f64, p: f64, along_x: bool) -> usize {
    let (n_along, n_across, across_mm, along_mm) = if along_x {
        (
            recipe.cols,
            recipe.rows,
            recipe.pitch_mm[1],
            recipe.pitch_mm[0],
        )
    } else {
        (
            recipe.rows,
            recipe.cols,
            recipe.pitch_mm[0],
            recipe.pitch_mm[1],
        )
    };
    let length = (n_along.max(1) - 1) as f64 * p;
    let across = (n_across.max(1) - 1) as f64 * p * across_mm / along_mm;
    let drift = length * super::envelope::ROTATION_DEG.to_radians().tan();
    (across + drift + 1.5 * tip_c).ceil() as usize + 2
}

/// The top-hat of the coarse search for tips `w` px wide (the faint
/// tips' wider smoothing box), less its mean.
fn centred_tophat(coarse: &Coarse, w: f64) -> Vec<f32> {
    let (mut t, _) = detect::tophat(coarse, w, Smoothing::Faint);
    let mean = t.iter().map(|&v| v as f64).sum::<f64>() / t.len().max(1) as f64;
    t.iter_mut().for_each(|v| *v -= mean as f32);
    t
}

/// Per line across the row, the sums of `t` (w × h) times itself shifted
/// by `d` along the row (x when `along_x`) and `e` across it, for each
/// `e` within [`TILT`]; each line holds `len_along − d` products.
/// `None` when the shift leaves less than a third of the row.
fn line_sums(t: &[f32], w: usize, h: usize, d: usize, along_x: bool) -> Option<Vec<Vec<f64>>> {
    let (len_along, len_across) = if along_x { (w, h) } else { (h, w) };
    if d == 0 || 3 * d >= 2 * len_along {
        return None;
    }
    let tilt = TILT.to_radians().tan();
    let reach = (tilt * d as f64).ceil() as isize;
    let out = (-reach..=reach)
        .filter(|e| e.unsigned_abs() < len_across)
        .map(|e| {
            (0..len_across)
                .map(|j| lag_sum(t, (w, h), along_x, (d, e), j..j + 1).0)
                .collect()
        })
        .collect();
    Some(out)
}

/// Prefix sums of each offset's line sums, for band sums in O(1).
fn prefix(sums: &[Vec<f64>]) -> Vec<Vec<f64>> {
    sums.iter()
        .map(|l| {
            let mut acc = vec![0f64; l.len() + 1];
            for (i, v) in l.iter().enumerate() {
                acc[i + 1] = acc[i] + v;
            }
            acc
        })
        .collect()
}

/// The best offset's correlation over lines `b..b + n` (sum of products).
fn band_best(pre: &[Vec<f64>], b: usize, n: usize) -> f64 {
    pre.iter()
        .map(|a| a[b + n] - a[b])
        .fold(f64::NEG_INFINITY, f64::max)
}

/// The periodicity statistic at shift `p` (coarse px), in standard
/// deviations of its value on noise alone, over the band of `band` lines
/// across the row where it is highest: the correlation at `p` less the
/// larger at `1.5 p` and `4 p / 3` (lags beyond the noise's own
/// correlation length: a lattice of every other tip correlates at
/// `1.5 p`, of every third at `4 p / 3`, a true pitch at neither). White
/// noise through the top-hat's smoothing box (`boxw` coarse px) correlates
/// over about a box, so the statistic over `n` products has a standard
/// deviation of about `boxw / √n` times the top-hat's variance (measured on
/// noise alone in `tests::noise_alone_shows_no_period`).
fn z_at(
    t: &[f32],
    w: usize,
    h: usize,
    p: f64,
    band: usize,
    along_x: bool,
    boxw: f64,
) -> Option<(f64, usize)> {
    let (len_along, len_across) = if along_x { (w, h) } else { (h, w) };
    let var = t.iter().map(|&v| (v as f64) * (v as f64)).sum::<f64>() / t.len().max(1) as f64;
    if var <= 0.0 {
        return None;
    }
    let lag = |f: f64| (f * p).round() as usize;
    let full = prefix(&line_sums(t, w, h, lag(1.0), along_x)?);
    let refs: Vec<(Vec<Vec<f64>>, usize)> = [1.5, 4.0 / 3.0]
        .iter()
        .filter_map(|&f| line_sums(t, w, h, lag(f), along_x).map(|s| (prefix(&s), lag(f))))
        .collect();
    let n = band.min(len_across);
    let step = (n / 4).max(1);
    let mut best = (f64::NEG_INFINITY, 0);
    let mut b = 0;
    while b + n <= len_across {
        let c = |pre: &[Vec<f64>], d: usize| band_best(pre, b, n) / (n * (len_along - d)) as f64;
        let reference = refs.iter().map(|(pre, d)| c(pre, *d)).fold(0f64, f64::max);
        let s = (c(&full, lag(1.0)) - reference) / var;
        let products = (n * (len_along - lag(1.0))) as f64;
        let z = s * products.sqrt() / boxw;
        if z > best.0 {
            best = (z, b);
        }
        if b + n == len_across {
            break;
        }
        b = (b + step).min(len_across - n);
    }
    best.0.is_finite().then_some(best)
}

/// The sum of `t` (w × h) times itself shifted by `d` along the row (x
/// when `along_x`) and `e` across it, over the lines `lines` across the
/// row, and how many products it holds.
fn lag_sum(
    t: &[f32],
    (w, h): (usize, usize),
    along_x: bool,
    (d, e): (usize, isize),
    lines: std::ops::Range<usize>,
) -> (f64, usize) {
    let (len_along, len_across) = if along_x { (w, h) } else { (h, w) };
    let ea = e.unsigned_abs();
    if d >= len_along || ea >= len_across {
        return (0.0, 0);
    }
    let (mut sum, mut n) = (0f64, 0usize);
    for j in lines.start..lines.end.min(len_across - ea) {
        let (j0, j1) = if e >= 0 { (j, j + ea) } else { (j + ea, j) };
        let row: f32 = if along_x {
            let a = &t[j0 * w..j0 * w + w - d];
            let b = &t[j1 * w + d..j1 * w + w];
            a.iter().zip(b).map(|(x, y)| x * y).sum()
        } else {
            (0..h - d)
                .map(|i| t[i * w + j0] * t[(i + d) * w + j1])
                .sum()
        };
        sum += row as f64;
        n += len_along - d;
    }
    (sum, n)
}

/// The lag (coarse px, to a fraction by a parabola through the peak and
/// its neighbours) of highest mean product over `lines` among the lags
/// `lo..=hi`, each at its best offset across within `es`; with that
/// offset.
fn peak_lag(
    t: &[f32],
    size: (usize, usize),
    along_x: bool,
    (lo, hi): (usize, usize),
    es: std::ops::RangeInclusive<isize>,
    lines: std::ops::Range<usize>,
) -> Option<(f64, isize)> {
    let at = |d: usize| -> Option<(f64, isize)> {
        es.clone()
            .filter_map(|e| {
                let (s, n) = lag_sum(t, size, along_x, (d, e), lines.clone());
                (n > 0).then(|| (s / n as f64, e))
            })
            .max_by(|a, b| a.0.total_cmp(&b.0))
    };
    let cs: Vec<(usize, f64, isize)> = (lo.max(2) - 1..=hi + 1)
        .filter_map(|d| at(d).map(|(c, e)| (d, c, e)))
        .collect();
    let i = (1..cs.len().saturating_sub(1))
        .filter(|&i| {
            (lo..=hi).contains(&cs[i].0) && cs[i - 1].0 + 1 == cs[i].0 && cs[i].0 + 1 == cs[i + 1].0
        })
        .max_by(|&a, &b| cs[a].1.total_cmp(&cs[b].1))?;
    let (c0, c1, c2) = (cs[i - 1].1, cs[i].1, cs[i + 1].1);
    let den = c0 - 2.0 * c1 + c2;
    let off = if den < 0.0 {
        (0.5 * (c0 - c2) / den).clamp(-0.5, 0.5)
    } else {
        0.0
    };
    Some((cs[i].0 as f64 + off, cs[i].2))
}

/// The pitch (coarse px) at the best width: the lag of highest
/// correlation within ±20 % of `p` over the band of lines where the
/// lattice stood out, then read again at `m` pitches (half the row's
/// length), where the same error in the lag is an `m`-th of the pitch.
fn refine(
    t: &[f32],
    size: (usize, usize),
    along_x: bool,
    p: f64,
    n_along: u32,
    lines: std::ops::Range<usize>,
) -> Option<f64> {
    let len_along = if along_x { size.0 } else { size.1 };
    let tilt = TILT.to_radians().tan();
    let reach = (tilt * 1.25 * p).ceil() as isize;
    let lags = ((0.8 * p).floor() as usize, (1.25 * p).ceil() as usize);
    let (p1, e1) = peak_lag(t, size, along_x, lags, -reach..=reach, lines.clone())?;
    let m = ((n_along.saturating_sub(1)) / 2).max(1) as f64;
    let m = m.min((2.0 * len_along as f64 / 3.0 / p1).floor());
    if m < 2.0 {
        return Some(p1);
    }
    let mi = m as isize;
    let es = mi * e1 - mi / 2 - 1..=mi * e1 + mi / 2 + 1;
    let lags = (
        (0.95 * m * p1).floor() as usize,
        (1.05 * m * p1).ceil() as usize,
    );
    match peak_lag(t, size, along_x, lags, es, lines) {
        Some((pm, _)) => Some(pm / m),
        None => Some(p1),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Gaussian noise alone (σ 15 DN, 8-bit) at three frame sizes: the
    /// statistic in [`z_at`]'s units over the whole ladder of widths
    /// stays within ±4, so the 5 of [`MIN_Z`] is never reached, and
    /// [`estimate`] finds no pitch.
    #[test]
    fn noise_alone_shows_no_period() {
        let mut rng = super::super::synth::Rng::new(12345);
        let recipe = Recipe::from_toml_str(
            "part_number = \"T\"\nview = \"top\"\nrows = 1\ncols = 8\npitch_mm = [1.0, 1.0]\npin_mm = 0.3\npin_shape = \"round\"\npolarity = \"bright\"\n[tolerance]\nposition_mm = 0.1\n",
            "t",
        )
        .unwrap();
        let mut zs = Vec::new();
        for &(w, h) in &[(320usize, 240usize), (640, 480), (1000, 1000)] {
            for _ in 0..3 {
                let data: Vec<u8> = (0..w * h)
                    .map(|_| (128.0 + 15.0 * rng.normal()).clamp(0.0, 255.0) as u8)
                    .collect();
                let plane = Plane { w, h, data: &data };
                assert_eq!(estimate(&plane, 1.0, &recipe), None);
                let mut wt = 40.0;
                while wt >= W_MIN {
                    let c = Coarse::build(&plane, detect::coarse_factor(wt), 1.0);
                    let t = centred_tophat(&c, wt);
                    let p = wt * 3.33 / c.k as f64;
                    let band = band_lines(&recipe, wt / c.k as f64, p, true);
                    if let Some((z, _)) = z_at(&t, c.w, c.h, p, band, true, smoothing_box(wt, c.k))
                    {
                        zs.push(z);
                    }
                    wt /= 1.2;
                }
            }
        }
        assert!(zs.len() > 100);
        let worst = zs.iter().fold(0f64, |a, z| a.max(z.abs()));
        assert!(worst < 4.0, "noise alone reached {worst:.2}");
        let mean = zs.iter().sum::<f64>() / zs.len() as f64;
        // (Each value is the best band's: noise alone averages about one.)
        assert!(mean.abs() < 1.5, "noise alone averages {mean:.2}");
    }

    fn scene_plane(r: &Recipe, contrast: f64, seed: u64) -> (Vec<u8>, usize, usize) {
        let (d, w, h, _) = super::super::scale::tests::faint_scene(
            r,
            MM_PER_PX,
            (contrast, 14.0, 2.4),
            seed,
            -2.8,
        );
        (d, w, h)
    }

    const MM_PER_PX: f64 = 0.044;

    /// Rows of small faint tips (0.3 mm at 0.044 mm/px: 6.8 px, blurred
    /// by 2.4 px, σ 14 DN, tilted 2.8°) over a ladder of contrasts down to
    /// where no tip stands out: wherever the periodicity gives a pitch it
    /// is the scene's (within 1 %; measured: 0.5 % at most), and it gives
    /// one on most scenes (12 of 20: none below contrast 0.15).
    #[test]
    fn faint_rows_give_the_scenes_pitch() {
        let truth = 1.0 / MM_PER_PX;
        let (mut found, mut tried) = (0, 0);
        for (rows, cols) in [(1, 14), (2, 18)] {
            let r = Recipe::from_toml_str(
                &format!(
                    "part_number = \"T\"\nview = \"top\"\nrows = {rows}\ncols = {cols}\npitch_mm = [1.0, 1.0]\npin_mm = 0.3\npin_shape = \"round\"\npolarity = \"bright\"\n[tolerance]\nposition_mm = 0.13\n"
                ),
                "t",
            )
            .unwrap();
            for contrast in [0.06, 0.1, 0.15, 0.25, 0.4] {
                for seed in 1..=2 {
                    let (d, w, h) = scene_plane(&r, contrast, seed);
                    let plane = Plane { w, h, data: &d };
                    tried += 1;
                    if let Some(e) = estimate(&plane, 1.0, &r) {
                        assert!(
                            (e.pitch_px / truth - 1.0).abs() < 0.01,
                            "{rows} x {cols}, contrast {contrast}, seed {seed}: pitch {:.2} px, truth {truth:.2}",
                            e.pitch_px
                        );
                        found += 1;
                    }
                }
            }
        }
        assert!(2 * found > tried, "a pitch on {found} of {tried} scenes");
    }
}
