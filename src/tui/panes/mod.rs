//! Drawing of each pane's view model. Layout and styling only: every
//! number shown was computed by the pane's view function.

use super::image_cache::ImageCache;
use super::theme::Theme;
use super::widgets::{
    ChartFrame, Col, bars_lines, block, block_in, column_widths, content_widths, draw_chart,
    draw_chart_with, format_value, header_row, kv_line, lengths, message, text_block, trunc,
    trunc_left,
};
use crate::panes::PaneView;
use crate::panes::methods::MethodsView;
use crate::panes::model::ModelView;
use crate::panes::overlay::OverlayView;
use crate::panes::session_pane::SessionView;
use crate::panes::signals::{SIDE_COLS, SignalsView};
use crate::panes::study::StudyView;
use crate::panes::vision::VisionView;
use crate::panes::yields::YieldView;
use ratatui::Frame;
use ratatui::layout::{Constraint, Layout, Rect};
use ratatui::style::Modifier;
use ratatui::text::{Line, Span};
use ratatui::widgets::{Cell, Paragraph, Row, Table, TableState, Wrap};

/// Draws a pane's view into `area`.
pub fn draw_pane(f: &mut Frame, area: Rect, view: &PaneView, theme: &Theme, img: &mut ImageCache) {
    match view {
        PaneView::Session(v) => session_pane::session(f, area, v, theme),
        PaneView::Signals(v) => signals::signals(f, area, v, theme),
        PaneView::Overlay(v) => overlay::overlay(f, area, v, theme),
        PaneView::Model(v) => model::model(f, area, v, theme),
        PaneView::Study(v) => study::study(f, area, v, theme),
        PaneView::Vision(v) => vision::vision(f, area, v, theme, img),
        PaneView::Yield(v) => yields::yields(f, area, v, theme),
        PaneView::Methods(v) => methods::methods(f, area, v, theme),
        PaneView::Line(v) => line::line(f, area, v, theme),
        PaneView::Trend(v) => trend::trend(f, area, v, theme),
    }
}

pub(super) fn fmt_s(t: f64) -> String {
    format!("{t:.4} s")
}

pub(super) fn opt(x: Option<f64>) -> String {
    x.map(format_value).unwrap_or_else(|| "–".into())
}

/// A value with four significant digits (a narrow readout).
pub(super) fn sig4(x: Option<f64>) -> String {
    match x {
        Some(v) if v.is_finite() && v != 0.0 => {
            let mag = v.abs().log10().floor() as i32;
            if !(-4..6).contains(&mag) {
                format!("{v:.3e}")
            } else {
                let decimals = (3 - mag).max(0) as usize;
                format!("{v:.decimals$}")
            }
        }
        Some(0.0) => "0".into(),
        _ => "–".into(),
    }
}

// ---------------------------------------------------------------- Session

pub(super) fn opt3(x: Option<f64>) -> String {
    match x {
        Some(v) if v.is_finite() => format!("{v:+.3}"),
        _ => "–".into(),
    }
}

// ---------------------------------------------------------------- Yield, Methods

mod line;
mod methods;
mod model;
mod overlay;
mod session_pane;
mod signals;
mod study;
mod trend;
mod vision;
mod yields;
