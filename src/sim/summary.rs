//! Summary figures of a run and the continuous-time peak tracker.

use crate::model::clearance::Outputs;
use serde::{Deserialize, Serialize};

/// The summary of one simulation (model.md, "Summary figures"), with the
/// run's identity and work. Field names carry units; they are the keys of
/// `pinsight simulate --json`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, Default)]
pub struct Summary {
    pub preset: String,
    pub motor_rpm: f64,
    pub clearance_mm: f64,
    pub material: String,
    pub contact_model: String,
    pub level: String,
    pub method: String,
    pub rtol: f64,
    pub atol: f64,
    /// Fixed step (s) when one was used.
    pub step_s: Option<f64>,
    pub warmup_revs: f64,
    pub revs: f64,
    /// Which view this is: "deterministic window" (warmup 0, ≤ 1 rev) or
    /// "single realisation" (one trajectory of a chaotic motion: compare
    /// statistics, not values).
    pub view: String,
    /// Accepted steps, rejected steps, right-hand-side evaluations of the integrator.
    pub steps: u64,
    pub rejected_steps: u64,
    pub rhs_evals: u64,
    /// Evaluations for figures and event location (same cost as a RHS evaluation).
    pub aux_evals: u64,
    pub jacobians: u64,
    pub wall_ms: f64,
    /// Contact onsets in the reported window.
    pub n_impacts: u64,
    pub peak_accel_mps2: f64,
    pub peak_contact_force_n: f64,
    pub disp_dev_mean_mm: f64,
    pub disp_dev_max_mm: f64,
    pub vel_dev_mean_mps: f64,
    pub vel_dev_max_mps: f64,
    /// Peak |M12|; null at the kinematic level (no forces).
    pub peak_torque_nm: Option<f64>,
    pub torque_dev_rms_nm: Option<f64>,
    pub stroke_min_mm: f64,
    pub stroke_max_mm: f64,
    /// Peak load-cell force (+ = pin pushed into the part); null at the kinematic level.
    pub peak_process_force_n: Option<f64>,
    /// The ideal mechanism's peaks over the same window, for comparison.
    pub ideal_peak_accel_mps2: f64,
    pub ideal_peak_torque_nm: Option<f64>,
    /// Largest penetration δ of the journal into the bearing, µm (continuous-time peak).
    pub peak_penetration_um: f64,
    /// Accepted steps taken in contact and in free flight (where the work goes).
    pub contact_steps: u64,
    pub free_steps: u64,
    /// Free-flight steps whose double crossing of the clearance boundary
    /// was caught by the guard.
    pub double_crossings_caught: u64,
    /// Level `motor`: speed ripple, motor torque and the energy balance.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub motor: Option<MotorSummary>,
    /// Stick law: how often the part held the pin bar, and the steps it took.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub stick: Option<StickSummary>,
}

/// Energy over the reported window (J): the motor's work at its shaft
/// against where it went.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct EnergyBalance {
    pub motor_work_j: f64,
    pub gear_loss_j: f64,
    pub guide_friction_j: f64,
    pub process_work_j: f64,
    /// Absorbed in the clearance joint by impacts (contact hysteresis) and
    /// joint friction.
    pub impact_and_joint_friction_j: f64,
    /// Change of kinetic energy (rotor, flywheel, crank, rod, pin bar),
    /// of potential energy (gravity) and of elastic contact energy.
    pub kinetic_change_j: f64,
    pub potential_change_j: f64,
    pub elastic_change_j: f64,
    /// Motor work − every term above: zero up to the integration error.
    pub residual_j: f64,
}

/// The motor level's own figures (model.md, "Summary figures" plus the
/// ripple and the motor's duty).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct MotorSummary {
    pub curve: String,
    pub control: String,
    /// The operating crank speed the run started from (rev/min).
    pub operating_crank_rpm: f64,
    /// Linear curve: the motor's no-load speed as given or chosen (`auto`).
    pub no_load_rpm: Option<f64>,
    /// Rotor + flywheel inertia referred to the crank, kg m².
    pub drive_inertia_kgm2: f64,
    /// Crank speed over the reported window (rev/min): time mean, min, max.
    pub mean_crank_rpm: f64,
    pub min_crank_rpm: f64,
    pub max_crank_rpm: f64,
    /// Speed ripple: peak-to-peak over the mean, %.
    pub ripple_p2p_pct: f64,
    /// First harmonic of the crank speed over crank angle, % of the mean
    /// (the rig logs' `ripple %`), and the crank angle after top dead
    /// centre where it peaks (None over less than one revolution).
    pub ripple_h1_pct: Option<f64>,
    pub ripple_h1_phase_deg: Option<f64>,
    /// The motor's duty at its shaft: peak |torque|, RMS torque (what
    /// heats it), mean power.
    pub peak_motor_torque_nm: f64,
    pub rms_motor_torque_nm: f64,
    pub mean_motor_power_w: f64,
    /// The torque the curve gives at the mean motor speed (the margin to
    /// the RMS demand), N·m.
    pub curve_torque_at_mean_nm: f64,
    pub energy: EnergyBalance,
}

/// The stick law's events over the whole run (warm-up included): the
/// switches between resisting down, up and holding; the holding phases and
/// the integration steps spent in them (bounded: no chattering).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, Default)]
pub struct StickSummary {
    pub events: u64,
    pub held_phases: u64,
    pub held_steps: u64,
    pub max_steps_per_phase: u64,
}

impl Summary {
    /// The first figure that must be a number and is not (NaN or
    /// infinite), by its key. The contact figures (`peak_contact_force_n`,
    /// `peak_penetration_um`) are left out: they are undefined, not wrong,
    /// in a run with no contact.
    pub fn non_finite(&self) -> Option<&'static str> {
        let figures = [
            ("peak_accel_mps2", Some(self.peak_accel_mps2)),
            ("disp_dev_mean_mm", Some(self.disp_dev_mean_mm)),
            ("disp_dev_max_mm", Some(self.disp_dev_max_mm)),
            ("vel_dev_mean_mps", Some(self.vel_dev_mean_mps)),
            ("vel_dev_max_mps", Some(self.vel_dev_max_mps)),
            ("peak_torque_nm", self.peak_torque_nm),
            ("torque_dev_rms_nm", self.torque_dev_rms_nm),
            ("stroke_min_mm", Some(self.stroke_min_mm)),
            ("stroke_max_mm", Some(self.stroke_max_mm)),
            ("peak_process_force_n", self.peak_process_force_n),
            ("ideal_peak_accel_mps2", Some(self.ideal_peak_accel_mps2)),
            ("ideal_peak_torque_nm", self.ideal_peak_torque_nm),
        ];
        figures
            .into_iter()
            .find(|(_, v)| v.is_some_and(|v| !v.is_finite()))
            .map(|(k, _)| k)
    }
}

/// Quantities whose continuous-time maxima are tracked.
pub(crate) const NQ: usize = 12;
pub(crate) const Q_ACC: usize = 0;
pub(crate) const Q_FN: usize = 1;
pub(crate) const Q_M12: usize = 2;
pub(crate) const Q_DS: usize = 3;
pub(crate) const Q_DV: usize = 4;
pub(crate) const Q_SMIN: usize = 5;
pub(crate) const Q_SMAX: usize = 6;
pub(crate) const Q_PROC: usize = 7;
pub(crate) const Q_PEN: usize = 8;
/// Crank speed's maximum and minimum (−ω2) and the motor torque's peak
/// (constant or NaN below the motor level: never refined there).
pub(crate) const Q_W2MAX: usize = 9;
pub(crate) const Q_W2MIN: usize = 10;
pub(crate) const Q_TM: usize = 11;

/// The tracked quantities of an output (all maximised; the stroke minimum
/// as the maximum of −s).
#[inline]
pub(crate) fn quantities(o: &Outputs) -> [f64; NQ] {
    [
        o.a4.abs(),
        o.f_n,
        o.m12.abs(),
        (o.s - o.ideal_s).abs(),
        (o.v4 - o.ideal_v).abs(),
        -o.s,
        o.s,
        -o.process_force,
        o.delta,
        o.omega2,
        -o.omega2,
        o.motor_torque.abs(),
    ]
}

/// Running maxima; candidates for refinement are found from the values at
/// segment ends (a discrete local maximum, or a parabola through three
/// consecutive ends peaking near the record).
#[derive(Debug, Clone)]
pub(crate) struct PeakTracker {
    pub best: [f64; NQ],
    /// Values at the last two segment boundaries: [t_{k-1}, t_k].
    vals: [[f64; NQ]; 2],
    times: [f64; 2],
    started: bool,
}

impl PeakTracker {
    pub fn new() -> Self {
        Self {
            best: [f64::NEG_INFINITY; NQ],
            vals: [[f64::NEG_INFINITY; NQ]; 2],
            times: [0.0; 2],
            started: false,
        }
    }

    /// Starts the window at time t with values v.
    pub fn start(&mut self, t: f64, v: [f64; NQ]) {
        self.best = v;
        self.vals = [v, v];
        self.times = [t, t];
        self.started = true;
    }

    pub fn started(&self) -> bool {
        self.started
    }

    /// A new segment ended at t with values v. Returns, per quantity,
    /// whether the previous boundary t_k (between the last two segments)
    /// should be refined.
    pub fn push(&mut self, t: f64, v: [f64; NQ]) -> [bool; NQ] {
        let mut refine = [false; NQ];
        let [vkm1, vk] = self.vals;
        let [tkm1, tk] = self.times;
        for q in 0..NQ {
            let local_max = vk[q] >= vkm1[q] && vk[q] >= v[q] && (vk[q] > vkm1[q] || vk[q] > v[q]);
            if local_max {
                // Parabola through the three points: its vertex value.
                let est = parabola_peak(tkm1, vkm1[q], tk, vk[q], t, v[q]).unwrap_or(vk[q]);
                let est = est.max(vk[q]);
                let b = self.best[q];
                if est >= b - 0.05 * b.abs() {
                    refine[q] = true;
                }
            }
            if v[q] > self.best[q] {
                self.best[q] = v[q];
            }
        }
        self.vals = [vk, v];
        self.times = [tk, t];
        refine
    }

    /// Offers a refined value.
    pub fn offer(&mut self, q: usize, v: f64) {
        if v > self.best[q] {
            self.best[q] = v;
        }
    }
}

/// Vertex value of the parabola through three points (None if degenerate or opening upward).
fn parabola_peak(t0: f64, v0: f64, t1: f64, v1: f64, t2: f64, v2: f64) -> Option<f64> {
    let d01 = t1 - t0;
    let d12 = t2 - t1;
    if d01 <= 0.0 || d12 <= 0.0 || !(v0.is_finite() && v1.is_finite() && v2.is_finite()) {
        return None;
    }
    let s01 = (v1 - v0) / d01;
    let s12 = (v2 - v1) / d12;
    let a = (s12 - s01) / (t2 - t0);
    if a >= 0.0 {
        return None;
    }
    let b = s01 - a * (t0 + t1);
    let tv = -b / (2.0 * a);
    if tv < t0 || tv > t2 {
        return None;
    }
    Some(v1 + s01 * (tv - t1) + a * (tv - t0) * (tv - t1))
}

#[cfg(test)]
mod tests {
    #[test]
    fn a_non_finite_figure_is_named() {
        let mut s = Summary::default();
        assert_eq!(s.non_finite(), None);
        // No contact: the contact figures are undefined, not an error.
        s.peak_contact_force_n = f64::NAN;
        assert_eq!(s.non_finite(), None);
        s.peak_torque_nm = Some(f64::INFINITY);
        assert_eq!(s.non_finite(), Some("peak_torque_nm"));
        s.peak_accel_mps2 = f64::NAN;
        assert_eq!(s.non_finite(), Some("peak_accel_mps2"));
    }

    use super::*;

    #[test]
    fn parabola_vertex() {
        let f = |t: f64| 3.0 - (t - 0.4) * (t - 0.4);
        let p = parabola_peak(0.0, f(0.0), 0.5, f(0.5), 1.5, f(1.5)).unwrap();
        assert!((p - 3.0).abs() < 1e-12);
        assert!(parabola_peak(0.0, 0.0, 1.0, 1.0, 2.0, 4.0).is_none());
    }

    #[test]
    fn local_maxima_flagged() {
        let mut tr = PeakTracker::new();
        let mut v = [0.0; NQ];
        tr.start(0.0, v);
        v[0] = 1.0;
        assert!(!tr.push(1.0, v)[0]);
        v[0] = 0.5;
        assert!(tr.push(2.0, v)[0], "boundary at t=1 is a local maximum");
        assert_eq!(tr.best[0], 1.0);
    }
}
