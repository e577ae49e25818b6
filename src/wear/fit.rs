//! Degradation models fitted to a clearance history with honest uncertainty.
//!
//! Linear wear: c(x) = a + b·x, x the head's cumulative cycle count at the
//! log (or the time in days when the cycle counter is unknown). Each point
//! carries the calibration's expanded uncertainty U95; its standard
//! uncertainty σ_i = U95_i/2 gives the weight w_i = 1/σ_i². Weighted least
//! squares:
//!
//! ```text
//! S = Σw, Sx = Σw·x, Sy = Σw·y, Sxx = Σw·x², Sxy = Σw·x·y, Δ = S·Sxx − Sx²
//! b = (S·Sxy − Sx·Sy)/Δ,  a = (Sxx·Sy − Sx·Sxy)/Δ
//! var(b) = S/Δ, var(a) = Sxx/Δ, cov(a, b) = −Sx/Δ      (σ_i taken as known)
//! χ² = Σw·(y − a − b·x)², ν = n − 2, χ²_red = χ²/ν
//! ```
//!
//! When χ²_red > 1 the scatter is larger than the stated uncertainties
//! explain (the calibrations' U95 too small, or wear not linear); the
//! covariance is then scaled by χ²_red (Birge ratio), never shrunk below the
//! stated one. Intervals use Student's t with ν = n − 2 degrees of freedom.
//! R² is the weighted coefficient of determination.

use serde::{Deserialize, Serialize};
use statrs::distribution::{ContinuousCDF, Normal, StudentsT};

/// A straight line fitted by weighted least squares.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct LineFit {
    pub n: usize,
    pub intercept: f64,
    pub slope: f64,
    /// Covariance of (intercept, slope) after the Birge scaling.
    pub var_intercept: f64,
    pub var_slope: f64,
    pub cov: f64,
    /// Degrees of freedom n − 2.
    pub dof: usize,
    pub chi2: f64,
    pub chi2_red: f64,
    /// The covariance was scaled by χ²_red (> 1).
    pub birge_scaled: bool,
    pub r2: f64,
    /// Standard uncertainty of the slope and its 95 % interval (Student t, ν = n − 2).
    pub slope_se: f64,
    pub slope_lo95: f64,
    pub slope_hi95: f64,
}

impl LineFit {
    /// The fitted line at x.
    pub fn at(&self, x: f64) -> f64 {
        self.intercept + self.slope * x
    }

    /// Standard uncertainty of the fitted line (the mean) at x.
    pub fn se_at(&self, x: f64) -> f64 {
        (self.var_intercept + 2.0 * x * self.cov + x * x * self.var_slope)
            .max(0.0)
            .sqrt()
    }
}

/// Why a line could not be fitted.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct FitError(pub String);

impl std::fmt::Display for FitError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.0)
    }
}

/// Weighted least-squares line through (x, y) with standard uncertainties
/// `sigma` (module docs). Needs 3 points (ν ≥ 1) at two or more distinct x.
pub fn fit_line(x: &[f64], y: &[f64], sigma: &[f64]) -> Result<LineFit, FitError> {
    let n = x.len();
    if y.len() != n || sigma.len() != n {
        return Err(FitError("x, y and σ differ in length".into()));
    }
    if n < 3 {
        return Err(FitError(format!(
            "a trend needs at least 3 calibrated logs, {n} available"
        )));
    }
    if let Some(i) = (0..n).find(|&i| {
        !(x[i].is_finite() && y[i].is_finite() && sigma[i].is_finite() && sigma[i] > 0.0)
    }) {
        return Err(FitError(format!(
            "point {i} is not usable (x {}, y {}, σ {})",
            x[i], y[i], sigma[i]
        )));
    }
    let (mut s, mut sx, mut sy, mut sxx, mut sxy) = (0.0, 0.0, 0.0, 0.0, 0.0);
    for i in 0..n {
        let w = 1.0 / (sigma[i] * sigma[i]);
        s += w;
        sx += w * x[i];
        sy += w * y[i];
        sxx += w * x[i] * x[i];
        sxy += w * x[i] * y[i];
    }
    let delta = s * sxx - sx * sx;
    let xspread = x.iter().cloned().fold(f64::NEG_INFINITY, f64::max)
        - x.iter().cloned().fold(f64::INFINITY, f64::min);
    if !(delta > 0.0) || !(xspread > 0.0) {
        return Err(FitError(
            "all logs are at the same point (cycles or time): no trend can be fitted".into(),
        ));
    }
    let slope = (s * sxy - sx * sy) / delta;
    let intercept = (sxx * sy - sx * sxy) / delta;
    let mut chi2 = 0.0;
    let ybar = sy / s;
    let mut ss_tot = 0.0;
    for i in 0..n {
        let w = 1.0 / (sigma[i] * sigma[i]);
        chi2 += w * (y[i] - intercept - slope * x[i]).powi(2);
        ss_tot += w * (y[i] - ybar).powi(2);
    }
    let dof = n - 2;
    let chi2_red = chi2 / dof as f64;
    let scale = chi2_red.max(1.0);
    let var_slope = s / delta * scale;
    let var_intercept = sxx / delta * scale;
    let cov = -sx / delta * scale;
    let slope_se = var_slope.sqrt();
    let t = t_quantile(0.975, dof as f64);
    Ok(LineFit {
        n,
        intercept,
        slope,
        var_intercept,
        var_slope,
        cov,
        dof,
        chi2,
        chi2_red,
        birge_scaled: chi2_red > 1.0,
        r2: if ss_tot > 0.0 {
            1.0 - chi2 / ss_tot
        } else {
            f64::NAN
        },
        slope_se,
        slope_lo95: slope - t * slope_se,
        slope_hi95: slope + t * slope_se,
    })
}

/// Above this many degrees of freedom the quantile is Fisher's expansion
/// about the normal quantile, not `statrs`'s inverse: statrs 0.19's
/// `StudentsT::inverse_cdf` (through its inverse regularised incomplete
/// beta) loses accuracy as ν grows (measured here: CDF at the returned
/// quantile off by 4e-7 at ν = 1e5, 7e-5 at 1e6, 1e-2 at 1e7) and never
/// returns for ν = ∞. At ν = 1e4 statrs is still exact to 1e-13 and the
/// expansion below to 2e-9 (both measured against statrs's own CDF).
const FISHER_NU: f64 = 1e4;

fn std_normal() -> Normal {
    Normal::standard()
}

/// Student's t cumulative distribution with ν > 0 degrees of freedom
/// (`statrs`; the normal for ν = ∞). NaN for ν ≤ 0 or NaN.
pub fn t_cdf(t: f64, nu: f64) -> f64 {
    if !(nu > 0.0) || t.is_nan() {
        return f64::NAN;
    }
    if nu.is_infinite() {
        return std_normal().cdf(t);
    }
    StudentsT::new(0.0, 1.0, nu).map_or(f64::NAN, |d| d.cdf(t))
}

/// The p-quantile of Student's t with ν > 0 degrees of freedom: `statrs`
/// for ν ≤ 10⁴, Fisher's expansion t ≈ z + (z³ + z)/(4ν) + (5z⁵ + 16z³ +
/// 3z)/(96ν²) above (Abramowitz & Stegun 26.7.5), the normal quantile z for
/// ν = ∞. NaN for p outside (0, 1) or ν ≤ 0.
pub fn t_quantile(p: f64, nu: f64) -> f64 {
    if !(p > 0.0 && p < 1.0 && nu > 0.0) {
        return f64::NAN;
    }
    if p == 0.5 {
        return 0.0;
    }
    let z = std_normal().inverse_cdf(p);
    if nu.is_infinite() {
        return z;
    }
    if nu > FISHER_NU {
        let (z3, z5) = (z.powi(3), z.powi(5));
        return z + (z3 + z) / (4.0 * nu) + (5.0 * z5 + 16.0 * z3 + 3.0 * z) / (96.0 * nu * nu);
    }
    StudentsT::new(0.0, 1.0, nu).map_or(f64::NAN, |d| d.inverse_cdf(p))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn t_quantiles_match_the_printed_table() {
        // Student t table (two-sided 95 % and 80 %), e.g. NIST/SEMATECH 1.3.6.7.2.
        for (nu, t975, t90) in [
            (1.0, 12.706, 3.078),
            (2.0, 4.303, 1.886),
            (5.0, 2.571, 1.476),
            (10.0, 2.228, 1.372),
            (30.0, 2.042, 1.310),
        ] {
            assert!((t_quantile(0.975, nu) - t975).abs() < 1e-3, "ν {nu}");
            assert!((t_quantile(0.90, nu) - t90).abs() < 1e-3, "ν {nu}");
            assert!((t_quantile(0.025, nu) + t975).abs() < 1e-3, "ν {nu}");
        }
        assert!((t_quantile(0.975, f64::INFINITY) - 1.95996).abs() < 1e-4);
        // Large ν (where statrs's inverse drifts) and ν = ∞ (where it never
        // returns): the table's last rows, z₀.₉₇₅ = 1.959964, z₀.₉₀ = 1.281552.
        for nu in [120.0, 1e4, 1e5, 1e6, 1e7, 1e12, f64::INFINITY] {
            let (t975, t90) = if nu == 120.0 {
                (1.980, 1.289)
            } else {
                (1.960, 1.282)
            };
            assert!((t_quantile(0.975, nu) - t975).abs() < 1e-3, "ν {nu}");
            assert!((t_quantile(0.90, nu) - t90).abs() < 1e-3, "ν {nu}");
        }
        assert!((t_quantile(0.975, f64::INFINITY) - 1.959_964).abs() < 1e-6);
        // Either side of the switch to Fisher's expansion: continuous to 1e-8.
        let (a, b) = (
            t_quantile(0.975, FISHER_NU),
            t_quantile(0.975, FISHER_NU * (1.0 + 1e-9)),
        );
        assert!((a - b).abs() < 1e-8, "{a} {b}");
        // The CDF: table values back, symmetric, the normal at ν = ∞.
        assert!((t_cdf(2.228, 10.0) - 0.975).abs() < 1e-4);
        assert!((t_cdf(-3.078, 1.0) - 0.10).abs() < 1e-4);
        assert!((t_cdf(1.959_964, f64::INFINITY) - 0.975).abs() < 1e-6);
        assert!(t_quantile(0.0, 5.0).is_nan() && t_quantile(0.5, 0.0).is_nan());
    }

    /// Hand-computed reference (written out, not produced by this code):
    /// x = [0, 1, 2, 3], y = [1.0, 1.9, 3.2, 3.9], σ = [0.1, 0.1, 0.2, 0.2]
    /// → w = [100, 100, 25, 25]; S = 250, Sx = 100+50+75 = 225,
    /// Sxx = 100+100+225 = 425, Sy = 100+190+80+97.5 = 467.5,
    /// Sxy = 190+160+292.5 = 642.5; Δ = 250·425 − 225² = 55 625.
    /// b = (250·642.5 − 225·467.5)/Δ = (160 625 − 105 187.5)/55 625 = 0.996 629…
    /// a = (425·467.5 − 225·642.5)/Δ = (198 687.5 − 144 562.5)/55 625 = 0.973 034…
    /// residuals: 1.0 − 0.973034 = 0.026966; 1.9 − 1.969663 = −0.069663;
    /// 3.2 − 2.966292 = 0.233708; 3.9 − 3.962921 = −0.062921
    /// χ² = 100·0.000727 + 100·0.004853 + 25·0.054619 + 25·0.003959
    ///    = 0.07272 + 0.48529 + 1.36547 + 0.09897 = 2.02245; ν = 2; χ²_red = 1.01122
    /// var(b) = S/Δ·χ²_red = 0.0044944·1.01122 = 0.0045449 → se 0.067416
    /// t(0.975, 2) = 4.303 → slope ∈ 0.99663 ± 0.29009.
    #[test]
    fn weighted_line_matches_the_hand_computation() {
        let f = fit_line(
            &[0.0, 1.0, 2.0, 3.0],
            &[1.0, 1.9, 3.2, 3.9],
            &[0.1, 0.1, 0.2, 0.2],
        )
        .unwrap();
        assert!((f.slope - 0.996_629).abs() < 1e-6, "{f:?}");
        assert!((f.intercept - 0.973_034).abs() < 1e-6);
        assert!((f.chi2 - 2.022_45).abs() < 1e-4);
        assert!((f.chi2_red - 1.011_22).abs() < 1e-4);
        assert!(f.birge_scaled);
        assert!((f.slope_se - 0.067_416).abs() < 1e-5);
        assert!((f.slope_hi95 - f.slope - 0.2901).abs() < 1e-3);
        assert_eq!(f.dof, 2);
    }

    #[test]
    fn too_few_or_degenerate_points_are_errors_not_panics() {
        assert!(fit_line(&[0.0, 1.0], &[1.0, 2.0], &[0.1, 0.1]).is_err());
        assert!(fit_line(&[1.0, 1.0, 1.0], &[1.0, 2.0, 3.0], &[0.1, 0.1, 0.1]).is_err());
        assert!(fit_line(&[0.0, 1.0, 2.0], &[1.0, f64::NAN, 3.0], &[0.1, 0.1, 0.1]).is_err());
        assert!(fit_line(&[0.0, 1.0, 2.0], &[1.0, 2.0, 3.0], &[0.1, 0.0, 0.1]).is_err());
    }
}
