//! The live line: following a rig while it records.
//!
//! - [`tail`]: a growing MCAP read from its last complete record; a chunk
//!   still being written is waited for, never reported as corruption.
//! - [`decode`]: the rig loader's decoder over the new chunks.
//! - [`cycles`]: the rig's cycle analysis on a short window, each cycle
//!   reported once when complete.
//! - [`folder`]: watched folders (camera images, the next log of a rig
//!   that starts a file per run), bounded memory of what was seen.
//! - [`alarms`]: configurable rules (yield, NOK in a row, stroke drift,
//!   speed, a stopped sensor), raised and cleared once.
//! - [`follower`]: all of it per poll → a [`events::LiveBatch`] of events
//!   and data; `pinsight watch` prints the events, the TUI draws the data.
//! - [`wake`]: when to poll: file-system events (`notify` with its
//!   debouncer) or a fixed interval for network shares.
//! - [`ring`]: the raw window and the shift's min/max history.
//! - [`sim`]: `pinsight rig-sim`, a rig writing a log in real time.
//!
//! Floor: below `engine` (which the faces reach it through), above `rig`,
//! `process` and `vision`, whose analyses it runs unchanged.

pub mod alarms;
pub mod cycles;
pub mod decode;
pub mod events;
pub mod folder;
pub mod follower;
pub mod ring;
pub mod sim;
pub mod tail;
pub mod wake;

pub use alarms::{AlarmEvent, AlarmRules, Alarms, Rule};
pub use events::{LiveBatch, LiveCycle, LiveEvent, LiveImage};
pub use follower::{Follower, LiveSummary};

use crate::process::ProcessRecipe;
use crate::rig::channel_map::ChannelMap;
use crate::rig::cycles::CycleOptions;
use crate::vision::batch::RecipeBook;
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;
use std::path::PathBuf;

/// How to follow: the defaults a technician gets, loadable from a TOML
/// `[follow]` section.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct FollowConfig {
    /// Raw samples kept at full rate (s of log time) for the Signals pane.
    pub window_s: f64,
    /// Buckets of the min/max history of the whole shift, per signal.
    pub history_buckets: usize,
    /// Seconds between polls: the only trigger with `notify = false`
    /// (network shares), a safety net with file-system events.
    pub poll_s: f64,
    /// Use file-system events (inotify …) to poll as soon as data is written.
    pub notify: bool,
    /// Debounce of file-system events (ms).
    pub debounce_ms: u64,
    /// Cycles kept with their grids for the Overlay and Line panes.
    pub recent_cycles: usize,
    /// Images kept with their pictures for the Vision pane.
    pub recent_images: usize,
    /// A log that stopped growing while a newer one is followed is closed
    /// after this many seconds.
    pub rotate_grace_s: f64,
    /// Cycles on which missing sensor zeros are estimated before they are held.
    pub warmup_cycles: usize,
}

impl Default for FollowConfig {
    fn default() -> Self {
        FollowConfig {
            window_s: 60.0,
            history_buckets: 4096,
            poll_s: 1.0,
            notify: true,
            debounce_ms: 30,
            recent_cycles: 200,
            recent_images: 20,
            rotate_grace_s: 3.0,
            warmup_cycles: 10,
        }
    }
}

impl FollowConfig {
    /// Reads the `[follow]` table of a TOML document (the whole document
    /// when it has no such table).
    pub fn from_toml(text: &str) -> Result<Self, String> {
        let v: toml::Table = text.parse().map_err(|e: toml::de::Error| e.to_string())?;
        let t = match v.get("follow") {
            Some(a) => a.clone(),
            None => toml::Value::Table(v),
        };
        t.try_into().map_err(|e: toml::de::Error| e.to_string())
    }
}

/// A duration as typed: `250ms`, `2s`, `10m`, `8h`, or seconds.
pub fn parse_duration(s: &str) -> Result<f64, String> {
    let s = s.trim();
    let (num, mul) = if let Some(x) = s.strip_suffix("ms") {
        (x, 1e-3)
    } else if let Some(x) = s.strip_suffix('s') {
        (x, 1.0)
    } else if let Some(x) = s.strip_suffix('m') {
        (x, 60.0)
    } else if let Some(x) = s.strip_suffix('h') {
        (x, 3600.0)
    } else {
        (s, 1.0)
    };
    match num.trim().parse::<f64>() {
        Ok(v) if v.is_finite() && v >= 0.0 && v * mul <= 1e7 => Ok(v * mul),
        _ => Err(format!("`{s}` is not a duration (e.g. 250ms, 2s, 10m, 8h)")),
    }
}

/// What to follow and how to judge it.
#[derive(Debug, Clone, Default)]
pub struct FollowInputs {
    /// Logs (`.mcap`, followed while written; a file not there yet is
    /// waited for) and folders (images and new logs).
    pub paths: Vec<PathBuf>,
    pub recipes: RecipeBook,
    pub process: Option<ProcessRecipe>,
    /// Learn the process recipe's envelopes on the first N good cycles.
    pub learn: usize,
    pub channel_map: ChannelMap,
    pub cycle_options: CycleOptions,
    pub meta_overrides: BTreeMap<String, String>,
    pub config: FollowConfig,
    pub alarms: AlarmRules,
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn durations_and_config() {
        assert_eq!(parse_duration("2s").unwrap(), 2.0);
        assert_eq!(parse_duration("250ms").unwrap(), 0.25);
        assert_eq!(parse_duration("8h").unwrap(), 28800.0);
        assert_eq!(parse_duration("1.5").unwrap(), 1.5);
        assert!(parse_duration("-1s").is_err() && parse_duration("x").is_err());
        let c = FollowConfig::from_toml("[follow]\nwindow_s = 600.0\nnotify = false\n").unwrap();
        assert_eq!(c.window_s, 600.0);
        assert!(!c.notify);
        assert!(FollowConfig::from_toml("[follow]\nwindow = 1\n").is_err());
        let back = toml::to_string(&FollowConfig::default()).unwrap();
        assert_eq!(
            FollowConfig::from_toml(&back).unwrap(),
            FollowConfig::default()
        );
    }
}
