//! The clearance limit, derived with the model.
//!
//! A connector is pressed to its depth at bottom dead centre (BDC, the
//! largest stroke). With clearance c the rod–pin-bar joint rattles: the
//! stroke at BDC departs from the ideal mechanism's by a mean amount and
//! varies from cycle to cycle. For each clearance of a ladder the model's
//! ensemble ([`crate::overlay::predict`], the clearance level, at the logged
//! speed with the head's calibrated parameters) gives the per-revolution
//! depth deviation d_r = s_r(φ_BDC) − s_ideal(φ_BDC). The tolerance `T` (the
//! side view's `height_tol_mm`, or a process window) is used up when
//!
//! ```text
//! |mean(d)| + 3·sd(d) ≥ T
//! ```
//!
//! (the ±3σ band of depths no longer fits inside ±T). The limit is that
//! crossing, interpolated linearly between the ladder's clearances. The
//! predicted yield at each clearance is the fraction of revolutions with
//! |d_r| ≤ T. A user's `--limit` replaces the derivation.

use crate::model::Params;
use crate::overlay::predict::{PredictOptions, predict};
use crate::progress::Progress;
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

/// The clearances (mm) the limit is searched over by default.
pub const DEFAULT_LADDER_MM: [f64; 11] = [0.05, 0.1, 0.2, 0.3, 0.4, 0.5, 0.65, 0.8, 1.0, 1.25, 1.5];

/// The predicted depth at BDC for one clearance.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct LadderPoint {
    pub clearance_mm: f64,
    /// Mean and standard deviation over revolutions of the depth deviation (mm).
    pub depth_error_mm: f64,
    pub depth_sd_mm: f64,
    /// |mean| + 3·sd (mm): what is compared with the tolerance.
    pub used_mm: f64,
    /// Fraction of simulated revolutions within ±T.
    pub predicted_yield: f64,
}

/// Where the limit came from.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum LimitSource {
    /// Given by the user (`--limit`).
    User,
    /// Derived with the model from the tolerance.
    Derived,
}

/// The clearance limit and, when derived, its curve.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ClearanceLimit {
    pub source: LimitSource,
    pub limit_mm: Option<f64>,
    pub tolerance_mm: Option<f64>,
    pub motor_rpm: Option<f64>,
    pub criterion: String,
    pub ladder: Vec<LadderPoint>,
    pub notes: Vec<String>,
}

impl ClearanceLimit {
    /// A limit the user gave.
    pub fn user(limit_mm: f64) -> Self {
        ClearanceLimit {
            source: LimitSource::User,
            limit_mm: Some(limit_mm),
            tolerance_mm: None,
            motor_rpm: None,
            criterion: "given by the user (--limit)".into(),
            ladder: Vec::new(),
            notes: Vec::new(),
        }
    }
}

/// The depth deviation statistics of one ensemble: `stroke_revs` per
/// revolution on the grid, `ideal` the ideal stroke on the same grid.
pub fn bdc_point(
    clearance_mm: f64,
    stroke_revs: &[Vec<f64>],
    ideal: &[f64],
    tol: f64,
) -> Option<LadderPoint> {
    let i = (0..ideal.len()).max_by(|&a, &b| ideal[a].total_cmp(&ideal[b]))?;
    let d: Vec<f64> = stroke_revs
        .iter()
        .filter_map(|r| r.get(i).map(|s| s - ideal[i]))
        .filter(|x| x.is_finite())
        .collect();
    if d.len() < 2 {
        return None;
    }
    let n = d.len() as f64;
    let mean = d.iter().sum::<f64>() / n;
    let sd = (d.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (n - 1.0)).sqrt();
    Some(LadderPoint {
        clearance_mm,
        depth_error_mm: mean,
        depth_sd_mm: sd,
        used_mm: mean.abs() + 3.0 * sd,
        predicted_yield: d.iter().filter(|x| x.abs() <= tol).count() as f64 / n,
    })
}

/// The first crossing of `tol` by the ladder's `used_mm` (linear between
/// clearances); None when the ladder never uses the tolerance up.
pub fn crossing(ladder: &[LadderPoint], tol: f64) -> Option<f64> {
    let k = ladder.iter().position(|p| p.used_mm >= tol)?;
    if k == 0 {
        return Some(ladder[0].clearance_mm);
    }
    let (a, b) = (ladder[k - 1], ladder[k]);
    let w = (tol - a.used_mm) / (b.used_mm - a.used_mm);
    Some(a.clearance_mm + w * (b.clearance_mm - a.clearance_mm))
}

/// Derives the limit for tolerance `tol_mm` at `motor_rpm` with `params`
/// (the head's calibrated parameters), simulating `revs` revolutions at
/// each clearance of `ladder_mm` in parallel.
pub fn derive_limit(
    params: &Params,
    motor_rpm: f64,
    tol_mm: f64,
    ladder_mm: &[f64],
    revs: usize,
) -> ClearanceLimit {
    let mut notes = Vec::new();
    let opts = PredictOptions {
        revs: revs.max(8),
        points_per_rev: 360,
        ..PredictOptions::default()
    };
    let runs: Vec<(f64, Result<LadderPoint, String>)> = ladder_mm
        .par_iter()
        .map(|&c| {
            let mut p = params.clone();
            p.clearance = c * 1e-3;
            let r = predict(&p, motor_rpm, &opts, &Progress::hidden())
                .map_err(|e| e.to_string())
                .and_then(|pr| {
                    bdc_point(c, &pr.stroke_revs, &pr.ideal_stroke_mm, tol_mm)
                        .ok_or_else(|| "fewer than 2 revolutions".to_string())
                });
            (c, r)
        })
        .collect();
    let mut ladder = Vec::new();
    for (c, r) in runs {
        match r {
            Ok(p) => ladder.push(p),
            Err(e) => notes.push(format!(
                "the model failed at clearance {c} mm ({e}); left out"
            )),
        }
    }
    ladder.sort_by(|a, b| a.clearance_mm.total_cmp(&b.clearance_mm));
    let limit_mm = crossing(&ladder, tol_mm);
    match (limit_mm, ladder.first(), ladder.last()) {
        (None, _, Some(last)) => notes.push(format!(
            "the tolerance ±{tol_mm} mm is not used up up to {} mm of clearance: no limit within the ladder",
            last.clearance_mm
        )),
        (Some(_), Some(first), _) if first.used_mm >= tol_mm => notes.push(format!(
            "the tolerance ±{tol_mm} mm is already used up at the smallest clearance simulated ({} mm)",
            first.clearance_mm
        )),
        _ => {}
    }
    ClearanceLimit {
        source: LimitSource::Derived,
        limit_mm,
        tolerance_mm: Some(tol_mm),
        motor_rpm: Some(motor_rpm),
        criterion: format!(
            "|mean depth error at BDC| + 3·sd over {} simulated revolutions ≥ ±{tol_mm} mm, at {motor_rpm:.0} rpm",
            opts.revs
        ),
        ladder,
        notes,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bdc_statistics_and_the_crossing_by_hand() {
        // ideal peaks at index 1 (10.0); deviations there: 0.01, 0.03, 0.02
        // → mean 0.02, sd 0.01, used 0.05; within ±0.025: 2 of 3.
        let ideal = [9.0, 10.0, 9.5];
        let revs = vec![
            vec![9.0, 10.01, 9.5],
            vec![9.0, 10.03, 9.5],
            vec![9.0, 10.02, 9.5],
        ];
        let p = bdc_point(0.3, &revs, &ideal, 0.025).unwrap();
        assert!((p.depth_error_mm - 0.02).abs() < 1e-12);
        assert!((p.depth_sd_mm - 0.01).abs() < 1e-12);
        assert!((p.used_mm - 0.05).abs() < 1e-12);
        assert!((p.predicted_yield - 2.0 / 3.0).abs() < 1e-12);
        // used 0.02 at 0.2 mm, 0.06 at 0.4 mm: 0.05 is crossed at 0.2 + 0.75·0.2 = 0.35.
        let mk = |c: f64, u: f64| LadderPoint {
            clearance_mm: c,
            depth_error_mm: u,
            depth_sd_mm: 0.0,
            used_mm: u,
            predicted_yield: 1.0,
        };
        let l = [mk(0.1, 0.01), mk(0.2, 0.02), mk(0.4, 0.06)];
        assert!((crossing(&l, 0.05).unwrap() - 0.35).abs() < 1e-12);
        assert!(crossing(&l, 0.1).is_none());
        assert_eq!(crossing(&l, 0.005), Some(0.1));
    }
}
