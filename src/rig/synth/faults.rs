//! Insertion faults for synthetic logs (issue 16's generator mode): a
//! [`FaultTruth`] is the ideal mechanism's stroke with a process load that
//! changes from cycle to cycle, as a real line's does, and on some cycles
//! carries the signature of a fault in the force curve.
//!
//! The head inserts a gang of `pins` pins per stroke; the whole gang's
//! press-in force is the recipe's `f_ins` table. Every cycle draws its own
//! part-to-part variation (force scale, seating depth); a faulty cycle adds
//! one of these signatures, each of a magnitude drawn at random:
//!
//! | fault | what happened | force curve | connector |
//! |---|---|---|---|
//! | `missing_pin` | one pin of the gang was not fed | the gang's force × (1 − 1/pins) | one pin missing |
//! | `too_deep` | the gang sits Δ lower in its carrier | contact Δ earlier, Δ deeper at bottom dead centre | every pin Δ too low |
//! | `not_fully_inserted` | the gang slipped back Δ in its carrier | contact Δ later | every pin Δ too high |
//! | `out_of_position` | the part sits off its nest; the pins land on the housing | a stiff rise k·depth, no press-in plateau | the row shifted sideways |
//!
//! Cycle k of the log (the `/rig/cycle` index) is crank revolution
//! `first_revolution + k`, counted from top dead centre; a cycle's draw
//! applies from its top dead centre to the next.

use super::truth::{IdealTruth, Truth, cd};
use serde::{Deserialize, Serialize};
use std::f64::consts::TAU;

/// A fault of one insertion.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum InsertionFault {
    MissingPin,
    TooDeep,
    NotFullyInserted,
    OutOfPosition,
}

impl InsertionFault {
    pub const ALL: [InsertionFault; 4] = [
        InsertionFault::MissingPin,
        InsertionFault::TooDeep,
        InsertionFault::NotFullyInserted,
        InsertionFault::OutOfPosition,
    ];

    pub fn name(self) -> &'static str {
        match self {
            InsertionFault::MissingPin => "missing_pin",
            InsertionFault::TooDeep => "too_deep",
            InsertionFault::NotFullyInserted => "not_fully_inserted",
            InsertionFault::OutOfPosition => "out_of_position",
        }
    }
}

/// What one cycle's insertion was like (drawn by [`draw_cycles`]).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct CycleDraw {
    /// The `/rig/cycle` index.
    pub index: u64,
    pub fault: Option<InsertionFault>,
    /// Part-to-part scale of the press-in force (≈ 1).
    pub force_scale: f64,
    /// How much deeper than nominal the gang is seated, mm (+ deeper, the
    /// pins stand lower): the part-to-part jitter, plus Δ of `too_deep`,
    /// minus Δ of `not_fully_inserted`.
    pub depth_dev_mm: f64,
    /// `out_of_position`: stiffness of the pins landing on the housing, N/mm.
    pub landing_n_per_mm: f64,
    /// `out_of_position`: sideways shift of the row, mm.
    pub shift_mm: f64,
}

/// How often and how strongly faults occur, and the good parts' spread.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct FaultRates {
    /// Probability of a fault per cycle (the kind drawn uniformly).
    pub fault_rate: f64,
    /// Pins inserted per stroke (a missing pin takes 1/pins of the force).
    pub pins: u32,
    /// σ of the good parts' force scale (relative) and seating depth (mm).
    pub force_scale_sd: f64,
    pub depth_sd_mm: f64,
    /// Δ ranges of `too_deep` and `not_fully_inserted`, mm.
    pub too_deep_mm: [f64; 2],
    pub not_fully_mm: [f64; 2],
    /// `out_of_position`: landing stiffness (N/mm) and sideways shift (mm).
    pub landing_n_per_mm: [f64; 2],
    pub shift_mm: [f64; 2],
}

impl Default for FaultRates {
    fn default() -> Self {
        FaultRates {
            fault_rate: 0.2,
            pins: 6,
            force_scale_sd: 0.02,
            depth_sd_mm: 0.015,
            too_deep_mm: [0.25, 0.8],
            not_fully_mm: [0.25, 1.0],
            landing_n_per_mm: [30.0, 80.0],
            shift_mm: [0.15, 0.3],
        }
    }
}

/// The rig generator's random numbers for fault draws (its own stream).
type FaultRng = crate::rng::SplitMix64<0x5EED_FA17_0000_0016>;

/// Draws `n` cycles' insertions, reproducibly from `seed`.
pub fn draw_cycles(n: usize, rates: &FaultRates, seed: u64) -> Vec<CycleDraw> {
    DrawStream::new(rates.clone(), seed).take(n).collect()
}

/// The draws of [`draw_cycles`] one cycle at a time (the same sequence for
/// the same seed), for a line that runs for hours without holding every
/// cycle's draw (`pinsight rig-sim`).
#[derive(Debug, Clone)]
pub struct DrawStream {
    rng: FaultRng,
    rates: FaultRates,
    k: u64,
}

impl DrawStream {
    pub fn new(rates: FaultRates, seed: u64) -> Self {
        DrawStream {
            rng: FaultRng::new(seed),
            rates,
            k: 0,
        }
    }

    /// The next cycle's draw with this fault rate (the rates' own rate is
    /// replaced: a line whose faults come in bursts).
    pub fn next_with_rate(&mut self, fault_rate: f64) -> CycleDraw {
        let rates = &self.rates;
        let rng = &mut self.rng;
        let k = self.k;
        self.k += 1;
        let faulty = rng.uniform() < fault_rate;
        let kind = InsertionFault::ALL[(rng.uniform() * 4.0) as usize % 4];
        let mut d = CycleDraw {
            index: k,
            fault: faulty.then_some(kind),
            force_scale: 1.0 + rates.force_scale_sd * rng.normal(),
            depth_dev_mm: rates.depth_sd_mm * rng.normal(),
            landing_n_per_mm: 0.0,
            shift_mm: 0.0,
        };
        let (a, b, c, e) = (rng.uniform(), rng.uniform(), rng.uniform(), rng.uniform());
        let lerp = |r: [f64; 2], u: f64| r[0] + (r[1] - r[0]) * u;
        match d.fault {
            Some(InsertionFault::TooDeep) => d.depth_dev_mm += lerp(rates.too_deep_mm, a),
            Some(InsertionFault::NotFullyInserted) => d.depth_dev_mm -= lerp(rates.not_fully_mm, b),
            Some(InsertionFault::OutOfPosition) => {
                d.landing_n_per_mm = lerp(rates.landing_n_per_mm, c);
                d.shift_mm = lerp(rates.shift_mm, e) * if a < 0.5 { -1.0 } else { 1.0 };
            }
            Some(InsertionFault::MissingPin) | None => {}
        }
        d
    }
}

impl Iterator for DrawStream {
    type Item = CycleDraw;
    fn next(&mut self) -> Option<CycleDraw> {
        let r = self.rates.fault_rate;
        Some(self.next_with_rate(r))
    }
}

/// The force of one revolution's insertion (see the module doc): the
/// load-cell reading at stroke `s` (m) moving at `v4` (m/s) with the draw
/// `d`, for the mechanism `ideal` inserting `pins` pins.
pub fn insertion_force(ideal: &IdealTruth, pins: u32, d: &CycleDraw, s: f64, v4: f64) -> f64 {
    let (v0, v1) = (ideal.v0, ideal.v1);
    let depth = s - (ideal.standoff_m - d.depth_dev_mm * 1e-3);
    if depth <= 0.0 {
        return 0.0;
    }
    match d.fault {
        Some(InsertionFault::OutOfPosition) => {
            // Pins pressed onto the housing: a stiff rise going down,
            // nothing to pull out coming back up.
            if v4 > 0.0 {
                d.landing_n_per_mm * depth * 1e3 * cd(v4, v0, v1)
            } else {
                0.0
            }
        }
        _ => {
            let gang = match d.fault {
                Some(InsertionFault::MissingPin) => 1.0 - 1.0 / pins.max(1) as f64,
                _ => 1.0,
            };
            let k = d.force_scale * gang;
            if v4 > 0.0 {
                k * ideal.f_ins.eval(depth) * cd(v4, v0, v1)
            } else {
                -k * ideal.f_wd.eval(depth) * cd(-v4, v0, v1)
            }
        }
    }
}

/// The ideal mechanism with each cycle's insertion (see the module doc).
#[derive(Debug, Clone)]
pub struct FaultTruth {
    pub ideal: IdealTruth,
    /// Crank revolution (counted from top dead centre) of cycle index 0.
    pub first_revolution: i64,
    pub pins: u32,
    pub cycles: Vec<CycleDraw>,
}

impl FaultTruth {
    /// The draw of the revolution θ2 lies in (None outside the drawn cycles:
    /// a nominal insertion).
    fn draw_at(&self, theta2: f64) -> Option<&CycleDraw> {
        let tdc = self.ideal.geometry.tdc_angle();
        let rev = ((theta2 - tdc) / TAU).floor() as i64;
        let k = rev - self.first_revolution;
        usize::try_from(k).ok().and_then(|k| self.cycles.get(k))
    }
}

impl Truth for FaultTruth {
    fn eval(&self, _t: f64, theta2: f64, omega2: f64) -> (f64, f64) {
        let g = &self.ideal.geometry;
        let pose = g.pose(theta2, omega2, 0.0);
        let s = pose.x4 - g.x4_tdc();
        let Some(d) = self.draw_at(theta2) else {
            return self.ideal.eval(0.0, theta2, omega2);
        };
        (
            s * 1e3,
            insertion_force(&self.ideal, self.pins, d, s, pose.v4),
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::Params;

    fn truth(draws: Vec<CycleDraw>) -> FaultTruth {
        FaultTruth {
            ideal: IdealTruth::from_params(&Params::paper()),
            first_revolution: 0,
            pins: 6,
            cycles: draws,
        }
    }

    fn nominal(fault: Option<InsertionFault>) -> CycleDraw {
        CycleDraw {
            index: 0,
            fault,
            force_scale: 1.0,
            depth_dev_mm: 0.0,
            landing_n_per_mm: 50.0,
            shift_mm: 0.2,
        }
    }

    /// The peak of the force over the down stroke of revolution 0.
    fn peak(t: &FaultTruth) -> f64 {
        let tdc = t.ideal.geometry.tdc_angle();
        (0..2000)
            .map(|i| t.eval(0.0, tdc + TAU * i as f64 / 2000.0, 125.0).1)
            .fold(f64::NEG_INFINITY, f64::max)
    }

    #[test]
    fn a_nominal_cycle_is_the_ideal_truth_and_each_fault_leaves_its_signature() {
        let ideal = peak(&truth(vec![]));
        assert!((peak(&truth(vec![nominal(None)])) - ideal).abs() < 1e-9);
        let missing = peak(&truth(vec![nominal(Some(InsertionFault::MissingPin))]));
        assert!(
            (missing - ideal * 5.0 / 6.0).abs() < 1e-9,
            "{missing} {ideal}"
        );
        let oop = peak(&truth(vec![nominal(Some(InsertionFault::OutOfPosition))]));
        assert!(oop > 3.0 * ideal, "{oop}");
        // A deeper seating meets the part earlier: force at the nominal
        // contact stroke + 0.1 mm is already well up the ramp.
        let mut deep = nominal(Some(InsertionFault::TooDeep));
        deep.depth_dev_mm = 0.5;
        let t = truth(vec![deep]);
        let g = t.ideal.geometry;
        // Find θ2 where the stroke is standoff + 0.1 mm on the way down.
        let target = t.ideal.standoff_m + 0.1e-3;
        let th = (0..20000)
            .map(|i| g.tdc_angle() + std::f64::consts::PI * i as f64 / 20000.0)
            .find(|&th| g.pose(th, 125.0, 0.0).x4 - g.x4_tdc() >= target)
            .unwrap();
        let f_deep = t.eval(0.0, th, 125.0).1;
        let f_nom = truth(vec![nominal(None)]).eval(0.0, th, 125.0).1;
        assert!(f_deep > 20.0 && f_nom < 5.0, "{f_deep} {f_nom}");
    }

    #[test]
    fn draws_are_reproducible_and_hit_every_fault() {
        let r = FaultRates::default();
        let a = draw_cycles(400, &r, 7);
        assert_eq!(a, draw_cycles(400, &r, 7));
        let faulty = a.iter().filter(|d| d.fault.is_some()).count();
        assert!((50..110).contains(&faulty), "{faulty}");
        for f in InsertionFault::ALL {
            assert!(a.iter().any(|d| d.fault == Some(f)), "{f:?}");
        }
        for d in &a {
            match d.fault {
                Some(InsertionFault::TooDeep) => assert!(d.depth_dev_mm > 0.15),
                Some(InsertionFault::NotFullyInserted) => assert!(d.depth_dev_mm < -0.15),
                _ => assert!(d.depth_dev_mm.abs() < 0.1),
            }
        }
    }
}
