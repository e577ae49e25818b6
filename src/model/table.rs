//! Piecewise-linear tables (process load F_ins / F_wd against insertion depth).

use serde::{Deserialize, Serialize};

/// A piecewise-linear function of depth, given as points (depth in m, force in N)
/// with strictly increasing depths. Before the first point the table holds the
/// first value, beyond the last point it holds the last value (model.md). An
/// empty table is zero everywhere.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, Default)]
pub struct Table {
    /// (depth m, force N), depths strictly increasing.
    pub points: Vec<(f64, f64)>,
}

impl Table {
    pub fn zero() -> Self {
        Self { points: Vec::new() }
    }

    /// Builds a table from (depth mm, force N) pairs, checking that depths are
    /// finite, ≥ 0 and strictly increasing and forces finite and ≥ 0.
    pub fn from_mm(points_mm: &[(f64, f64)]) -> Result<Self, String> {
        let mut pts = Vec::with_capacity(points_mm.len());
        for (i, &(d, f)) in points_mm.iter().enumerate() {
            if !d.is_finite() || !f.is_finite() {
                return Err(format!("point {i} ({d}, {f}) is not finite"));
            }
            if d < 0.0 {
                return Err(format!("point {i}: depth {d} mm is negative"));
            }
            if f < 0.0 {
                return Err(format!("point {i}: force {f} N is negative"));
            }
            if let Some(&(prev, _)) = pts.last()
                && d * 1e-3 <= prev
            {
                return Err(format!(
                    "depths must increase strictly: point {i} at {d} mm follows {} mm",
                    prev * 1e3
                ));
            }
            pts.push((d * 1e-3, f));
        }
        Ok(Self { points: pts })
    }

    /// The table as (depth mm, force N) pairs.
    pub fn to_mm(&self) -> Vec<(f64, f64)> {
        self.points.iter().map(|&(d, f)| (d * 1e3, f)).collect()
    }

    pub fn is_zero(&self) -> bool {
        self.points.iter().all(|p| p.1 == 0.0)
    }

    /// Value at depth `d` (m).
    #[inline]
    pub fn eval(&self, d: f64) -> f64 {
        let p = &self.points;
        match p.len() {
            0 => 0.0,
            1 => p[0].1,
            n => {
                if d <= p[0].0 {
                    return p[0].1;
                }
                if d >= p[n - 1].0 {
                    return p[n - 1].1;
                }
                // Tables are short (a handful of points): linear scan.
                let mut i = 1;
                while p[i].0 < d {
                    i += 1;
                }
                let (d0, f0) = p[i - 1];
                let (d1, f1) = p[i];
                f0 + (f1 - f0) * (d - d0) / (d1 - d0)
            }
        }
    }

    /// The largest value in the table.
    pub fn max_value(&self) -> f64 {
        self.points.iter().map(|p| p.1).fold(0.0, f64::max)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn interpolates_and_holds_ends() {
        let t = Table::from_mm(&[(0.0, 0.0), (0.2, 8.0), (0.5, 21.0), (2.0, 23.0)]).unwrap();
        assert_eq!(t.eval(-1.0), 0.0);
        assert!((t.eval(0.1e-3) - 4.0).abs() < 1e-12);
        assert!((t.eval(0.35e-3) - 14.5).abs() < 1e-12);
        assert_eq!(t.eval(5e-3), 23.0);
        assert_eq!(t.max_value(), 23.0);
        assert_eq!(Table::zero().eval(1.0), 0.0);
    }

    #[test]
    fn rejects_non_monotone_and_negative() {
        assert!(Table::from_mm(&[(0.0, 0.0), (0.0, 1.0)]).is_err());
        assert!(Table::from_mm(&[(0.5, 0.0), (0.2, 1.0)]).is_err());
        assert!(Table::from_mm(&[(-0.1, 0.0)]).is_err());
        assert!(Table::from_mm(&[(0.1, -3.0)]).is_err());
        assert!(Table::from_mm(&[(f64::NAN, 0.0)]).is_err());
    }
}
