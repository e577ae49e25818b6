//! Output curves on a crank-angle grid (the `--csv` columns).

use crate::model::clearance::Outputs;
use serde::{Deserialize, Serialize};
use std::io::Write;

/// Curves sampled on a uniform crank-angle grid over the reported window.
/// `crank_deg` is θ2 in the model frame wrapped to [0, 360) (top dead centre
/// at 180° for zero offset); `process_force_n` is the predicted load-cell
/// force (+ = pin pushed into the part), i.e. minus the process force on the
/// pin bar.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct Curves {
    #[serde(deserialize_with = "nan_vec")]
    pub t_s: Vec<f64>,
    #[serde(deserialize_with = "nan_vec")]
    pub crank_deg: Vec<f64>,
    #[serde(deserialize_with = "nan_vec")]
    pub stroke_mm: Vec<f64>,
    #[serde(deserialize_with = "nan_vec")]
    pub vel_mps: Vec<f64>,
    #[serde(deserialize_with = "nan_vec")]
    pub acc_mps2: Vec<f64>,
    #[serde(deserialize_with = "nan_vec")]
    pub torque_nm: Vec<f64>,
    #[serde(deserialize_with = "nan_vec")]
    pub contact_force_n: Vec<f64>,
    #[serde(deserialize_with = "nan_vec")]
    pub ecc_x_mm: Vec<f64>,
    #[serde(deserialize_with = "nan_vec")]
    pub ecc_y_mm: Vec<f64>,
    #[serde(deserialize_with = "nan_vec")]
    pub ideal_stroke_mm: Vec<f64>,
    #[serde(deserialize_with = "nan_vec")]
    pub ideal_vel_mps: Vec<f64>,
    #[serde(deserialize_with = "nan_vec")]
    pub ideal_acc_mps2: Vec<f64>,
    #[serde(deserialize_with = "nan_vec")]
    pub ideal_torque_nm: Vec<f64>,
    #[serde(deserialize_with = "nan_vec")]
    pub process_force_n: Vec<f64>,
    /// Tangential slip speed at the clearance joint's contact point (m/s;
    /// NaN at the deterministic levels). Not a CSV column: the Archard wear
    /// model (`wear::archard`) integrates contact_force_n·|slip_mps|.
    #[serde(default, deserialize_with = "nan_vec")]
    pub slip_mps: Vec<f64>,
}

/// A curve read back from JSON (a sweep shard's partial): JSON has no NaN,
/// so serde_json writes the NaN of a quantity not computed (the forces at
/// the kinematic level, the slip away from contact) as `null`; it reads
/// back as NaN, so the merged study is the single run's.
fn nan_vec<'de, D: serde::Deserializer<'de>>(d: D) -> Result<Vec<f64>, D::Error> {
    Ok(Vec::<Option<f64>>::deserialize(d)?
        .into_iter()
        .map(|v| v.unwrap_or(f64::NAN))
        .collect())
}

/// Column names in CSV order.
pub const COLUMNS: [&str; 14] = [
    "t_s",
    "crank_deg",
    "stroke_mm",
    "vel_mps",
    "acc_mps2",
    "torque_nm",
    "contact_force_n",
    "ecc_x_mm",
    "ecc_y_mm",
    "ideal_stroke_mm",
    "ideal_vel_mps",
    "ideal_acc_mps2",
    "ideal_torque_nm",
    "process_force_n",
];

impl Curves {
    pub fn with_capacity(n: usize) -> Self {
        let v = || Vec::with_capacity(n);
        Self {
            t_s: v(),
            crank_deg: v(),
            stroke_mm: v(),
            vel_mps: v(),
            acc_mps2: v(),
            torque_nm: v(),
            contact_force_n: v(),
            ecc_x_mm: v(),
            ecc_y_mm: v(),
            ideal_stroke_mm: v(),
            ideal_vel_mps: v(),
            ideal_acc_mps2: v(),
            ideal_torque_nm: v(),
            process_force_n: v(),
            slip_mps: v(),
        }
    }

    pub fn len(&self) -> usize {
        self.t_s.len()
    }

    pub fn is_empty(&self) -> bool {
        self.t_s.is_empty()
    }

    /// Appends one sample. `forces` is false at the kinematic level (torque
    /// and forces are then NaN, written as empty CSV fields).
    pub fn push(&mut self, o: &Outputs, forces: bool) {
        let nan_unless = |x: f64| if forces { x } else { f64::NAN };
        self.t_s.push(o.t);
        self.crank_deg.push(super::wrap_deg(o.theta2));
        self.stroke_mm.push(o.s * 1e3);
        self.vel_mps.push(o.v4);
        self.acc_mps2.push(o.a4);
        self.torque_nm.push(nan_unless(o.m12));
        self.contact_force_n.push(nan_unless(o.f_n));
        self.ecc_x_mm.push(o.ecc[0] * 1e3);
        self.ecc_y_mm.push(o.ecc[1] * 1e3);
        self.ideal_stroke_mm.push(o.ideal_s * 1e3);
        self.ideal_vel_mps.push(o.ideal_v);
        self.ideal_acc_mps2.push(o.ideal_a);
        self.ideal_torque_nm.push(nan_unless(o.ideal_m12));
        self.process_force_n.push(nan_unless(-o.process_force));
        self.slip_mps.push(nan_unless(o.v_slip));
    }

    /// One grid point of a lean run ([`super::SimOptions::lean_curves`]):
    /// the stroke and the process force only, as [`Curves::push`] writes
    /// them (s in m, the force on the bar in N).
    pub fn push_lean(&mut self, s: f64, process_force: f64) {
        self.stroke_mm.push(s * 1e3);
        self.process_force_n.push(-process_force);
    }

    /// The columns in CSV order.
    pub fn columns(&self) -> [&[f64]; 14] {
        [
            &self.t_s,
            &self.crank_deg,
            &self.stroke_mm,
            &self.vel_mps,
            &self.acc_mps2,
            &self.torque_nm,
            &self.contact_force_n,
            &self.ecc_x_mm,
            &self.ecc_y_mm,
            &self.ideal_stroke_mm,
            &self.ideal_vel_mps,
            &self.ideal_acc_mps2,
            &self.ideal_torque_nm,
            &self.process_force_n,
        ]
    }

    /// Writes the curves as CSV with a header row (NaN as an empty field).
    pub fn write_csv<W: Write>(&self, mut w: W) -> std::io::Result<()> {
        writeln!(w, "{}", COLUMNS.join(","))?;
        let cols = self.columns();
        let mut line = String::with_capacity(256);
        for i in 0..self.len() {
            line.clear();
            for (j, c) in cols.iter().enumerate() {
                if j > 0 {
                    line.push(',');
                }
                let v = c[i];
                if v.is_finite() {
                    line.push_str(&format!("{v:.10e}"));
                }
            }
            line.push('\n');
            w.write_all(line.as_bytes())?;
        }
        Ok(())
    }
}
