//! The paper's parameter study: clearance × motor speed × material.
//!
//! Every case runs the same protocol (default: 2 warm-up + 3 reported
//! revolutions at the clearance level) in parallel with rayon; a case that
//! fails is recorded with its error and the others go on. The charts follow
//! the paper: for each factor, the curves of the last reported revolution
//! (stroke, speed, acceleration, drive torque against crank angle) at each
//! level of that factor with the other two at their nominal values, beside
//! the ideal curve; and bar charts of the mean displacement and speed
//! deviations per level of each factor. Each case is one realisation of a
//! chaotic motion (model.md): the mean deviations are the robust figures.

use super::{Curves, Level, SimOptions, Summary, simulate};
use crate::model::materials::Material;
use crate::model::params::Params;
use crate::plot::{BarChart, LineChart, Panel, Series, SeriesStyle};
use crate::progress::Progress;
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

/// The grid of the study.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SweepGrid {
    pub clearances_mm: Vec<f64>,
    pub speeds_rpm: Vec<f64>,
    pub materials: Vec<String>,
}

impl Default for SweepGrid {
    /// The paper's study: 4 clearances × 5 speeds × 5 materials (the ideal
    /// joint, c = 0, is the reference curve of every chart).
    fn default() -> Self {
        Self {
            clearances_mm: vec![0.1, 0.3, 0.5, 0.8],
            speeds_rpm: vec![1000.0, 1200.0, 1500.0, 1800.0, 2000.0],
            materials: Material::names().iter().map(|s| s.to_string()).collect(),
        }
    }
}

impl SweepGrid {
    /// Reads a grid file: `clearances_mm = [..]`, `speeds_rpm = [..]`,
    /// `materials = [..]`; a missing key keeps the default list.
    pub fn from_toml_str(text: &str) -> Result<Self, String> {
        let t: toml::Table = text.parse().map_err(|e: toml::de::Error| e.to_string())?;
        let mut g = Self::default();
        for (k, v) in &t {
            let nums = |v: &toml::Value| -> Result<Vec<f64>, String> {
                v.as_array()
                    .ok_or_else(|| format!("`{k}` must be an array"))?
                    .iter()
                    .map(|x| {
                        x.as_float()
                            .or_else(|| x.as_integer().map(|i| i as f64))
                            .ok_or_else(|| format!("`{k}`: {x} is not a number"))
                    })
                    .collect()
            };
            match k.as_str() {
                "clearances_mm" => g.clearances_mm = nums(v)?,
                "speeds_rpm" | "motor_rpm" => g.speeds_rpm = nums(v)?,
                "materials" => {
                    g.materials = v
                        .as_array()
                        .ok_or("`materials` must be an array")?
                        .iter()
                        .map(|x| {
                            x.as_str()
                                .map(str::to_string)
                                .ok_or(format!("`materials`: {x} is not a string"))
                        })
                        .collect::<Result<_, _>>()?
                }
                other => {
                    return Err(format!(
                        "unknown key `{other}` (allowed: clearances_mm, speeds_rpm, materials)"
                    ));
                }
            }
        }
        g.validate()?;
        Ok(g)
    }

    pub fn validate(&self) -> Result<(), String> {
        if self.clearances_mm.is_empty() || self.speeds_rpm.is_empty() || self.materials.is_empty()
        {
            return Err("every factor needs at least one level".into());
        }
        // The grid refuses only levels that are not a quantity at all; a
        // level outside a parameter's physical range is run as its own case,
        // which fails in validation and is recorded with the reason while
        // the other cases are written (the sweep's per-case promise).
        use crate::fmt::fmt_num;
        for &c in &self.clearances_mm {
            if !(c >= 0.0) || !c.is_finite() {
                return Err(format!("clearance {} mm: allowed ≥ 0", fmt_num(c)));
            }
        }
        for &s in &self.speeds_rpm {
            if !(s > 0.0) || !s.is_finite() {
                return Err(format!("speed {} rpm: allowed > 0", fmt_num(s)));
            }
        }
        for m in &self.materials {
            if Material::by_name(m).is_none() {
                return Err(format!(
                    "unknown material `{m}` (allowed: {})",
                    Material::names().join(", ")
                ));
            }
        }
        Ok(())
    }

    pub fn len(&self) -> usize {
        self.clearances_mm.len() * self.speeds_rpm.len() * self.materials.len()
    }

    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }
}

/// One case of the study.
#[derive(Debug, Clone, Serialize)]
pub struct SweepCase {
    pub clearance_mm: f64,
    pub motor_rpm: f64,
    pub material: String,
    pub summary: Option<Summary>,
    pub error: Option<String>,
    /// The last reported revolution on a 1° grid (kept for the chart cases only).
    #[serde(skip)]
    pub curves: Option<Curves>,
}

/// The nominal levels: the base parameters' values when they are in the
/// grid, else each factor's first level.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Nominal {
    pub clearance_mm: f64,
    pub motor_rpm: f64,
    pub material: String,
}

#[derive(Debug, Clone, Serialize)]
pub struct SweepResult {
    pub preset: String,
    pub grid: SweepGrid,
    pub nominal: Nominal,
    pub method: String,
    pub rtol: f64,
    pub warmup_revs: f64,
    pub revs: f64,
    pub cases: Vec<SweepCase>,
    pub failed: usize,
    pub wall_ms: f64,
    /// The ideal mechanism's last revolution at each speed (chart reference).
    #[serde(skip)]
    pub ideal_curves: Vec<(f64, Curves)>,
}

fn close(a: f64, b: f64) -> bool {
    (a - b).abs() <= 1e-9 * a.abs().max(b.abs()).max(1e-12)
}

/// Keeps the last revolution of curves sampled at 1° (361 points → 360 + end).
fn last_rev(c: Curves) -> Curves {
    let n = c.len();
    if n <= 361 {
        return c;
    }
    let start = n - 361;
    let cut = |v: &Vec<f64>| v[start..].to_vec();
    Curves {
        t_s: cut(&c.t_s),
        crank_deg: cut(&c.crank_deg),
        stroke_mm: cut(&c.stroke_mm),
        vel_mps: cut(&c.vel_mps),
        acc_mps2: cut(&c.acc_mps2),
        torque_nm: cut(&c.torque_nm),
        contact_force_n: cut(&c.contact_force_n),
        ecc_x_mm: cut(&c.ecc_x_mm),
        ecc_y_mm: cut(&c.ecc_y_mm),
        ideal_stroke_mm: cut(&c.ideal_stroke_mm),
        ideal_vel_mps: cut(&c.ideal_vel_mps),
        ideal_acc_mps2: cut(&c.ideal_acc_mps2),
        ideal_torque_nm: cut(&c.ideal_torque_nm),
        process_force_n: cut(&c.process_force_n),
        slip_mps: c
            .slip_mps
            .get(start..)
            .map(<[f64]>::to_vec)
            .unwrap_or_default(),
    }
}

/// Runs the study in parallel. `progress` counts finished cases.
pub fn run_sweep(
    base: &Params,
    grid: &SweepGrid,
    opts: &SimOptions,
    progress: &Progress,
) -> SweepResult {
    run_sweep_cases(base, grid, opts, &|_| true, progress)
}

/// [`run_sweep`] over the cases `keep` accepts (by their index in the
/// grid's order: clearance, then speed, then material): one shard of a
/// sweep split across machines (`--shard`, `plant::sweep`).
pub fn run_sweep_cases(
    base: &Params,
    grid: &SweepGrid,
    opts: &SimOptions,
    keep: &(dyn Fn(usize) -> bool + Sync),
    progress: &Progress,
) -> SweepResult {
    let start = std::time::Instant::now();
    let nominal = Nominal {
        clearance_mm: grid
            .clearances_mm
            .iter()
            .copied()
            .find(|&c| close(c, base.clearance * 1e3))
            .unwrap_or(grid.clearances_mm[0]),
        motor_rpm: grid
            .speeds_rpm
            .iter()
            .copied()
            .find(|&s| close(s, base.motor_rpm))
            .unwrap_or(grid.speeds_rpm[0]),
        material: grid
            .materials
            .iter()
            .find(|m| **m == base.material_name())
            .cloned()
            .unwrap_or_else(|| grid.materials[0].clone()),
    };
    let mut jobs = Vec::with_capacity(grid.len());
    for &c in &grid.clearances_mm {
        for &s in &grid.speeds_rpm {
            for m in &grid.materials {
                jobs.push((c, s, m.clone()));
            }
        }
    }
    let jobs: Vec<_> = jobs
        .into_iter()
        .enumerate()
        .filter(|(i, _)| keep(*i))
        .map(|(_, j)| j)
        .collect();
    progress.set_total(jobs.len() as u64);
    progress.set_done(0);
    let on_chart_line = |c: f64, s: f64, m: &str| {
        let nc = close(c, nominal.clearance_mm);
        let ns = close(s, nominal.motor_rpm);
        let nm = m == nominal.material;
        // On a chart line when at least two of the three factors are nominal.
        u8::from(nc) + u8::from(ns) + u8::from(nm) >= 2
    };
    let cases: Vec<SweepCase> = jobs
        .par_iter()
        .map(|(c, s, m)| {
            let mut case = SweepCase {
                clearance_mm: *c,
                motor_rpm: *s,
                material: m.clone(),
                summary: None,
                error: None,
                curves: None,
            };
            if progress.is_cancelled() {
                case.error = Some("cancelled".into());
                return case;
            }
            let mut p = base.clone();
            let set = p
                .set_str("clearance_mm", &c.to_string())
                .and_then(|_| p.set_str("motor_rpm", &s.to_string()))
                .and_then(|_| p.set_str("material", m))
                .and_then(|_| p.validate());
            if let Err(e) = set {
                case.error = Some(e.to_string());
                progress.inc(1);
                return case;
            }
            let o = SimOptions {
                level: Level::Clearance,
                grid_deg: on_chart_line(*c, *s, m).then_some(1.0),
                record_events: false,
                ..opts.clone()
            };
            match simulate(&p, &o, &Progress::hidden()) {
                Ok(r) => {
                    case.summary = Some(r.summary);
                    case.curves = r.curves.map(last_rev);
                }
                Err(e) => case.error = Some(e.to_string()),
            }
            progress.inc(1);
            case
        })
        .collect();
    let ideal_curves = grid
        .speeds_rpm
        .iter()
        .filter_map(|&s| {
            let mut p = base.clone();
            p.motor_rpm = s;
            let o = SimOptions {
                level: Level::Ideal,
                grid_deg: Some(1.0),
                ..opts.clone()
            };
            simulate(&p, &o, &Progress::hidden())
                .ok()
                .and_then(|r| r.curves.map(|c| (s, last_rev(c))))
        })
        .collect();
    let failed = cases.iter().filter(|c| c.error.is_some()).count();
    SweepResult {
        preset: base.preset.clone(),
        grid: grid.clone(),
        nominal,
        method: opts.method.name().into(),
        rtol: opts.rtol,
        warmup_revs: opts.warmup,
        revs: opts.revs,
        cases,
        failed,
        wall_ms: start.elapsed().as_secs_f64() * 1e3,
        ideal_curves,
    }
}

/// The factor a chart varies.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Factor {
    Clearance,
    Speed,
    Material,
}

impl Factor {
    pub const ALL: [Factor; 3] = [Factor::Clearance, Factor::Speed, Factor::Material];
    pub fn name(self) -> &'static str {
        match self {
            Factor::Clearance => "clearance",
            Factor::Speed => "speed",
            Factor::Material => "material",
        }
    }
}

/// Picks a column of the curves.
type Column = fn(&Curves) -> &Vec<f64>;

impl SweepResult {
    /// The cases on one factor's line through the nominal point, in grid order.
    pub fn line(&self, f: Factor) -> Vec<&SweepCase> {
        let n = &self.nominal;
        self.cases
            .iter()
            .filter(|c| match f {
                Factor::Clearance => close(c.motor_rpm, n.motor_rpm) && c.material == n.material,
                Factor::Speed => close(c.clearance_mm, n.clearance_mm) && c.material == n.material,
                Factor::Material => {
                    close(c.clearance_mm, n.clearance_mm) && close(c.motor_rpm, n.motor_rpm)
                }
            })
            .collect()
    }

    fn label(f: Factor, c: &SweepCase) -> String {
        match f {
            Factor::Clearance => format!("c = {} mm", crate::fmt::plain(c.clearance_mm)),
            Factor::Speed => format!("{} rpm", crate::fmt::plain(c.motor_rpm)),
            Factor::Material => c.material.clone(),
        }
    }

    /// Four panels (stroke, speed, acceleration, torque against crank angle)
    /// for the cases along one factor, each beside the ideal curve.
    pub fn curve_panels(&self, f: Factor) -> Vec<Panel> {
        let line = self.line(f);
        let cols: [(&str, &str, Column, Column); 4] = [
            (
                "stroke",
                "stroke (mm)",
                |c| &c.stroke_mm,
                |c| &c.ideal_stroke_mm,
            ),
            (
                "pin bar speed",
                "speed (m/s)",
                |c| &c.vel_mps,
                |c| &c.ideal_vel_mps,
            ),
            (
                "pin bar acceleration",
                "acceleration (m/s²)",
                |c| &c.acc_mps2,
                |c| &c.ideal_acc_mps2,
            ),
            (
                "drive torque",
                "M12 (N·m)",
                |c| &c.torque_nm,
                |c| &c.ideal_torque_nm,
            ),
        ];
        cols.iter()
            .map(|(title, ylab, get, ideal)| {
                let mut series = Vec::new();
                // Ideal reference(s): one per speed on the speed chart, else the nominal speed.
                for (s, ic) in &self.ideal_curves {
                    if f == Factor::Speed || close(*s, self.nominal.motor_rpm) {
                        let pts = split_wrap(&ic.crank_deg, ideal(ic));
                        let label = if f == Factor::Speed {
                            format!("ideal {s} rpm")
                        } else {
                            "ideal".into()
                        };
                        series.push(
                            Series::line(label, pts)
                                .with_style(SeriesStyle::Dashed)
                                .with_color(8),
                        );
                    }
                }
                for (i, c) in line.iter().enumerate() {
                    if let Some(cv) = &c.curves {
                        let pts = split_wrap(&cv.crank_deg, get(cv));
                        series.push(Series::line(Self::label(f, c), pts).with_color(i));
                    }
                }
                Panel::Line(LineChart {
                    title: format!("{title} — by {}", f.name()),
                    x_label: "crank angle θ2 (°)".into(),
                    y_label: (*ylab).into(),
                    series,
                    x_range: Some((0.0, 360.0)),
                    ..Default::default()
                })
            })
            .collect()
    }

    /// Bars of the mean displacement and speed deviations along one factor.
    pub fn bar_panels(&self, f: Factor) -> Vec<Panel> {
        let line = self.line(f);
        let cats: Vec<String> = line.iter().map(|c| Self::label(f, c)).collect();
        let get = |g: fn(&Summary) -> f64| -> Vec<f64> {
            line.iter()
                .map(|c| c.summary.as_ref().map(g).unwrap_or(f64::NAN))
                .collect()
        };
        vec![
            Panel::Bar(BarChart {
                title: format!("mean displacement deviation — by {}", f.name()),
                x_label: f.name().into(),
                y_label: "mean |s − s_ideal| (mm)".into(),
                categories: cats.clone(),
                series: vec![("mean |Δs|".into(), get(|s| s.disp_dev_mean_mm))],
                errors: None,
            }),
            Panel::Bar(BarChart {
                title: format!("mean speed deviation — by {}", f.name()),
                x_label: f.name().into(),
                y_label: "mean |v − v_ideal| (m/s)".into(),
                categories: cats,
                series: vec![("mean |Δv|".into(), get(|s| s.vel_dev_mean_mps))],
                errors: None,
            }),
        ]
    }
}

/// Points of a curve against a wrapped angle, with a NaN break where the
/// angle wraps from 360° to 0° (so no line is drawn across the chart).
fn split_wrap(x: &[f64], y: &[f64]) -> Vec<(f64, f64)> {
    let mut out = Vec::with_capacity(x.len() + 2);
    for i in 0..x.len().min(y.len()) {
        if i > 0 && x[i] < x[i - 1] {
            out.push((f64::NAN, f64::NAN));
        }
        out.push((x[i], y[i]));
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn grid_file_and_validation() {
        let g = SweepGrid::from_toml_str("clearances_mm = [0.1, 0.2]\nmaterials = [\"copper\"]")
            .unwrap();
        assert_eq!(g.clearances_mm, vec![0.1, 0.2]);
        assert_eq!(g.speeds_rpm.len(), 5);
        assert_eq!(g.len(), 10);
        assert!(
            SweepGrid::from_toml_str("materials = [\"gold\"]")
                .unwrap_err()
                .contains("gold")
        );
        assert!(SweepGrid::from_toml_str("speeds_rpm = [-5]").is_err());
        assert!(
            SweepGrid::from_toml_str("colour = 1")
                .unwrap_err()
                .contains("colour")
        );
        assert_eq!(SweepGrid::default().len(), 100);
    }

    #[test]
    fn small_sweep_runs_in_parallel_and_keeps_chart_curves() {
        let grid = SweepGrid {
            clearances_mm: vec![0.1, 0.3],
            speeds_rpm: vec![1200.0, 1800.0],
            materials: vec!["alloy_steel".into(), "aluminium".into()],
        };
        let opts = SimOptions {
            warmup: 1.0,
            revs: 1.0,
            ..SimOptions::default()
        };
        let r = run_sweep(&Params::paper(), &grid, &opts, &Progress::hidden());
        assert_eq!(r.cases.len(), 8);
        assert_eq!(r.failed, 0);
        assert_eq!(r.nominal.clearance_mm, 0.1);
        for f in Factor::ALL {
            let line = r.line(f);
            assert_eq!(line.len(), 2, "{f:?}");
            assert!(
                line.iter()
                    .all(|c| c.curves.as_ref().is_some_and(|cv| cv.len() == 361))
            );
            assert_eq!(r.curve_panels(f).len(), 4);
            assert_eq!(r.bar_panels(f).len(), 2);
        }
        // Larger clearance, larger mean displacement deviation (at the nominal speed and material).
        let line = r.line(Factor::Clearance);
        let d: Vec<f64> = line
            .iter()
            .map(|c| c.summary.as_ref().unwrap().disp_dev_mean_mm)
            .collect();
        assert!(d[1] > d[0], "{d:?}");
    }
}
