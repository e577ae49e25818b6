//! The evaluation objects on one cycle's curve: each gives OK or NOK with
//! the reason and by how much, as a press monitor reports it.

use super::curve::CycleCurve;
use super::recipe::{Axis, Direction, Envelope, Side, Threshold, ValueCheck, Window};
use serde::{Deserialize, Serialize};

/// What one object found on one cycle.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ObjectResult {
    /// `window`, `threshold`, `envelope` or `value`.
    #[serde(deserialize_with = "super::serde_back::name")]
    pub kind: super::serde_back::Name,
    pub name: String,
    pub ok: bool,
    /// Why it failed, with the numbers.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub reason: Option<String>,
    /// How far outside, in the object's unit (N for force objects, the
    /// value's unit for value checks); 0 when OK.
    #[serde(deserialize_with = "super::serde_back::f64_nan")]
    pub by: f64,
    /// The measured value (value checks).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub value: Option<f64>,
}

impl ObjectResult {
    fn ok(kind: &'static str, name: &str, value: Option<f64>) -> Self {
        ObjectResult {
            kind,
            name: name.to_string(),
            ok: true,
            reason: None,
            by: 0.0,
            value,
        }
    }

    fn nok(kind: &'static str, name: &str, reason: String, by: f64, value: Option<f64>) -> Self {
        ObjectResult {
            kind,
            name: name.to_string(),
            ok: false,
            reason: Some(reason),
            by,
            value,
        }
    }
}

fn unit_of(axis: Axis) -> &'static str {
    match axis {
        Axis::Stroke => "mm",
        Axis::Angle => "°",
    }
}

/// Where segment p→q crosses the box's boundary first (parameter t in
/// [0, 1]) and through which side.
fn crossing(
    p: (f64, f64),
    q: (f64, f64),
    x: [f64; 2],
    y: [f64; 2],
    entering: bool,
) -> Option<(f64, Side)> {
    let mut best: Option<(f64, Side)> = None;
    let mut consider = |t: f64, side: Side, other: f64, lo: f64, hi: f64| {
        if (0.0..=1.0).contains(&t) && other >= lo && other <= hi {
            let better = match best {
                None => true,
                // Entering: the last boundary crossed before inside; leaving: the first.
                Some((b, _)) => {
                    if entering {
                        t > b
                    } else {
                        t < b
                    }
                }
            };
            if better {
                best = Some((t, side));
            }
        }
    };
    let (dx, dy) = (q.0 - p.0, q.1 - p.1);
    if dx != 0.0 {
        for (xe, side) in [(x[0], Side::Left), (x[1], Side::Right)] {
            let t = (xe - p.0) / dx;
            consider(t, side, p.1 + t * dy, y[0], y[1]);
        }
    }
    if dy != 0.0 {
        for (ye, side) in [(y[0], Side::Bottom), (y[1], Side::Top)] {
            let t = (ye - p.1) / dy;
            consider(t, side, p.0 + t * dx, x[0], x[1]);
        }
    }
    best
}

/// A window: the curve enters through `entry` and leaves through `exit`.
pub fn window(w: &Window, curve: &CycleCurve) -> ObjectResult {
    let pts = curve.points(w.x, w.branch);
    let inside = |p: (f64, f64)| {
        p.0 >= w.x_range[0] && p.0 <= w.x_range[1] && p.1 >= w.y_range[0] && p.1 <= w.y_range[1]
    };
    let mut entry: Option<Side> = None;
    let mut exit: Option<Side> = None;
    let mut entries = 0;
    for s in pts.windows(2) {
        let (a, b) = (inside(s[0]), inside(s[1]));
        if !a && b {
            entries += 1;
            if entry.is_none() {
                entry = crossing(s[0], s[1], w.x_range, w.y_range, true).map(|c| c.1);
            }
            exit = None;
        } else if a && !b {
            exit = crossing(s[0], s[1], w.x_range, w.y_range, false).map(|c| c.1);
        }
    }
    let started_inside = pts.first().is_some_and(|p| inside(*p));
    if entries == 0 && !started_inside {
        // By how much: the force gap to the window over its x range.
        let in_x: Vec<f64> = pts
            .iter()
            .filter(|p| p.0 >= w.x_range[0] && p.0 <= w.x_range[1])
            .map(|p| p.1)
            .collect();
        let (reason, by) = if in_x.is_empty() {
            (
                format!(
                    "the curve never reaches x {}–{} {}",
                    w.x_range[0],
                    w.x_range[1],
                    unit_of(w.x)
                ),
                f64::NAN,
            )
        } else {
            let lo = in_x.iter().copied().fold(f64::INFINITY, f64::min);
            let hi = in_x.iter().copied().fold(f64::NEG_INFINITY, f64::max);
            if lo > w.y_range[1] {
                (
                    format!("passes above the window by {:.3} N", lo - w.y_range[1]),
                    lo - w.y_range[1],
                )
            } else {
                (
                    format!("passes below the window by {:.3} N", w.y_range[0] - hi),
                    w.y_range[0] - hi,
                )
            }
        };
        return ObjectResult::nok("window", &w.name, reason, by, None);
    }
    let mut why = Vec::new();
    match (started_inside, entry) {
        (true, _) => why.push("starts inside the window".to_string()),
        (false, Some(s)) if s != w.entry => why.push(format!(
            "enters through the {} side, not the {}",
            s.name(),
            w.entry.name()
        )),
        _ => {}
    }
    match exit {
        None => why.push("does not leave the window".to_string()),
        Some(s) if s != w.exit => why.push(format!(
            "leaves through the {} side, not the {}",
            s.name(),
            w.exit.name()
        )),
        _ => {}
    }
    if entries > 1 {
        why.push(format!("enters {entries} times"));
    }
    if why.is_empty() {
        ObjectResult::ok("window", &w.name, None)
    } else {
        ObjectResult::nok("window", &w.name, why.join("; "), f64::NAN, None)
    }
}

/// A threshold: the force crosses `level` exactly once, in the direction,
/// inside the x range.
pub fn threshold(t: &Threshold, curve: &CycleCurve) -> ObjectResult {
    let pts: Vec<(f64, f64)> = curve
        .points(t.x, t.branch)
        .into_iter()
        .filter(|p| p.0 >= t.x_range[0] && p.0 <= t.x_range[1])
        .collect();
    if pts.is_empty() {
        return ObjectResult::nok(
            "threshold",
            &t.name,
            format!(
                "no force data at x {}–{} {}",
                t.x_range[0],
                t.x_range[1],
                unit_of(t.x)
            ),
            f64::NAN,
            None,
        );
    }
    // Signed so that "rising" is the crossing to count in both directions.
    let sign = match t.direction {
        Direction::Rising => 1.0,
        Direction::Falling => -1.0,
    };
    let (level, h) = (sign * t.level, t.hysteresis_n());
    let mut armed = false;
    let mut crossings = 0;
    for p in &pts {
        let f = sign * p.1;
        if f < level - h {
            armed = true;
        } else if armed && f >= level {
            crossings += 1;
            armed = false;
        }
    }
    let (dir, word) = match t.direction {
        Direction::Rising => ("rising", "max"),
        Direction::Falling => ("falling", "min"),
    };
    match crossings {
        1 => ObjectResult::ok("threshold", &t.name, None),
        0 => {
            let extreme = match t.direction {
                Direction::Rising => pts.iter().map(|p| p.1).fold(f64::NEG_INFINITY, f64::max),
                Direction::Falling => pts.iter().map(|p| p.1).fold(f64::INFINITY, f64::min),
            };
            let by = (t.level - extreme).abs();
            ObjectResult::nok(
                "threshold",
                &t.name,
                format!(
                    "never crosses {} N {dir} in x {}–{} {} ({word} {extreme:.3} N, {by:.3} N short)",
                    t.level,
                    t.x_range[0],
                    t.x_range[1],
                    unit_of(t.x)
                ),
                by,
                Some(extreme),
            )
        }
        n => ObjectResult::nok(
            "threshold",
            &t.name,
            format!("crosses {} N {dir} {n} times (once expected)", t.level),
            f64::NAN,
            None,
        ),
    }
}

/// An envelope: every point of the curve inside the learned band.
pub fn envelope(e: &Envelope, curve: &CycleCurve) -> ObjectResult {
    if e.x_grid.is_empty() {
        return ObjectResult::nok(
            "envelope",
            &e.name,
            "not learned yet (pinsight monitor --learn N)".into(),
            f64::NAN,
            None,
        );
    }
    let mut worst: Option<(f64, f64, bool)> = None; // (excess, x, above)
    let mut outside = 0;
    let mut missing = 0;
    let forces = curve.forces_at(e.x, e.branch, &e.x_grid);
    for (((&x, &lo), &hi), f) in e.x_grid.iter().zip(&e.lo).zip(&e.hi).zip(forces) {
        let Some(f) = f else {
            missing += 1;
            continue;
        };
        let (excess, above) = if f > hi {
            (f - hi, true)
        } else if f < lo {
            (lo - f, false)
        } else {
            continue;
        };
        outside += 1;
        if worst.is_none_or(|w| excess > w.0) {
            worst = Some((excess, x, above));
        }
    }
    if missing * 2 > e.x_grid.len() {
        return ObjectResult::nok(
            "envelope",
            &e.name,
            format!(
                "no force data at {missing} of the envelope's {} points",
                e.x_grid.len()
            ),
            f64::NAN,
            None,
        );
    }
    match worst {
        None => ObjectResult::ok("envelope", &e.name, None),
        Some((excess, x, above)) => ObjectResult::nok(
            "envelope",
            &e.name,
            format!(
                "{} the envelope by {excess:.3} N at {x:.2} {} ({outside} point(s) outside)",
                if above { "above" } else { "below" },
                unit_of(e.x)
            ),
            excess,
            None,
        ),
    }
}

/// A value check against its limits.
pub fn value(v: &ValueCheck, curve: &CycleCurve) -> ObjectResult {
    let unit = v.quantity.unit();
    let Some(x) = curve.value(v.quantity, v.at_depth_mm) else {
        return ObjectResult::nok(
            "value",
            &v.name,
            format!("{} cannot be computed (no data)", v.quantity.name()),
            f64::NAN,
            None,
        );
    };
    if let Some(lo) = v.min
        && x < lo
    {
        return ObjectResult::nok(
            "value",
            &v.name,
            format!("{x:.4} {unit} below the minimum {lo} by {:.4}", lo - x),
            lo - x,
            Some(x),
        );
    }
    if let Some(hi) = v.max
        && x > hi
    {
        return ObjectResult::nok(
            "value",
            &v.name,
            format!("{x:.4} {unit} above the maximum {hi} by {:.4}", x - hi),
            x - hi,
            Some(x),
        );
    }
    ObjectResult::ok("value", &v.name, Some(x))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::process::recipe::Branch;
    use crate::rig::cycles::Cycle;

    /// A cycle whose force rises linearly with the stroke on the way down.
    fn cycle(force: impl Fn(f64, f64) -> f64) -> (Vec<f64>, Vec<f64>, Vec<f64>, Cycle) {
        let angle: Vec<f64> = (0..720).map(|i| i as f64 * 0.5).collect();
        let stroke: Vec<f64> = angle
            .iter()
            .map(|a| 8.0 * (1.0 - a.to_radians().cos()))
            .collect();
        let f: Vec<f64> = angle
            .iter()
            .zip(&stroke)
            .map(|(&a, &s)| force(a, s))
            .collect();
        let c = Cycle {
            stroke_mm: stroke.clone(),
            force_n: f.clone(),
            ..Cycle::default()
        };
        (angle, stroke, f, c)
    }

    fn curve<'a>(a: &'a [f64], s: &'a [f64], f: &'a [f64], c: &'a Cycle) -> CycleCurve<'a> {
        CycleCurve {
            angle: a,
            stroke: s,
            force: f,
            ideal: s,
            standoff_mm: 14.0,
            cycle: c,
        }
    }

    /// Force 0 until the standoff, then 20 N/mm, on the way down only.
    fn press(a: f64, s: f64) -> f64 {
        if a <= 180.0 && s > 14.0 {
            20.0 * (s - 14.0)
        } else {
            0.0
        }
    }

    #[test]
    fn window_entry_and_exit_sides() {
        let (a, s, f, c) = cycle(press);
        let cur = curve(&a, &s, &f, &c);
        let w = |x: [f64; 2], y: [f64; 2], entry, exit| Window {
            name: "w".into(),
            x: Axis::Stroke,
            branch: Branch::Down,
            x_range: x,
            y_range: y,
            entry,
            exit,
        };
        // The ramp is at 10 N at 14.5 mm: it enters [14.5, 15.0] × [5, 30]
        // through the left side and leaves through the right (20 N at 15 mm).
        let r = window(&w([14.5, 15.0], [5.0, 30.0], Side::Left, Side::Right), &cur);
        assert!(r.ok, "{r:?}");
        let r = window(
            &w([14.5, 15.0], [5.0, 30.0], Side::Bottom, Side::Right),
            &cur,
        );
        assert!(
            !r.ok
                && r.reason
                    .as_ref()
                    .unwrap()
                    .contains("left side, not the bottom"),
            "{r:?}"
        );
        // Leaves through the top when the box is low.
        let r = window(&w([14.2, 15.5], [0.0, 12.0], Side::Left, Side::Right), &cur);
        assert!(
            !r.ok && r.reason.as_ref().unwrap().contains("top side"),
            "{r:?}"
        );
        // A window the curve passes above.
        let r = window(&w([15.5, 15.8], [0.0, 5.0], Side::Left, Side::Right), &cur);
        // 30 N at 15.5 mm, the window's top at 5 N (to the 0.5° grid).
        assert!(!r.ok && (r.by - 25.0).abs() < 0.5, "{r:?}");
    }

    #[test]
    fn threshold_counts_crossings() {
        let (a, s, f, c) = cycle(press);
        let cur = curve(&a, &s, &f, &c);
        let t = |level, direction| Threshold {
            name: "t".into(),
            x: Axis::Stroke,
            branch: Branch::Down,
            x_range: [14.0, 16.0],
            level,
            direction,
            hysteresis: None,
        };
        assert!(threshold(&t(15.0, Direction::Rising), &cur).ok);
        let r = threshold(&t(45.0, Direction::Rising), &cur);
        assert!(!r.ok && (r.by - 5.0).abs() < 0.01, "{r:?}");
        assert!(!threshold(&t(15.0, Direction::Falling), &cur).ok);
    }

    #[test]
    fn envelope_and_values() {
        let (a, s, f, c) = cycle(press);
        let cur = curve(&a, &s, &f, &c);
        let mut e = Envelope {
            name: "e".into(),
            x: Axis::Angle,
            branch: Branch::Down,
            x_range: [100.0, 170.0],
            mode: Default::default(),
            k: 4.0,
            margin: 0.0,
            learned_from: 1,
            x_grid: vec![150.0, 160.0],
            lo: vec![0.0, 0.0],
            hi: vec![100.0, 100.0],
        };
        assert!(envelope(&e, &cur).ok);
        e.hi[1] = 10.0;
        let r = envelope(&e, &cur);
        let expected = press(160.0, 8.0 * (1.0 - 160f64.to_radians().cos())) - 10.0;
        assert!(
            !r.ok && (r.by - expected).abs() < 1e-9,
            "{r:?} vs {expected}"
        );
        let v = ValueCheck {
            name: "f@1".into(),
            quantity: crate::process::recipe::Quantity::ForceAtDepthN,
            at_depth_mm: Some(1.0),
            min: Some(10.0),
            max: Some(19.0),
        };
        let r = value(&v, &cur);
        assert!(!r.ok && (r.value.unwrap() - 20.0).abs() < 0.05, "{r:?}");
    }
}
