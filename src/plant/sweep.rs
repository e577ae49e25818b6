//! `sweep` at plant scale: the grid of the study split across machines.
//! Case `i` of the grid (in its order: clearance, then speed, then
//! material) belongs to shard `i mod n`; each shard simulates its cases
//! and hands over their summaries (and the chart cases' curves); the merge
//! puts the cases back in grid order and writes the study with the single
//! run's writer (`sweep_folder`).
//!
//! The merged study is the single run's, byte for byte
//! (`tests/plant/jobs.rs`). The wall-clock times (`wall_ms` of each case
//! and of the run), which no two runs share, stay in memory for the
//! terminal and are kept out of every file — `sweep.json`, `sweep.csv` and
//! the partial — so a re-run of a shard writes the same bytes too.

use super::partial::{Found, Header, Partial};
use crate::output::json::{NOT_REPRODUCIBLE, to_vec_pretty_without};
use crate::plot::render_png;
use crate::sim::Curves;
use crate::sim::ensemble::{FIGURES, figure};
use crate::sim::summary::Summary;
use crate::sim::sweep::{Factor, Nominal, SweepCase, SweepGrid, SweepResult};
use serde::{Deserialize, Serialize};
use std::io::Write;

/// One case as a shard hands it over.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct CaseData {
    pub index: u64,
    pub clearance_mm: f64,
    pub motor_rpm: f64,
    pub material: String,
    pub summary: Option<Summary>,
    pub error: Option<String>,
    pub curves: Option<Curves>,
}

/// A sweep shard's partial (after the [`Header`]).
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct SweepBody {
    pub preset: String,
    pub grid: SweepGrid,
    pub nominal: (f64, f64, String),
    pub method: String,
    pub rtol: f64,
    pub warmup_revs: f64,
    pub revs: f64,
    pub charts: bool,
    pub cases: Vec<CaseData>,
    pub ideal_curves: Vec<(f64, Curves)>,
}

/// The unit names of a grid's cases (their index, zero-padded: rank is
/// the index, so case `i` goes to shard `i mod n`).
pub fn case_units(grid: &SweepGrid) -> Vec<String> {
    (0..grid.len()).map(|i| format!("{i:012}")).collect()
}

/// The files of a sweep folder: `sweep.csv`, `sweep.json` and (with
/// `charts`) the PNG charts; with `shard` (its header and its cases'
/// indices in the grid), also `partial.json`.
pub fn sweep_folder(
    result: &SweepResult,
    charts: bool,
    shard: Option<(Header, &[u64])>,
) -> anyhow::Result<Vec<(String, Vec<u8>)>> {
    let mut csv = Vec::new();
    write_csv(&mut csv, result)?;
    let mut files = vec![
        ("sweep.csv".to_string(), csv),
        (
            "sweep.json".to_string(),
            to_vec_pretty_without(result, NOT_REPRODUCIBLE)?,
        ),
    ];
    if charts {
        for f in Factor::ALL {
            let png = render_png(&result.curve_panels(f), 2, 1600, 1100)?;
            files.push((format!("curves_{}.png", f.name()), png));
            let png = render_png(&result.bar_panels(f), 2, 1400, 550)?;
            files.push((format!("bars_{}.png", f.name()), png));
        }
    }
    if let Some((header, indices)) = shard {
        anyhow::ensure!(
            indices.len() == result.cases.len(),
            "a grid index for every case is needed"
        );
        let body = SweepBody {
            preset: result.preset.clone(),
            grid: result.grid.clone(),
            nominal: (
                result.nominal.clearance_mm,
                result.nominal.motor_rpm,
                result.nominal.material.clone(),
            ),
            method: result.method.clone(),
            rtol: result.rtol,
            warmup_revs: result.warmup_revs,
            revs: result.revs,
            charts,
            cases: result
                .cases
                .iter()
                .zip(indices)
                .map(|(c, &index)| CaseData {
                    index,
                    clearance_mm: c.clearance_mm,
                    motor_rpm: c.motor_rpm,
                    material: c.material.clone(),
                    // No wall-clock time in a partial (a re-run writes
                    // the same bytes): 0 in the summary it hands over.
                    summary: c.summary.clone().map(|mut s| {
                        s.wall_ms = 0.0;
                        s
                    }),
                    error: c.error.clone(),
                    curves: c.curves.clone(),
                })
                .collect(),
            ideal_curves: result.ideal_curves.clone(),
        };
        files.push((
            super::partial::PARTIAL_FILE.into(),
            serde_json::to_vec(&Partial { header, body })?,
        ));
    }
    Ok(files)
}

/// A merged sweep and its folder's files.
pub struct MergedSweep {
    pub result: SweepResult,
    pub files: Vec<(String, Vec<u8>)>,
}

/// Merges one job's sweep partials (one complete set, in shard order).
pub fn merge_sweep(set: Vec<(&Found, Partial<SweepBody>)>) -> Result<MergedSweep, String> {
    let start = std::time::Instant::now();
    let (f0, p0) = set.first().ok_or("nothing to merge")?;
    let b0 = &p0.body;
    let same = |b: &SweepBody| {
        b.preset == b0.preset
            && b.grid == b0.grid
            && b.nominal == b0.nominal
            && b.method == b0.method
            && b.rtol.to_bits() == b0.rtol.to_bits()
            && b.warmup_revs.to_bits() == b0.warmup_revs.to_bits()
            && b.revs.to_bits() == b0.revs.to_bits()
            && b.charts == b0.charts
    };
    for (f, p) in &set {
        if !same(&p.body) {
            return Err(format!(
                "{}: its study (grid, preset, method, revolutions) differs from {}'s: not shards of one job",
                f.shown, f0.shown
            ));
        }
    }
    let (grid, charts) = (b0.grid.clone(), b0.charts);
    let nominal = Nominal {
        clearance_mm: b0.nominal.0,
        motor_rpm: b0.nominal.1,
        material: b0.nominal.2.clone(),
    };
    let (preset, method, rtol, warmup_revs, revs) = (
        b0.preset.clone(),
        b0.method.clone(),
        b0.rtol,
        b0.warmup_revs,
        b0.revs,
    );
    let ideal_curves = b0.ideal_curves.clone();
    let mut cases: Vec<(u64, String, CaseData)> = Vec::new();
    for (f, p) in set {
        cases.extend(
            p.body
                .cases
                .into_iter()
                .map(|c| (c.index, f.shown.clone(), c)),
        );
    }
    cases.sort_by_key(|c| c.0);
    if let Some(w) = cases.windows(2).find(|w| w[0].0 == w[1].0) {
        return Err(format!(
            "{} and {} both hold case {} of the grid: the partials overlap",
            w[0].1, w[1].1, w[0].0
        ));
    }
    if cases.len() != grid.len() || cases.iter().enumerate().any(|(i, c)| c.0 != i as u64) {
        return Err(format!(
            "the shards hold {} of the grid's {} cases: a corrupt partial",
            cases.len(),
            grid.len()
        ));
    }
    let cases: Vec<SweepCase> = cases
        .into_iter()
        .map(|(_, _, c)| SweepCase {
            clearance_mm: c.clearance_mm,
            motor_rpm: c.motor_rpm,
            material: c.material,
            summary: c.summary,
            error: c.error,
            curves: c.curves,
        })
        .collect();
    let result = SweepResult {
        preset,
        grid,
        nominal,
        method,
        rtol,
        warmup_revs,
        revs,
        failed: cases.iter().filter(|c| c.error.is_some()).count(),
        cases,
        // The merge's own time (in no file).
        wall_ms: start.elapsed().as_secs_f64() * 1e3,
        ideal_curves,
    };
    let files = sweep_folder(&result, charts, None).map_err(|e| e.to_string())?;
    Ok(MergedSweep { result, files })
}

/// A grid value in a CSV cell: as written, but in exponent form far from 1
/// (a refused 1e-300 is not 300 zeros).
fn csv_num(x: f64) -> String {
    if x != 0.0 && !(1e-4..1e16).contains(&x.abs()) {
        format!("{x:e}")
    } else {
        format!("{x}")
    }
}

fn write_csv(f: &mut Vec<u8>, r: &SweepResult) -> anyhow::Result<()> {
    write!(f, "clearance_mm,motor_rpm,material,status")?;
    for name in FIGURES {
        write!(f, ",{name}")?;
    }
    writeln!(f, ",n_impacts,steps,rejected_steps,rhs_evals,error")?;
    for c in &r.cases {
        write!(
            f,
            "{},{},{},{}",
            csv_num(c.clearance_mm),
            csv_num(c.motor_rpm),
            c.material,
            if c.error.is_some() { "error" } else { "ok" }
        )?;
        for name in FIGURES {
            match &c.summary {
                Some(s) => {
                    let v = figure(s, name);
                    if v.is_finite() {
                        write!(f, ",{v}")?
                    } else {
                        write!(f, ",")?
                    }
                }
                None => write!(f, ",")?,
            }
        }
        match &c.summary {
            Some(s) => write!(
                f,
                ",{},{},{},{}",
                s.n_impacts, s.steps, s.rejected_steps, s.rhs_evals
            )?,
            None => write!(f, ",,,,")?,
        }
        let err = c.error.as_deref().unwrap_or("").replace(['"', '\n'], " ");
        writeln!(f, ",\"{err}\"")?;
    }
    Ok(())
}
