//! When will the clearance reach its limit?
//!
//! With the fitted line c(x) = a + b·x (covariance V of (a, b), ν degrees of
//! freedom) and the limit L, the crossing is x* = (L − a)/b. Its interval
//! at level p is Fieller's: the x where the fitted line's two-sided
//! p-confidence band meets L, the roots of
//!
//! ```text
//! (a + b·x − L)² = t²·(V_aa + 2x·V_ab + x²·V_bb),  t = t_{(1+p)/2}(ν)
//! (b² − t²V_bb)·x² + 2((a − L)·b − t²V_ab)·x + (a − L)² − t²V_aa = 0
//! ```
//!
//! When b² ≤ t²V_bb the slope is not significantly positive at that level:
//! the band never leaves L on the far side and the interval is unbounded
//! ("no trend the data can support"). Counted from the last log.

use super::fit::{LineFit, t_quantile};
use serde::{Deserialize, Serialize};

/// The crossing of the limit.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Forecast {
    pub limit_mm: f64,
    /// Interval level (e.g. 0.8).
    pub level: f64,
    /// Abscissa of the crossing (cycles or days, as the fit) and its interval
    /// (`hi` None: unbounded).
    pub at: f64,
    pub at_lo: f64,
    pub at_hi: Option<f64>,
    /// From the last log: abscissa units to the limit (point, interval).
    pub remaining: f64,
    pub remaining_lo: f64,
    pub remaining_hi: Option<f64>,
    /// The same in days when the abscissa is cycles and the cycle rate is known.
    pub days: Option<f64>,
    pub days_lo: Option<f64>,
    pub days_hi: Option<f64>,
    /// The limit is already reached by the fitted line at the last log.
    pub reached: bool,
    pub notes: Vec<String>,
}

/// Crossing of `limit_mm` by `fit`, counted from abscissa `last`, with a
/// `level` interval; `per_day` converts the abscissa to days (1 when the
/// abscissa is days). None when the fitted wear rate is not positive.
pub fn forecast(
    fit: &LineFit,
    limit_mm: f64,
    last: f64,
    level: f64,
    per_day: Option<f64>,
) -> Result<Forecast, String> {
    if !(fit.slope > 0.0) {
        return Err(format!(
            "the fitted wear rate is not positive ({:.3e} mm per unit): no crossing of {limit_mm} mm can be forecast",
            fit.slope
        ));
    }
    let (a, b) = (fit.intercept, fit.slope);
    let at = (limit_mm - a) / b;
    let t = t_quantile(0.5 + level / 2.0, fit.dof as f64);
    let t2 = t * t;
    let d = a - limit_mm;
    let qa = b * b - t2 * fit.var_slope;
    let qb = 2.0 * (d * b - t2 * fit.cov);
    let qc = d * d - t2 * fit.var_intercept;
    let mut notes = Vec::new();
    let (lo, hi) = if qa > 0.0 {
        let disc = (qb * qb - 4.0 * qa * qc).max(0.0).sqrt();
        let r1 = (-qb - disc) / (2.0 * qa);
        let r2 = (-qb + disc) / (2.0 * qa);
        (r1.min(r2), Some(r1.max(r2)))
    } else {
        notes.push(format!(
            "the wear rate is not significantly above zero at {:.0} %: the interval has no upper end",
            level * 100.0
        ));
        // The lower end: the root where the band's upper edge reaches L.
        let lo = if qa.abs() > 0.0 && qb * qb - 4.0 * qa * qc >= 0.0 {
            let disc = (qb * qb - 4.0 * qa * qc).sqrt();
            let r = [(-qb - disc) / (2.0 * qa), (-qb + disc) / (2.0 * qa)];
            r.into_iter()
                .filter(|x| *x <= at)
                .fold(f64::NEG_INFINITY, f64::max)
        } else {
            f64::NEG_INFINITY
        };
        (lo, None)
    };
    let to_days = |x: f64| per_day.map(|r| x / r);
    let remaining = at - last;
    let remaining_lo = lo - last;
    let remaining_hi = hi.map(|h| h - last);
    Ok(Forecast {
        limit_mm,
        level,
        at,
        at_lo: lo,
        at_hi: hi,
        remaining,
        remaining_lo,
        remaining_hi,
        days: to_days(remaining),
        days_lo: to_days(remaining_lo),
        days_hi: remaining_hi.and_then(to_days),
        reached: fit.at(last) >= limit_mm,
        notes,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn line(a: f64, b: f64, va: f64, vb: f64, cov: f64, dof: usize) -> LineFit {
        LineFit {
            n: dof + 2,
            intercept: a,
            slope: b,
            var_intercept: va,
            var_slope: vb,
            cov,
            dof,
            chi2: 0.0,
            chi2_red: 1.0,
            birge_scaled: false,
            r2: 1.0,
            slope_se: vb.sqrt(),
            slope_lo95: 0.0,
            slope_hi95: 0.0,
        }
    }

    /// Hand computation: a = 0.2 mm, b = 1e-6 mm/cycle, L = 0.5 → x* = 300 000.
    /// V_aa = 1e-4, V_bb = 1e-14, V_ab = 0, ν = 8, level 80 % → t(0.9, 8) = 1.3968.
    /// t² = 1.95105; qa = 1e-12 − 1.95105e-14 = 9.80490e-13;
    /// qb = 2·(−0.3·1e-6) = −6e-7; qc = 0.09 − 1.95109e-4 = 0.0898049.
    /// disc = √(3.6e-13 − 4·9.80489e-13·0.0898049) = √(3.6e-13 − 3.52211e-13)
    ///      = √7.7894e-15 = 8.8256e-8
    /// roots = (6e-7 ∓ 8.8256e-8)/(1.96098e-12) → 260 964 and 350 976
    /// (re-checked in Python with t(0.9, 8) = 1.3968153 from the t table).
    #[test]
    fn fieller_interval_matches_the_hand_computation() {
        let f = forecast(
            &line(0.2, 1e-6, 1e-4, 1e-14, 0.0, 8),
            0.5,
            100_000.0,
            0.8,
            Some(10_000.0),
        )
        .unwrap();
        assert!((f.at - 300_000.0).abs() < 1e-6);
        assert!((f.at_lo - 260_964.0).abs() < 20.0, "{f:?}");
        assert!((f.at_hi.unwrap() - 350_976.0).abs() < 20.0, "{f:?}");
        assert!((f.remaining - 200_000.0).abs() < 1e-6);
        assert!((f.days.unwrap() - 20.0).abs() < 1e-9);
        assert!(!f.reached);
    }

    #[test]
    fn an_insignificant_rate_has_no_upper_end_and_a_flat_one_no_forecast() {
        let f = forecast(&line(0.2, 1e-7, 1e-6, 1e-14, 0.0, 4), 0.5, 0.0, 0.8, None).unwrap();
        assert!(f.at_hi.is_none());
        assert!(!f.notes.is_empty());
        assert!(forecast(&line(0.2, 0.0, 1e-6, 1e-14, 0.0, 4), 0.5, 0.0, 0.8, None).is_err());
        assert!(forecast(&line(0.2, -1e-6, 1e-6, 1e-14, 0.0, 4), 0.5, 0.0, 0.8, None).is_err());
    }
}
