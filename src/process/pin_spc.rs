//! SPC of the pins' positions, measured on each connector's photograph: per
//! pin (row, column) and per measure, the same capability and control
//! charts as the process values (see [`super::spc`]).
//!
//! Measures and their specification limits, from the vision recipe's
//! tolerance (`position_mm` = p, the largest allowed distance of a pin
//! from its nominal point):
//!
//! | measure | what | LSL | USL |
//! |---|---|---|---|
//! | `dx` | offset along the row, mm | −p | +p |
//! | `dy` | offset across the rows, mm (top view) | −p | +p |
//! | `offset` | radial offset √(dx² + dy²), mm (top view) | – | p |
//! | `true position` | **2 × radial offset**, the drawing convention (ISO 1101 / ASME Y14.5 position tolerance is a diameter), mm (top view) | – | 2p |
//! | `height` | height above the housing, mm (side view) | nominal − tol | nominal + tol |
//!
//! `dx` and `dy` against ±p are the box that holds the round zone: a pin can
//! pass both and still fail `offset`; the radial measures are the ones the
//! verdict uses. Offset and true position are bounded below by zero, so
//! only the upper limit is given and Cpk is Cpk upper (Cp is not defined).
//! Every measured pin counts (ok, bent, damaged: SPC sees the process as it
//! ran); a missing pin has no position.

use super::monitor::Characteristic;
use super::spc::{capability, control_chart};
use crate::vision::result::Inspection;
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;

/// One pin measured on one connector's photograph.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct PinObs {
    pub row: u32,
    pub col: u32,
    pub dx_mm: Option<f64>,
    pub dy_mm: Option<f64>,
    pub offset_mm: Option<f64>,
    pub height_mm: Option<f64>,
    /// The recipe's `position_mm`.
    pub position_mm: f64,
    /// The recipe's nominal height and its tolerance (side view).
    pub height_nominal_mm: Option<f64>,
    pub height_tol_mm: Option<f64>,
}

/// The pins one connector's photograph measured, with its cycle.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ConnectorPins {
    pub cycle: u64,
    pub t_start_ns: i64,
    pub pins: Vec<PinObs>,
}

/// Every measured pin of an inspection.
pub fn observations(ins: &Inspection) -> Vec<PinObs> {
    let t = &ins.tolerance;
    ins.pins
        .iter()
        .filter(|p| p.dx_mm.is_some() || p.height_mm.is_some())
        .map(|p| PinObs {
            row: p.row,
            col: p.col,
            dx_mm: p.dx_mm,
            dy_mm: p.dy_mm,
            offset_mm: p.offset_mm,
            height_mm: p.height_mm,
            position_mm: t.position_mm,
            height_nominal_mm: t.height_mm,
            height_tol_mm: t.height_tol_mm,
        })
        .collect()
}

/// A measure of a pin's position.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord)]
pub enum PinMeasure {
    Dx,
    Dy,
    Offset,
    TruePosition,
    Height,
}

impl PinMeasure {
    pub const ALL: [PinMeasure; 5] = [
        PinMeasure::Dx,
        PinMeasure::Dy,
        PinMeasure::Offset,
        PinMeasure::TruePosition,
        PinMeasure::Height,
    ];

    /// The characteristic number (Q-DAS K2001) and JSON `quantity`.
    pub fn quantity(self) -> &'static str {
        match self {
            PinMeasure::Dx => "pin_dx_mm",
            PinMeasure::Dy => "pin_dy_mm",
            PinMeasure::Offset => "pin_offset_mm",
            PinMeasure::TruePosition => "pin_true_position_mm",
            PinMeasure::Height => "pin_height_mm",
        }
    }

    pub fn label(self) -> &'static str {
        match self {
            PinMeasure::Dx => "dx",
            PinMeasure::Dy => "dy",
            PinMeasure::Offset => "offset",
            PinMeasure::TruePosition => "true position",
            PinMeasure::Height => "height",
        }
    }

    /// The characteristic's name for pin (row, col), e.g. `pin r0c3 dx`.
    pub fn char_name(self, row: u32, col: u32) -> String {
        format!("pin r{row}c{col} {}", self.label())
    }

    /// The pin's value of this measure. Offset and true position need both
    /// axes (the side view measures along the row only).
    pub fn value(self, o: &PinObs) -> Option<f64> {
        let v = match self {
            PinMeasure::Dx => o.dx_mm,
            PinMeasure::Dy => o.dy_mm,
            PinMeasure::Offset => o.dy_mm.and(o.offset_mm),
            PinMeasure::TruePosition => o.dy_mm.and(o.offset_mm).map(|r| 2.0 * r),
            PinMeasure::Height => o.height_mm,
        };
        v.filter(|x| x.is_finite())
    }

    /// Specification limits (LSL, USL) from the recipe's tolerance.
    pub fn limits(self, o: &PinObs) -> (Option<f64>, Option<f64>) {
        let p = o.position_mm;
        match self {
            PinMeasure::Dx | PinMeasure::Dy => (Some(-p), Some(p)),
            PinMeasure::Offset => (None, Some(p)),
            PinMeasure::TruePosition => (None, Some(2.0 * p)),
            PinMeasure::Height => match (o.height_nominal_mm, o.height_tol_mm) {
                (Some(h), Some(t)) => (Some(h - t), Some(h + t)),
                _ => (None, None),
            },
        }
    }
}

/// The SPC of every pin and measure over the connectors, in the order given
/// (the series of a pin is its values in connector order); pins in row then
/// column order, measures in [`PinMeasure::ALL`] order. `charts: false`
/// leaves the control charts out (the by-lot and by-speed tables).
pub fn pin_characteristics(
    connectors: &[&ConnectorPins],
    subgroup: usize,
    charts: bool,
) -> Vec<Characteristic> {
    let mut by_pin: BTreeMap<(u32, u32), Vec<&PinObs>> = BTreeMap::new();
    for c in connectors {
        for p in &c.pins {
            by_pin.entry((p.row, p.col)).or_default().push(p);
        }
    }
    let mut out = Vec::new();
    for ((row, col), obs) in by_pin {
        for m in PinMeasure::ALL {
            let series: Vec<f64> = obs.iter().filter_map(|o| m.value(o)).collect();
            if series.is_empty() {
                continue;
            }
            let (lsl, usl) = m.limits(obs[0]);
            out.push(Characteristic {
                name: m.char_name(row, col),
                quantity: m.quantity(),
                unit: "mm",
                capability: capability(&series, subgroup, lsl, usl),
                chart: if charts {
                    control_chart(&series, subgroup)
                } else {
                    None
                },
            });
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn obs(row: u32, col: u32, dx: f64, dy: f64) -> PinObs {
        PinObs {
            row,
            col,
            dx_mm: Some(dx),
            dy_mm: Some(dy),
            offset_mm: Some(dx.hypot(dy)),
            height_mm: None,
            position_mm: 0.1,
            height_nominal_mm: None,
            height_tol_mm: None,
        }
    }

    #[test]
    fn true_position_is_twice_the_radial_offset_against_twice_the_tolerance() {
        let o = obs(0, 0, 0.03, 0.04);
        assert_eq!(PinMeasure::Offset.value(&o), Some(0.05));
        assert!((PinMeasure::TruePosition.value(&o).unwrap() - 0.1).abs() < 1e-15);
        assert_eq!(PinMeasure::TruePosition.limits(&o), (None, Some(0.2)));
        assert_eq!(PinMeasure::Dy.limits(&o), (Some(-0.1), Some(0.1)));
        // The side view measures along the row only: no radial measures.
        let side = PinObs {
            dy_mm: None,
            offset_mm: Some(0.03),
            height_mm: Some(2.95),
            height_nominal_mm: Some(3.0),
            height_tol_mm: Some(0.1),
            ..o
        };
        assert_eq!(PinMeasure::TruePosition.value(&side), None);
        assert_eq!(PinMeasure::Height.limits(&side), (Some(2.9), Some(3.1)));
    }

    #[test]
    fn one_series_per_pin_and_measure_in_connector_order() {
        // Pin r0c1's dx over four connectors: 0.01, 0.03, −0.01, 0.01.
        // Mean 0.01; sample σ = sqrt((0 + 0.0004 + 0.0004 + 0)/3) = 0.016330;
        // moving ranges 0.02, 0.04, 0.02 → MR̄ 0.026667, σ within = MR̄/1.128
        // = 0.023641; Cpk = min(0.11, 0.09)/(3 σ within) = 1.26900.
        let dx = [0.01, 0.03, -0.01, 0.01];
        let cons: Vec<ConnectorPins> = dx
            .iter()
            .enumerate()
            .map(|(i, &d)| ConnectorPins {
                cycle: i as u64,
                t_start_ns: 0,
                pins: vec![obs(0, 1, d, 0.0), obs(0, 0, 0.0, 0.0)],
            })
            .collect();
        let refs: Vec<&ConnectorPins> = cons.iter().collect();
        let chars = pin_characteristics(&refs, 1, true);
        let names: Vec<&str> = chars.iter().map(|c| c.name.as_str()).collect();
        assert_eq!(
            names,
            [
                "pin r0c0 dx",
                "pin r0c0 dy",
                "pin r0c0 offset",
                "pin r0c0 true position",
                "pin r0c1 dx",
                "pin r0c1 dy",
                "pin r0c1 offset",
                "pin r0c1 true position"
            ]
        );
        let c = &chars[4];
        assert_eq!(c.quantity, "pin_dx_mm");
        assert_eq!(c.chart.as_ref().unwrap().points, dx);
        let k = c.capability.as_ref().unwrap();
        assert!((k.mean - 0.01).abs() < 1e-12);
        assert!((k.sigma_overall - 0.016_329_93).abs() < 1e-7);
        assert!((k.sigma_within - 0.023_640_66).abs() < 1e-7);
        assert!((k.cpk.unwrap() - 1.269_00).abs() < 1e-4, "{k:?}");
        assert!(pin_characteristics(&refs, 1, false)[4].chart.is_none());
    }
}
