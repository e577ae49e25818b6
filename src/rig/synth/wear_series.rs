//! A wear series: N logs of one head over weeks whose true clearance grows
//! by a known law, c(n) = c₀ + rate·n in the head's cumulative cycles n
//! (rate 0: a head that does not wear), or any law the caller tabulates
//! (`clearance_table`, e.g. an Archard law it computed with the model). Each log carries the head's cycle
//! counter at its start in the `rig` metadata (`head_cycles`), starts
//! `days_between` days after the previous one and is a clearance-model
//! truth seen through the default sensors. The metadata clearance is the
//! first log's (what a technician would have written), never the truth.

use super::{ModelTruth, SynthConfig, WriteSettings, generate, write};
use crate::model::Params;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

/// The series to write.
#[derive(Debug, Clone, serde::Serialize)]
pub struct WearSeries {
    pub rig_id: String,
    pub logs: usize,
    /// Clearance (mm) at head cycle 0 and its growth (mm per cycle).
    pub c0_mm: f64,
    pub rate_mm_per_cycle: f64,
    /// Head cycles between the starts of consecutive logs, and the days between them.
    pub cycles_between: f64,
    pub days_between: f64,
    /// The first log's start (ns since the Unix epoch).
    pub start_ns: u64,
    /// Cycles in each log and the motor speed.
    pub cycles_per_log: usize,
    pub motor_rpm: f64,
    pub seed: u64,
    /// When not empty: the true clearance (mm) at head cycle n, linear
    /// between these (head cycles, mm) points, instead of c₀ + rate·n.
    pub clearance_table: Vec<(f64, f64)>,
}

impl Default for WearSeries {
    fn default() -> Self {
        WearSeries {
            rig_id: "head-A".into(),
            logs: 10,
            c0_mm: 0.15,
            rate_mm_per_cycle: 2.5e-7,
            cycles_between: 200_000.0,
            days_between: 7.0,
            start_ns: 1_790_000_000_000_000_000,
            cycles_per_log: 12,
            motor_rpm: 1200.0,
            seed: 1,
            clearance_table: Vec::new(),
        }
    }
}

/// One log of the series and its truth.
#[derive(Debug, Clone, serde::Serialize)]
pub struct SeriesLog {
    pub path: PathBuf,
    pub head_cycles: f64,
    pub start_ns: u64,
    pub clearance_mm: f64,
}

impl WearSeries {
    /// The true clearance at head cycle n.
    pub fn clearance_at(&self, n: f64) -> f64 {
        let t = &self.clearance_table;
        if t.is_empty() {
            return self.c0_mm + self.rate_mm_per_cycle * n;
        }
        let i = t.partition_point(|p| p.0 < n).clamp(1, t.len().max(2) - 1);
        if t.len() == 1 {
            return t[0].1;
        }
        let (a, b) = (t[i - 1], t[i]);
        a.1 + (n - a.0) / (b.0 - a.0) * (b.1 - a.1)
    }

    /// Writes the logs into `dir` as `<rig_id>-NN.mcap`.
    pub fn write(&self, dir: &Path) -> Result<Vec<SeriesLog>, String> {
        let mut out = Vec::new();
        for i in 0..self.logs {
            let n = i as f64 * self.cycles_between;
            let c = self.clearance_at(n);
            let start_ns = self.start_ns + (i as f64 * self.days_between * 86_400e9) as u64;
            let mut meta = BTreeMap::new();
            meta.insert("rig_id".to_string(), self.rig_id.clone());
            meta.insert("clearance_mm".to_string(), format!("{}", self.c0_mm));
            meta.insert("material".to_string(), "alloy_steel".to_string());
            meta.insert("motor_rpm".to_string(), format!("{}", self.motor_rpm));
            meta.insert("gear_ratio".to_string(), "1".to_string());
            meta.insert("standoff_mm".to_string(), "14.0".to_string());
            meta.insert("head_cycles".to_string(), format!("{n:.0}"));
            let seed = self.seed.wrapping_mul(1000).wrapping_add(i as u64);
            let cfg = SynthConfig {
                start_ns,
                motor_rpm: self.motor_rpm,
                revolutions: self.cycles_per_log as f64 + 1.4,
                metadata: Some(meta),
                seed,
                ..SynthConfig::default()
            };
            let mut p = Params::paper();
            p.clearance = c * 1e-3;
            p.motor_rpm = self.motor_rpm;
            // Another realisation of the chaotic motion per log.
            let perturb = ((seed % 17) as f64 / 8.0 - 1.0) * 1e-6;
            let truth = ModelTruth::simulate_perturbed(&p, &cfg, 3.0, 0.1, 1e-8, perturb)
                .map_err(|e| format!("log {i}: truth simulation failed: {e}"))?;
            let log = generate(&cfg, &truth);
            let path = dir.join(format!("{}-{i:02}.mcap", self.rig_id));
            let mut bytes = std::io::Cursor::new(Vec::new());
            write(&log, &mut bytes, &WriteSettings::default())
                .map_err(|e| format!("{}: {e}", path.display()))?;
            crate::output::write_file(&path, &bytes.into_inner()).map_err(|e| e.to_string())?;
            out.push(SeriesLog {
                path,
                head_cycles: n,
                start_ns,
                clearance_mm: c,
            });
        }
        Ok(out)
    }
}
