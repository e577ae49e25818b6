//! The Methods pane: work–precision and stability charts from
//! `pinsight::methods`. That module is not on main yet; the pane says so.

use super::PaneState;
use super::session::Session;
use crate::plot::Panel;
use serde::Serialize;

/// UI state of the Methods pane.
#[derive(Debug, Clone, Default, Serialize)]
pub struct MethodsUi {
    pub chart: usize,
}

/// The Methods pane's view.
#[derive(Debug, Clone, Serialize)]
pub struct MethodsView {
    pub available: bool,
    pub panels: Vec<Panel>,
    pub message: Option<String>,
}

impl MethodsView {
    pub fn to_csv(&self) -> String {
        "chart,series,x,y\n".into()
    }
}

pub fn view(_s: &Session, _ui: &PaneState) -> MethodsView {
    MethodsView {
        available: false,
        panels: Vec::new(),
        message: Some(
            "not available yet: the methods lab (pinsight::methods — work–precision, stability, fidelity tables) is not on main"
                .into(),
        ),
    }
}
