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

/// ln Γ(x) for x > 0 (Lanczos, g = 7, 9 terms; relative error < 1e-13).
fn ln_gamma(x: f64) -> f64 {
    const C: [f64; 9] = [
        0.999_999_999_999_809_9,
        676.520_368_121_885_1,
        -1_259.139_216_722_402_8,
        771.323_428_777_653_1,
        -176.615_029_162_140_6,
        12.507_343_278_686_905,
        -0.138_571_095_265_720_12,
        9.984_369_578_019_572e-6,
        1.505_632_735_149_311_6e-7,
    ];
    if x < 0.5 {
        let pi = std::f64::consts::PI;
        return (pi / (pi * x).sin()).ln() - ln_gamma(1.0 - x);
    }
    let x = x - 1.0;
    let mut a = C[0];
    let t = x + 7.5;
    for (i, c) in C.iter().enumerate().skip(1) {
        a += c / (x + i as f64);
    }
    0.5 * (2.0 * std::f64::consts::PI).ln() + (x + 0.5) * t.ln() - t + a.ln()
}

/// Continued fraction of the incomplete beta function (modified Lentz).
fn beta_cf(a: f64, b: f64, x: f64) -> f64 {
    let tiny = 1e-300;
    let (qab, qap, qam) = (a + b, a + 1.0, a - 1.0);
    let mut c = 1.0;
    let mut d = 1.0 - qab * x / qap;
    if d.abs() < tiny {
        d = tiny;
    }
    d = 1.0 / d;
    let mut h = d;
    for m in 1..300 {
        let m = m as f64;
        let m2 = 2.0 * m;
        let aa = m * (b - m) * x / ((qam + m2) * (a + m2));
        d = 1.0 + aa * d;
        if d.abs() < tiny {
            d = tiny;
        }
        c = 1.0 + aa / c;
        if c.abs() < tiny {
            c = tiny;
        }
        d = 1.0 / d;
        h *= d * c;
        let aa = -(a + m) * (qab + m) * x / ((a + m2) * (qap + m2));
        d = 1.0 + aa * d;
        if d.abs() < tiny {
            d = tiny;
        }
        c = 1.0 + aa / c;
        if c.abs() < tiny {
            c = tiny;
        }
        d = 1.0 / d;
        let del = d * c;
        h *= del;
        if (del - 1.0).abs() < 1e-15 {
            break;
        }
    }
    h
}

/// Regularised incomplete beta I_x(a, b).
fn inc_beta(a: f64, b: f64, x: f64) -> f64 {
    if x <= 0.0 {
        return 0.0;
    }
    if x >= 1.0 {
        return 1.0;
    }
    let lbt = ln_gamma(a + b) - ln_gamma(a) - ln_gamma(b) + a * x.ln() + b * (1.0 - x).ln();
    if x < (a + 1.0) / (a + b + 2.0) {
        lbt.exp() * beta_cf(a, b, x) / a
    } else {
        1.0 - lbt.exp() * beta_cf(b, a, 1.0 - x) / b
    }
}

/// Student's t cumulative distribution with ν degrees of freedom.
pub fn t_cdf(t: f64, nu: f64) -> f64 {
    let x = nu / (nu + t * t);
    let tail = 0.5 * inc_beta(0.5 * nu, 0.5, x);
    if t >= 0.0 { 1.0 - tail } else { tail }
}

/// The p-quantile of Student's t with ν > 0 degrees of freedom (bisection
/// on [`t_cdf`] to 1e-12); the normal quantile's limit for ν = ∞.
pub fn t_quantile(p: f64, nu: f64) -> f64 {
    let nu = if nu.is_finite() { nu.max(1e-3) } else { 1e7 };
    if p == 0.5 {
        return 0.0;
    }
    let (mut lo, mut hi) = (-1e4, 1e4);
    for _ in 0..200 {
        let mid = 0.5 * (lo + hi);
        if t_cdf(mid, nu) < p {
            lo = mid;
        } else {
            hi = mid;
        }
        if hi - lo < 1e-12 {
            break;
        }
    }
    0.5 * (lo + hi)
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
