//! The live line's state in the session (see [`super::live`] for how a
//! follower's batch enters it): counts, recent cycles and events, alarms,
//! the files' states, the signals' min/max history of the whole shift.

use crate::live::events::FileState;
use crate::live::ring::MinMaxHistory;
use crate::live::{FollowConfig, LiveCycle};
use crate::rig::channel_map::SignalKind;
use std::collections::VecDeque;

/// Lines of recent events kept for the Session pane.
pub const RECENT_LINES: usize = 200;

/// The live line's state in the session.
#[derive(Debug, Clone)]
pub struct LiveState {
    pub config: FollowConfig,
    /// What is followed (for titles).
    pub sources: Vec<String>,
    pub t0_ns: Option<i64>,
    /// Per signal: its channel index in the session's first log and its history.
    pub history: Vec<(SignalKind, MinMaxHistory)>,
    pub cycles: u64,
    pub images: u64,
    pub bytes: u64,
    pub findings: u64,
    pub recent_cycles: VecDeque<LiveCycle>,
    /// Newest sample time (s from t0).
    pub latest_s: Option<f64>,
    /// Alarm rules raised now, and the last alarm's text.
    pub active_alarms: Vec<&'static str>,
    pub last_alarm: Option<String>,
    pub alarms_raised: u64,
    /// Files followed and their states.
    pub files: Vec<(String, FileState, u64, u64)>,
    /// Recent events as text lines (newest last).
    pub lines: VecDeque<String>,
    /// Wall time of the last batch with data (for the indicator).
    pub last_data: Option<std::time::Instant>,
    /// A raised alarm not yet announced to the terminal (bell / OSC 9).
    pub announce: Vec<String>,
}

impl LiveState {
    pub fn new(config: FollowConfig, sources: Vec<String>) -> Self {
        LiveState {
            config,
            sources,
            t0_ns: None,
            history: Vec::new(),
            cycles: 0,
            images: 0,
            bytes: 0,
            findings: 0,
            recent_cycles: VecDeque::new(),
            latest_s: None,
            active_alarms: Vec::new(),
            last_alarm: None,
            alarms_raised: 0,
            files: Vec::new(),
            lines: VecDeque::new(),
            last_data: None,
            announce: Vec::new(),
        }
    }

    /// One line for the status bar: counts, yield (`yield_frac` of the
    /// session's yield), alarms.
    pub fn status(&self, yield_frac: Option<f64>) -> String {
        let y = yield_frac
            .map(|y| format!(" · yield {:.1} %", 100.0 * y))
            .unwrap_or_default();
        let alarms = if self.active_alarms.is_empty() {
            String::new()
        } else {
            format!(" · ALARM {}", self.active_alarms.join(", "))
        };
        format!("{} cycles · {} images{y}{alarms}", self.cycles, self.images)
    }

    pub(crate) fn line(&mut self, s: String) {
        self.lines.push_back(s);
        while self.lines.len() > RECENT_LINES {
            self.lines.pop_front();
        }
    }
}
