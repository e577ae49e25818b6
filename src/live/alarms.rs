//! Alarms of a live line: configurable rules evaluated on every new cycle,
//! image and poll; each rule is raised once when its condition starts and
//! cleared once when it ends (no repeat while it holds).
//!
//! The rules are plain serde data, loadable from a TOML section:
//!
//! ```toml
//! [alarms]
//! bell = false        # ring the terminal bell when an alarm is raised
//! osc9 = false        # also send an OSC 9 desktop notification
//! [[alarms.rule]]
//! kind = "yield_below"    # yield over the last `last` connectors below `min`
//! last = 50
//! min = 0.9
//! [[alarms.rule]]
//! kind = "nok_in_a_row"   # `count` NOK cycles in a row
//! count = 3
//! [[alarms.rule]]
//! kind = "stroke_drift"   # stroke residual out of the band learned on the first cycles
//! learn = 50
//! k = 4.0
//! consecutive = 5
//! [[alarms.rule]]
//! kind = "speed_off"      # cycle speed off the set-point by more than `tolerance` (relative)
//! tolerance = 0.02
//! consecutive = 3
//! [[alarms.rule]]
//! kind = "sensor_stopped" # a signal without samples for `after_s` of log time while others go on
//! after_s = 1.0
//! ```

use crate::rig::channel_map::SignalKind;
use serde::{Deserialize, Serialize};
use std::collections::{BTreeMap, VecDeque};

/// One rule.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case", deny_unknown_fields)]
pub enum Rule {
    YieldBelow {
        #[serde(default = "d_last")]
        last: usize,
        #[serde(default = "d_min")]
        min: f64,
    },
    NokInARow {
        #[serde(default = "d_count")]
        count: usize,
    },
    StrokeDrift {
        #[serde(default = "d_learn")]
        learn: usize,
        #[serde(default = "d_k")]
        k: f64,
        #[serde(default = "d_consecutive")]
        consecutive: usize,
    },
    SpeedOff {
        #[serde(default = "d_tol")]
        tolerance: f64,
        #[serde(default = "d_speed_consecutive")]
        consecutive: usize,
        /// The set-point (rev/min); default: the log's `motor_rpm` metadata.
        #[serde(default)]
        setpoint_rpm: Option<f64>,
    },
    SensorStopped {
        #[serde(default = "d_after")]
        after_s: f64,
    },
}

fn d_last() -> usize {
    50
}
fn d_min() -> f64 {
    0.9
}
fn d_count() -> usize {
    3
}
fn d_learn() -> usize {
    50
}
fn d_k() -> f64 {
    4.0
}
fn d_consecutive() -> usize {
    5
}
fn d_tol() -> f64 {
    0.02
}
fn d_speed_consecutive() -> usize {
    3
}
fn d_after() -> f64 {
    1.0
}

impl Rule {
    /// The rule's name in events and on screen.
    pub fn name(&self) -> &'static str {
        match self {
            Rule::YieldBelow { .. } => "yield_below",
            Rule::NokInARow { .. } => "nok_in_a_row",
            Rule::StrokeDrift { .. } => "stroke_drift",
            Rule::SpeedOff { .. } => "speed_off",
            Rule::SensorStopped { .. } => "sensor_stopped",
        }
    }
}

/// The alarm rules and how a raised alarm is announced.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct AlarmRules {
    /// Ring the terminal bell (BEL) when an alarm is raised.
    pub bell: bool,
    /// Send an OSC 9 notification (`ESC ] 9 ; text BEL`) when an alarm is raised.
    pub osc9: bool,
    #[serde(rename = "rule")]
    pub rules: Vec<Rule>,
}

impl Default for AlarmRules {
    fn default() -> Self {
        AlarmRules {
            bell: false,
            osc9: false,
            rules: vec![
                Rule::YieldBelow {
                    last: d_last(),
                    min: d_min(),
                },
                Rule::NokInARow { count: d_count() },
                Rule::StrokeDrift {
                    learn: d_learn(),
                    k: d_k(),
                    consecutive: d_consecutive(),
                },
                Rule::SpeedOff {
                    tolerance: d_tol(),
                    consecutive: d_speed_consecutive(),
                    setpoint_rpm: None,
                },
                Rule::SensorStopped { after_s: d_after() },
            ],
        }
    }
}

impl AlarmRules {
    /// Reads the `[alarms]` table of a TOML document (the whole document
    /// when it has no such table).
    pub fn from_toml(text: &str) -> Result<Self, String> {
        let v: toml::Table = text.parse().map_err(|e: toml::de::Error| e.to_string())?;
        let t = match v.get("alarms") {
            Some(a) => a.clone(),
            None => toml::Value::Table(v),
        };
        t.try_into().map_err(|e: toml::de::Error| e.to_string())
    }

    /// The announcement of an alarm for a terminal (bell and/or OSC 9), or "".
    pub fn notification(&self, text: &str) -> String {
        let mut s = String::new();
        if self.osc9 {
            let clean: String = text.chars().filter(|c| !c.is_control()).collect();
            s.push_str(&format!("\x1b]9;pinsight: {clean}\x07"));
        }
        if self.bell {
            s.push('\x07');
        }
        s
    }
}

/// A change of an alarm: raised or cleared.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct AlarmEvent {
    pub rule: &'static str,
    pub raised: bool,
    pub message: String,
    pub file: Option<String>,
    pub cycle: Option<u64>,
    /// Log time of the cycle or sample that changed it (ns).
    pub t_ns: Option<i64>,
}

/// What the alarms look at for one cycle.
#[derive(Debug, Clone)]
pub struct CycleInput<'a> {
    pub file: &'a str,
    pub index: u64,
    pub t_ns: i64,
    pub motor_rpm: f64,
    pub stroke_dev_rms_mm: f64,
    /// Process verdict: Some(true) NOK, Some(false) OK, None not judged.
    pub nok: Option<bool>,
    pub setpoint_rpm: Option<f64>,
}

#[derive(Debug, Clone, Default)]
struct RuleState {
    active: bool,
    run: usize,
    learn: Vec<f64>,
    band: Option<(f64, f64)>,
    recent: VecDeque<bool>,
}

impl RuleState {
    /// Counts a cycle out of bounds (a clean one resets the count): the
    /// alarm is raised after `consecutive` in a row and cleared by the
    /// first cycle back.
    fn streak(&mut self, out: bool, consecutive: usize) -> bool {
        self.run = if out { self.run + 1 } else { 0 };
        if self.active {
            out
        } else {
            self.run >= consecutive.max(1)
        }
    }
}

/// What a cycle rule says when it is raised or cleared: the figures of
/// the cycle that changed it.
enum Said {
    /// Cycles NOK in a row.
    NokRun(usize),
    /// The stroke residual (mm), its band and the cycles needed out of it.
    Drift(f64, (f64, f64), usize),
    /// The motor speed and the set-point (rpm).
    Speed(f64, f64),
}

impl Said {
    fn text(&self, raised: bool, cycle: u64) -> String {
        match (self, raised) {
            (Said::NokRun(run), true) => {
                format!("{run} NOK cycles in a row (up to cycle {cycle})")
            }
            (Said::NokRun(_), false) => format!("cycle {cycle} OK again"),
            (Said::Drift(x, (lo, hi), consecutive), true) => format!(
                "stroke residual {x:.4} mm out of its band {lo:.4}–{hi:.4} mm for {consecutive} cycles (cycle {cycle}): joint wear?"
            ),
            (Said::Drift(..), false) => {
                format!("stroke residual back in its band (cycle {cycle})")
            }
            (Said::Speed(rpm, sp), true) => format!(
                "motor speed {rpm:.1} rpm is {:+.1} % off the set-point {sp:.0} rpm (cycle {cycle})",
                100.0 * (rpm - sp) / sp
            ),
            (Said::Speed(..), false) => {
                format!("motor speed back at the set-point (cycle {cycle})")
            }
        }
    }
}

/// The rules' state over a shift (bounded: the last `last` connectors of a
/// yield rule, the learning cycles of a drift rule).
#[derive(Debug, Clone)]
pub struct Alarms {
    pub rules: AlarmRules,
    state: Vec<RuleState>,
    stopped: BTreeMap<SignalKind, bool>,
}

impl Alarms {
    pub fn new(rules: AlarmRules) -> Self {
        let n = rules.rules.len();
        Alarms {
            rules,
            state: vec![RuleState::default(); n],
            stopped: BTreeMap::new(),
        }
    }

    /// Names and messages of the alarms raised now.
    pub fn active(&self) -> Vec<&'static str> {
        self.rules
            .rules
            .iter()
            .zip(&self.state)
            .filter(|(_, s)| s.active)
            .map(|(r, _)| r.name())
            .collect()
    }

    fn set(
        st: &mut RuleState,
        on: bool,
        rule: &'static str,
        msg: impl FnOnce() -> String,
        c: Option<&CycleInput>,
        out: &mut Vec<AlarmEvent>,
    ) {
        if on != st.active {
            st.active = on;
            out.push(AlarmEvent {
                rule,
                raised: on,
                message: msg(),
                file: c.map(|c| c.file.to_string()),
                cycle: c.map(|c| c.index),
                t_ns: c.map(|c| c.t_ns),
            });
        }
    }

    /// A new cycle.
    pub fn cycle(&mut self, c: &CycleInput, out: &mut Vec<AlarmEvent>) {
        for (r, st) in self.rules.rules.iter().zip(self.state.iter_mut()) {
            let (on, said) = match r {
                Rule::NokInARow { count } => {
                    match c.nok {
                        Some(true) => st.run += 1,
                        Some(false) => st.run = 0,
                        None => {}
                    }
                    (st.run >= (*count).max(1), Said::NokRun(st.run))
                }
                Rule::StrokeDrift {
                    learn,
                    k,
                    consecutive,
                } => {
                    let x = c.stroke_dev_rms_mm;
                    if !x.is_finite() {
                        continue;
                    }
                    let Some((lo, hi)) = st.band else {
                        st.learn.push(x);
                        if st.learn.len() >= (*learn).max(2) {
                            let n = st.learn.len() as f64;
                            let m = st.learn.iter().sum::<f64>() / n;
                            let sd = (st.learn.iter().map(|v| (v - m).powi(2)).sum::<f64>()
                                / (n - 1.0))
                                .sqrt()
                                .max(1e-4);
                            st.band = Some((m - k * sd, m + k * sd));
                            st.learn = Vec::new();
                        }
                        continue;
                    };
                    let on = st.streak(x < lo || x > hi, *consecutive);
                    (on, Said::Drift(x, (lo, hi), *consecutive))
                }
                Rule::SpeedOff {
                    tolerance,
                    consecutive,
                    setpoint_rpm,
                } => {
                    let Some(sp) = setpoint_rpm.or(c.setpoint_rpm) else {
                        continue;
                    };
                    if !c.motor_rpm.is_finite() || sp <= 0.0 {
                        continue;
                    }
                    let off = (c.motor_rpm - sp).abs() / sp > *tolerance;
                    (st.streak(off, *consecutive), Said::Speed(c.motor_rpm, sp))
                }
                _ => continue,
            };
            Self::set(st, on, r.name(), || said.text(on, c.index), Some(c), out);
        }
    }

    /// A connector judged by vision (`pass`: true when it passed, errors are not counted).
    pub fn image(&mut self, name: &str, pass: Option<bool>, out: &mut Vec<AlarmEvent>) {
        let Some(pass) = pass else {
            return;
        };
        for (r, st) in self.rules.rules.iter().zip(self.state.iter_mut()) {
            if let Rule::YieldBelow { last, min } = r {
                st.recent.push_back(pass);
                while st.recent.len() > (*last).max(1) {
                    st.recent.pop_front();
                }
                if st.recent.len() < (*last).max(1) {
                    continue;
                }
                let y = st.recent.iter().filter(|p| **p).count() as f64 / st.recent.len() as f64;
                let on = y < *min;
                let n = st.recent.len();
                if on != st.active {
                    st.active = on;
                    out.push(AlarmEvent {
                        rule: r.name(),
                        raised: on,
                        message: if on {
                            format!(
                                "yield {:.1} % over the last {n} connectors, below {:.1} % (at {name})",
                                100.0 * y,
                                100.0 * min
                            )
                        } else {
                            format!("yield back to {:.1} % over the last {n} connectors", 100.0 * y)
                        },
                        file: None,
                        cycle: None,
                        t_ns: None,
                    });
                }
            }
        }
    }

    /// The latest sample time of each signal of a log: a signal more than
    /// `after_s` behind the newest one has stopped.
    pub fn sensors(&mut self, file: &str, last: &[(SignalKind, i64)], out: &mut Vec<AlarmEvent>) {
        let Some(after) = self.rules.rules.iter().find_map(|r| match r {
            Rule::SensorStopped { after_s } => Some(*after_s),
            _ => None,
        }) else {
            return;
        };
        let Some(newest) = last.iter().map(|x| x.1).max() else {
            return;
        };
        for &(k, t) in last {
            if k == SignalKind::Cycle {
                continue;
            }
            let lag = (newest - t) as f64 * 1e-9;
            let stopped = lag > after;
            let was = self.stopped.insert(k, stopped).unwrap_or(false);
            if stopped != was {
                out.push(AlarmEvent {
                    rule: "sensor_stopped",
                    raised: stopped,
                    message: if stopped {
                        format!("{} has sent no sample for {lag:.1} s of log time", k.name())
                    } else {
                        format!("{} is sending again", k.name())
                    },
                    file: Some(file.to_string()),
                    cycle: None,
                    t_ns: Some(t),
                });
            }
        }
        let any = self.stopped.values().any(|s| *s);
        for (r, st) in self.rules.rules.iter().zip(self.state.iter_mut()) {
            if matches!(r, Rule::SensorStopped { .. }) {
                st.active = any;
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn cyc(i: u64, nok: Option<bool>, rpm: f64, dev: f64) -> CycleInput<'static> {
        CycleInput {
            file: "f",
            index: i,
            t_ns: i as i64,
            motor_rpm: rpm,
            stroke_dev_rms_mm: dev,
            nok,
            setpoint_rpm: Some(1500.0),
        }
    }

    #[test]
    fn each_rule_raises_once_and_clears_once() {
        let mut a = Alarms::new(AlarmRules::default());
        let mut ev = Vec::new();
        for i in 0..60 {
            a.cycle(
                &cyc(i, Some(false), 1500.0, 0.01 + 1e-4 * (i % 3) as f64),
                &mut ev,
            );
        }
        assert!(ev.is_empty(), "{ev:?}");
        for i in 60..65 {
            a.cycle(&cyc(i, Some(true), 1500.0, 0.01), &mut ev);
        }
        let nok: Vec<_> = ev.iter().filter(|e| e.rule == "nok_in_a_row").collect();
        assert_eq!(nok.len(), 1);
        assert!(nok[0].raised && nok[0].cycle == Some(62), "{nok:?}");
        a.cycle(&cyc(65, Some(false), 1500.0, 0.01), &mut ev);
        assert_eq!(ev.iter().filter(|e| e.rule == "nok_in_a_row").count(), 2);
        // Drift: 5 cycles far out of the learned band.
        for i in 66..72 {
            a.cycle(&cyc(i, Some(false), 1500.0, 0.05), &mut ev);
        }
        let d: Vec<_> = ev.iter().filter(|e| e.rule == "stroke_drift").collect();
        assert_eq!(d.len(), 1, "{d:?}");
        assert_eq!(d[0].cycle, Some(70));
        // Speed 3 % off for 3 cycles.
        for i in 72..75 {
            a.cycle(&cyc(i, Some(false), 1545.0, 0.01), &mut ev);
        }
        assert!(
            ev.iter()
                .any(|e| e.rule == "speed_off" && e.raised && e.cycle == Some(74))
        );
        // Yield: 50 connectors, 10 fail.
        for i in 0..50 {
            a.image("x", Some(i % 5 != 0), &mut ev);
        }
        assert!(ev.iter().any(|e| e.rule == "yield_below" && e.raised));
        let mut s = Vec::new();
        a.sensors(
            "f",
            &[(SignalKind::Force, 0), (SignalKind::Angle, 2_000_000_000)],
            &mut s,
        );
        assert_eq!(s.len(), 1);
        assert!(s[0].raised && s[0].message.contains("force"));
        a.sensors(
            "f",
            &[
                (SignalKind::Force, 2_000_000_000),
                (SignalKind::Angle, 2_000_000_000),
            ],
            &mut s,
        );
        assert_eq!(s.len(), 2);
        assert!(!s[1].raised);
    }

    #[test]
    fn rules_load_from_a_toml_section() {
        let r = AlarmRules::from_toml(
            "[alarms]\nbell = true\n[[alarms.rule]]\nkind = \"nok_in_a_row\"\ncount = 5\n",
        )
        .unwrap();
        assert!(r.bell);
        assert_eq!(r.rules, vec![Rule::NokInARow { count: 5 }]);
        assert!(AlarmRules::from_toml("[[alarms.rule]]\nkind = \"nope\"\n").is_err());
        let back = toml::to_string(&AlarmRules::default()).unwrap();
        assert_eq!(AlarmRules::from_toml(&back).unwrap(), AlarmRules::default());
        assert_eq!(
            AlarmRules {
                osc9: true,
                bell: true,
                rules: vec![]
            }
            .notification("a\nb"),
            "\x1b]9;pinsight: ab\x07\x07"
        );
    }
}
