//! Statistical process control as a quality department reads it:
//! capability (Cp, Cpk within; Pp, Ppk overall) and control charts (X̄/R
//! for subgroups of 2–10 consecutive cycles, I-MR for individuals) with the
//! Western Electric run rules.
//!
//! σ within is estimated from the ranges (R̄/d₂, or MR̄/1.128 for
//! individuals), σ overall is the sample standard deviation of all values:
//! the conventions of AIAG's SPC manual, with its constants (d₂, A₂, D₃, D₄).

use serde::{Deserialize, Serialize};

/// d₂, A₂, D₃, D₄ for subgroup sizes 2..=10 (AIAG SPC manual, 2nd ed.).
const D2: [f64; 9] = [
    1.128, 1.693, 2.059, 2.326, 2.534, 2.704, 2.847, 2.970, 3.078,
];
const A2: [f64; 9] = [
    1.880, 1.023, 0.729, 0.577, 0.483, 0.419, 0.373, 0.337, 0.308,
];
const D3: [f64; 9] = [0.0, 0.0, 0.0, 0.0, 0.0, 0.076, 0.136, 0.184, 0.223];
/// E₂ of the individuals chart (3/d₂ for moving ranges of two, as tabulated).
const E2: f64 = 2.66;
const D4: [f64; 9] = [
    3.267, 2.574, 2.282, 2.114, 2.004, 1.924, 1.864, 1.816, 1.777,
];

/// Capability of one characteristic.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Capability {
    /// Values used (finite ones).
    pub n: usize,
    pub subgroup: usize,
    #[serde(deserialize_with = "super::serde_back::f64_nan")]
    pub mean: f64,
    #[serde(deserialize_with = "super::serde_back::f64_nan")]
    pub sigma_within: f64,
    #[serde(deserialize_with = "super::serde_back::f64_nan")]
    pub sigma_overall: f64,
    pub lsl: Option<f64>,
    pub usl: Option<f64>,
    /// None where a limit is missing (Cp, Pp need both).
    pub cp: Option<f64>,
    pub cpk: Option<f64>,
    pub pp: Option<f64>,
    pub ppk: Option<f64>,
}

/// A Western Electric rule broken at a point of a chart.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct RunAlarm {
    /// 1: beyond 3σ; 2: 2 of 3 beyond 2σ, same side; 3: 4 of 5 beyond 1σ,
    /// same side; 4: 8 in a row on one side of the centre line.
    pub rule: u8,
    /// Index of the point that completes the pattern.
    pub point: usize,
    pub text: String,
}

/// A control chart pair: location (X̄ or I) and spread (R or MR).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ControlChart {
    /// `xbar_r` or `i_mr`.
    #[serde(deserialize_with = "super::serde_back::name")]
    pub kind: super::serde_back::Name,
    pub subgroup: usize,
    /// Subgroup means (or the individual values).
    #[serde(deserialize_with = "super::serde_back::vec_nan")]
    pub points: Vec<f64>,
    #[serde(deserialize_with = "super::serde_back::f64_nan")]
    pub cl: f64,
    #[serde(deserialize_with = "super::serde_back::f64_nan")]
    pub ucl: f64,
    #[serde(deserialize_with = "super::serde_back::f64_nan")]
    pub lcl: f64,
    /// Subgroup ranges (or moving ranges; the first individual has none).
    #[serde(deserialize_with = "super::serde_back::vec_nan")]
    pub ranges: Vec<f64>,
    #[serde(deserialize_with = "super::serde_back::f64_nan")]
    pub r_cl: f64,
    #[serde(deserialize_with = "super::serde_back::f64_nan")]
    pub r_ucl: f64,
    #[serde(deserialize_with = "super::serde_back::f64_nan")]
    pub r_lcl: f64,
    /// Run-rule alarms on the location chart.
    pub alarms: Vec<RunAlarm>,
}

fn mean(v: &[f64]) -> f64 {
    v.iter().sum::<f64>() / v.len() as f64
}

fn sample_sd(v: &[f64]) -> f64 {
    if v.len() < 2 {
        return f64::NAN;
    }
    let m = mean(v);
    (v.iter().map(|x| (x - m) * (x - m)).sum::<f64>() / (v.len() - 1) as f64).sqrt()
}

fn range(v: &[f64]) -> f64 {
    let (lo, hi) = v
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &x| {
            (a.min(x), b.max(x))
        });
    hi - lo
}

/// The control chart of a series: X̄/R over consecutive subgroups of
/// `subgroup` values (an incomplete last subgroup is left out), or I-MR
/// when `subgroup` is 1. None with fewer than two points.
pub fn control_chart(values: &[f64], subgroup: usize) -> Option<ControlChart> {
    let v: Vec<f64> = values.iter().copied().filter(|x| x.is_finite()).collect();
    if subgroup <= 1 {
        if v.len() < 2 {
            return None;
        }
        let mr: Vec<f64> = v.windows(2).map(|w| (w[1] - w[0]).abs()).collect();
        let mrb = mean(&mr);
        let cl = mean(&v);
        let (ucl, lcl) = (cl + E2 * mrb, cl - E2 * mrb);
        let alarms = western_electric(&v, cl, (ucl - cl) / 3.0);
        return Some(ControlChart {
            kind: "i_mr",
            subgroup: 1,
            points: v,
            cl,
            ucl,
            lcl,
            ranges: mr,
            r_cl: mrb,
            r_ucl: D4[0] * mrb,
            r_lcl: 0.0,
            alarms,
        });
    }
    let n = subgroup.min(10);
    let groups: Vec<&[f64]> = v.chunks_exact(n).collect();
    if groups.len() < 2 {
        return None;
    }
    let points: Vec<f64> = groups.iter().map(|g| mean(g)).collect();
    let ranges: Vec<f64> = groups.iter().map(|g| range(g)).collect();
    let (cl, rb) = (mean(&points), mean(&ranges));
    let k = n - 2;
    let (ucl, lcl) = (cl + A2[k] * rb, cl - A2[k] * rb);
    let alarms = western_electric(&points, cl, (ucl - cl) / 3.0);
    Some(ControlChart {
        kind: "xbar_r",
        subgroup: n,
        points,
        cl,
        ucl,
        lcl,
        ranges,
        r_cl: rb,
        r_ucl: D4[k] * rb,
        r_lcl: D3[k] * rb,
        alarms,
    })
}

/// Capability of a series against its limits (σ within from the same
/// ranges as [`control_chart`]). None with fewer than two values.
pub fn capability(
    values: &[f64],
    subgroup: usize,
    lsl: Option<f64>,
    usl: Option<f64>,
) -> Option<Capability> {
    let v: Vec<f64> = values.iter().copied().filter(|x| x.is_finite()).collect();
    let chart = control_chart(&v, subgroup)?;
    let sigma_within = if chart.kind == "i_mr" {
        chart.r_cl / D2[0]
    } else {
        chart.r_cl / D2[chart.subgroup - 2]
    };
    let sigma_overall = sample_sd(&v);
    let m = mean(&v);
    let index = |sigma: f64| {
        let both = lsl.zip(usl).map(|(l, u)| (u - l) / (6.0 * sigma));
        let lower = lsl.map(|l| (m - l) / (3.0 * sigma));
        let upper = usl.map(|u| (u - m) / (3.0 * sigma));
        let k = match (lower, upper) {
            (Some(a), Some(b)) => Some(a.min(b)),
            (a, b) => a.or(b),
        };
        let ok = |x: Option<f64>| x.filter(|x| x.is_finite());
        (ok(both), ok(k))
    };
    let (cp, cpk) = index(sigma_within);
    let (pp, ppk) = index(sigma_overall);
    Some(Capability {
        n: v.len(),
        subgroup: chart.subgroup,
        mean: m,
        sigma_within,
        sigma_overall,
        lsl,
        usl,
        cp,
        cpk,
        pp,
        ppk,
    })
}

/// The usual reading of a Cpk.
pub fn cpk_band(cpk: f64) -> &'static str {
    if cpk >= 1.33 {
        "capable"
    } else if cpk >= 1.0 {
        "adequate"
    } else {
        "inadequate"
    }
}

/// Western Electric rules 1–4 on a chart with centre `cl` and `sigma` (of
/// the plotted points); each alarm is raised at the point that completes
/// its pattern, once per rule and point.
pub fn western_electric(points: &[f64], cl: f64, sigma: f64) -> Vec<RunAlarm> {
    let mut out = Vec::new();
    if !(sigma > 0.0) {
        return out;
    }
    let z: Vec<f64> = points.iter().map(|p| (p - cl) / sigma).collect();
    let side = |x: f64| {
        if x > 0.0 {
            1
        } else if x < 0.0 {
            -1
        } else {
            0
        }
    };
    for i in 0..z.len() {
        if z[i].abs() > 3.0 {
            out.push(RunAlarm {
                rule: 1,
                point: i,
                text: format!("point {i} beyond 3σ ({:+.2}σ)", z[i]),
            });
        }
        // k of the last m points beyond `limit` σ on one side.
        let mut k_of_m = |rule: u8, k: usize, m: usize, limit: f64| {
            if i + 1 < m {
                return;
            }
            let win = &z[i + 1 - m..=i];
            for s in [1.0, -1.0] {
                // The completing point must itself be one of the k.
                if z[i] * s <= limit {
                    continue;
                }
                if win.iter().filter(|&&x| x * s > limit).count() >= k {
                    out.push(RunAlarm {
                        rule,
                        point: i,
                        text: format!(
                            "{k} of {m} points beyond {limit}σ on the {} side, ending at point {i}",
                            if s > 0.0 { "upper" } else { "lower" }
                        ),
                    });
                }
            }
        };
        k_of_m(2, 2, 3, 2.0);
        k_of_m(3, 4, 5, 1.0);
        if i >= 7 {
            let s = side(z[i]);
            if s != 0 && z[i - 7..=i].iter().all(|&x| side(x) == s) {
                out.push(RunAlarm {
                    rule: 4,
                    point: i,
                    text: format!(
                        "8 points in a row on the {} side of the centre line, ending at point {i}",
                        if s > 0 { "upper" } else { "lower" }
                    ),
                });
            }
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Reference values computed independently with Python's `statistics`
    /// module (mean, stdev) and the AIAG constants, for
    /// x = 20.1 19.8 20.4 20.0 19.9 | 20.3 20.6 20.2 20.5 20.1 |
    ///     19.7 19.9 20.0 19.6 20.2 | 20.8 20.4 20.6 20.9 20.5,
    /// LSL 18.5, USL 22.0:
    /// subgroups of 5: means 20.04 20.34 19.88 20.64, ranges 0.6 0.5 0.6 0.5,
    /// X̄̄ 20.225, R̄ 0.55, σw = R̄/2.326 = 0.2364574377, σo = 0.3611021141,
    /// Cp 2.4669697, Cpk 2.4317273, Pp 1.6154249, Ppk 1.5923474,
    /// UCL 20.54235, LCL 19.90765, R UCL 1.1627;
    /// individuals: MR̄ 0.3578947368, I UCL 21.177, LCL 19.273,
    /// MR UCL 1.1692421, Cpk 1.8122647.
    const X: [f64; 20] = [
        20.1, 19.8, 20.4, 20.0, 19.9, 20.3, 20.6, 20.2, 20.5, 20.1, 19.7, 19.9, 20.0, 19.6, 20.2,
        20.8, 20.4, 20.6, 20.9, 20.5,
    ];

    fn close(a: f64, b: f64) {
        assert!((a - b).abs() < 1e-6, "{a} vs {b}");
    }

    #[test]
    fn xbar_r_and_capability_match_the_hand_computation() {
        let c = control_chart(&X, 5).unwrap();
        for (p, e) in c.points.iter().zip([20.04, 20.34, 19.88, 20.64]) {
            close(*p, e);
        }
        close(c.cl, 20.225);
        close(c.r_cl, 0.55);
        close(c.ucl, 20.54235);
        close(c.lcl, 19.90765);
        close(c.r_ucl, 1.1627);
        let k = capability(&X, 5, Some(18.5), Some(22.0)).unwrap();
        close(k.sigma_within, 0.2364574377);
        close(k.sigma_overall, 0.3611021141);
        close(k.cp.unwrap(), 2.4669697);
        close(k.cpk.unwrap(), 2.4317273);
        close(k.pp.unwrap(), 1.6154249);
        close(k.ppk.unwrap(), 1.5923474);
        // Subgroup 2 (19.88) is below the LCL and subgroup 3 (20.64) above the UCL.
        let beyond: Vec<usize> = c
            .alarms
            .iter()
            .filter(|a| a.rule == 1)
            .map(|a| a.point)
            .collect();
        assert_eq!(beyond, [2, 3]);
    }

    #[test]
    fn individuals_match_the_hand_computation() {
        let c = control_chart(&X, 1).unwrap();
        close(c.r_cl, 0.3578947368);
        close(c.ucl, 21.177);
        close(c.lcl, 19.273);
        close(c.r_ucl, 1.1692421);
        let k = capability(&X, 1, Some(18.5), Some(22.0)).unwrap();
        close(k.cpk.unwrap(), 1.8122647);
        // One-sided: only the upper limit.
        let k = capability(&X, 1, None, Some(22.0)).unwrap();
        assert!(k.cp.is_none());
        close(
            k.cpk.unwrap(),
            (22.0 - 20.225) / (3.0 * 0.3578947368 / 1.128),
        );
    }

    #[test]
    fn run_rules() {
        // Rule 4: eight in a row above the centre (small, inside 1σ).
        let mut p = vec![0.5; 8];
        let a = western_electric(&p, 0.0, 1.0);
        assert_eq!(
            a.iter()
                .filter(|a| a.rule == 4)
                .map(|a| a.point)
                .collect::<Vec<_>>(),
            [7]
        );
        // Rule 2: two of three beyond 2σ on one side.
        p = vec![0.0, 2.5, -0.5, 2.2];
        let a = western_electric(&p, 0.0, 1.0);
        assert!(a.iter().any(|a| a.rule == 2 && a.point == 3), "{a:?}");
        assert!(!a.iter().any(|a| a.rule == 1));
        // Rule 3: four of five beyond 1σ.
        p = vec![1.5, 1.2, 0.0, 1.1, 1.3];
        let a = western_electric(&p, 0.0, 1.0);
        assert!(a.iter().any(|a| a.rule == 3 && a.point == 4), "{a:?}");
        assert_eq!(cpk_band(1.4), "capable");
        assert_eq!(cpk_band(1.1), "adequate");
        assert_eq!(cpk_band(0.7), "inadequate");
    }
}
