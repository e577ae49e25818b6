//! The Yield pane: the batch's yield with its confidence interval, the
//! Pareto of defects, yield by speed and lot, and the worst pins.

use super::PaneState;
use super::session::Session;
use crate::plot::Panel;
use serde::Serialize;

/// UI state of the Yield pane.
#[derive(Debug, Clone, Default, Serialize)]
pub struct YieldUi {
    pub selected: usize,
}

impl YieldUi {
    pub fn set(&mut self, k: &str, _v: &str) -> Result<(), String> {
        Err(format!("no option `{k}`"))
    }
}

/// The Yield pane's view.
#[derive(Debug, Clone, Serialize)]
pub struct YieldView {
    pub images: usize,
    pub message: Option<String>,
}

impl YieldView {
    pub fn to_csv(&self) -> String {
        "group,inspected,passed,yield\n".into()
    }
    pub fn panels(&self) -> Vec<Panel> {
        Vec::new()
    }
}

pub fn view(s: &Session, _ui: &PaneState) -> YieldView {
    YieldView {
        images: s.images.len(),
        message: Some(
            "not available yet: connector inspection needs the vision module (not on main yet)"
                .into(),
        ),
    }
}
