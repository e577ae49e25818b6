//! View models: one pure function per pane from the session's state (and
//! the pane's UI state) to plain serialisable data.
//!
//! The TUI ([`crate::tui`]) draws these views and nothing else; `pinsight
//! render` and `pinsight batch` ([`crate::batch`]) compute the same views and
//! print them through the same drawing code, or write them as JSON / CSV /
//! PNG. So a figure a batch check reads is the figure the technician sees.
//!
//! | pane | module | data |
//! |---|---|---|
//! | Session | [`session_pane`] | files opened, their metadata, parameters in force, load errors |
//! | Signals | [`signals`] | a log's channels (or the prediction), decimated per column |
//! | Overlay | [`overlay`] | measured vs predicted per cycle, fidelity level and why |
//! | Model | [`model`] | every parameter, editable; level; the latest run's figures |
//! | Study | [`study`] | the paper's sweep as curves and bars |
//! | Vision | [`vision`] | a connector image with pins by verdict, per-pin table |
//! | Yield | [`yields`] | batch yield, confidence interval, Pareto, worst pins |
//! | Methods | [`methods`] | work–precision and stability charts |
//! | Line | [`line`] | process monitor: cycles OK/NOK with reasons, the press curve against its objects, SPC with Cpk bands, run-rule alarms, process × vision |
//! | Trend | [`trend`] | wear trend: a head's clearance ± U95 per log, the fitted wear, the limit and the forecast |

pub mod chart;
pub mod demo;
pub mod line;
pub mod live;
pub mod live_state;
pub mod methods;
pub mod model;
pub mod overlay;
pub mod session;
pub mod session_pane;
pub mod signals;
pub mod study;
pub mod table;
pub mod trend;
pub mod vision;
pub mod yields;

use crate::plot::Panel;
use serde::Serialize;
pub use session::Session;

/// The panes, in tab order (number keys 1–9).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum PaneId {
    Session,
    Signals,
    Overlay,
    Model,
    Study,
    Vision,
    Yield,
    Methods,
    Line,
    Trend,
}

impl PaneId {
    pub const ALL: [PaneId; 10] = [
        PaneId::Session,
        PaneId::Signals,
        PaneId::Overlay,
        PaneId::Model,
        PaneId::Study,
        PaneId::Vision,
        PaneId::Yield,
        PaneId::Methods,
        PaneId::Line,
        PaneId::Trend,
    ];

    pub fn name(self) -> &'static str {
        match self {
            PaneId::Session => "session",
            PaneId::Signals => "signals",
            PaneId::Overlay => "overlay",
            PaneId::Model => "model",
            PaneId::Study => "study",
            PaneId::Vision => "vision",
            PaneId::Yield => "yield",
            PaneId::Methods => "methods",
            PaneId::Line => "line",
            PaneId::Trend => "trend",
        }
    }

    pub fn title(self) -> &'static str {
        match self {
            PaneId::Session => "Session",
            PaneId::Signals => "Signals",
            PaneId::Overlay => "Overlay",
            PaneId::Model => "Model",
            PaneId::Study => "Study",
            PaneId::Vision => "Vision",
            PaneId::Yield => "Yield",
            PaneId::Methods => "Methods",
            PaneId::Line => "Line",
            PaneId::Trend => "Trend",
        }
    }

    pub fn index(self) -> usize {
        Self::ALL.iter().position(|&p| p == self).unwrap_or(0)
    }

    pub fn parse(s: &str) -> Option<Self> {
        let s = s.trim().to_ascii_lowercase();
        Self::ALL
            .into_iter()
            .find(|p| p.name() == s || (s.len() >= 3 && p.name().starts_with(&s)))
    }

    pub fn names() -> String {
        Self::ALL.map(|p| p.name()).join(", ")
    }
}

/// Per-pane UI state (what the user chose to look at), plus the size of the
/// screen the views are for. Views read it; only the TUI's `update` and
/// batch `ui` options change it.
#[derive(Debug, Clone, Serialize)]
pub struct PaneState {
    /// Screen size in cells (the views decimate series to this width).
    pub width: u16,
    pub height: u16,
    pub session: session_pane::SessionUi,
    pub signals: signals::SignalsUi,
    pub overlay: overlay::OverlayUi,
    pub model: model::ModelUi,
    pub study: study::StudyUi,
    pub vision: vision::VisionUi,
    pub yields: yields::YieldUi,
    pub methods: methods::MethodsUi,
    pub line: line::LineUi,
    pub trend: trend::TrendUi,
    /// Live mode: the views follow the newest data (Signals' window slides,
    /// Vision shows the latest connector). `F` toggles it, scrolling back
    /// pauses it, `End`/`G` resumes it.
    pub follow: bool,
}

impl PaneState {
    pub fn new(width: u16, height: u16) -> Self {
        Self {
            width,
            height,
            session: Default::default(),
            signals: Default::default(),
            overlay: Default::default(),
            model: Default::default(),
            study: Default::default(),
            vision: Default::default(),
            yields: Default::default(),
            methods: Default::default(),
            line: Default::default(),
            trend: Default::default(),
            follow: true,
        }
    }

    /// Columns available to a chart drawn across `fraction` of the screen
    /// (braille: two dots per cell).
    pub fn chart_columns(&self, fraction: f64) -> usize {
        ((self.width as f64 * fraction).max(8.0) as usize) * 2
    }

    /// Sets a UI option by name (`pinsight render --ui key=value`, batch
    /// `ui = { … }`): `signals.t0`, `study.factor`, `vision.image` … Returns
    /// an error naming the allowed keys.
    pub fn set_option(&mut self, key: &str, value: &str) -> Result<(), String> {
        let (pane, k) = key.split_once('.').unwrap_or(("", key));
        let res = match pane {
            "session" => self.session.set(k, value),
            "signals" => self.signals.set(k, value),
            "overlay" => self.overlay.set(k, value),
            "model" => self.model.set(k, value),
            "study" => self.study.set(k, value),
            "vision" => self.vision.set(k, value),
            "yield" => self.yields.set(k, value),
            "methods" => self.methods.set(k, value),
            "line" => self.line.set(k, value),
            "trend" => self.trend.set(k, value),
            _ => Err("an option is named pane.key".to_string()),
        };
        res.map_err(|e| {
            format!(
                "UI option `{key}={value}`: {e} (options: {})",
                UI_OPTIONS.join(", ")
            )
        })
    }
}

/// Every UI option [`PaneState::set_option`] accepts.
pub const UI_OPTIONS: &[&str] = &[
    "session.selected",
    "signals.t0",
    "signals.t1",
    "signals.cursor",
    "signals.hide",
    "signals.channel",
    "overlay.cycle",
    "overlay.log",
    "overlay.calibrate",
    "model.selected",
    "study.factor",
    "study.quantity",
    "vision.image",
    "vision.pin",
    "yield.selected",
    "methods.chart",
    "line.cycle",
    "line.log",
    "trend.head",
];

pub(crate) fn parse_f64(v: &str) -> Result<f64, String> {
    v.trim()
        .parse::<f64>()
        .ok()
        .filter(|x| x.is_finite())
        .ok_or_else(|| format!("`{v}` is not a number"))
}

pub(crate) fn parse_bool(v: &str) -> Result<bool, String> {
    match v.trim().to_ascii_lowercase().as_str() {
        "yes" | "true" | "on" | "1" => Ok(true),
        "no" | "false" | "off" | "0" => Ok(false),
        _ => Err(format!("`{v}` is not yes or no")),
    }
}

pub(crate) fn parse_usize(v: &str) -> Result<usize, String> {
    v.trim()
        .parse::<usize>()
        .map_err(|_| format!("`{v}` is not a non-negative integer"))
}

/// A pane's view, whichever pane it is. (One is built per frame; boxing
/// the larger variants would buy nothing.)
#[allow(clippy::large_enum_variant)]
#[derive(Debug, Clone, Serialize)]
#[serde(untagged)]
pub enum PaneView {
    Session(session_pane::SessionView),
    Signals(signals::SignalsView),
    Overlay(overlay::OverlayView),
    Model(model::ModelView),
    Study(study::StudyView),
    Vision(vision::VisionView),
    Yield(yields::YieldView),
    Methods(methods::MethodsView),
    Line(line::LineView),
    Trend(trend::TrendView),
}

impl PaneView {
    pub fn pane(&self) -> PaneId {
        match self {
            PaneView::Session(_) => PaneId::Session,
            PaneView::Signals(_) => PaneId::Signals,
            PaneView::Overlay(_) => PaneId::Overlay,
            PaneView::Model(_) => PaneId::Model,
            PaneView::Study(_) => PaneId::Study,
            PaneView::Vision(_) => PaneId::Vision,
            PaneView::Yield(_) => PaneId::Yield,
            PaneView::Methods(_) => PaneId::Methods,
            PaneView::Line(_) => PaneId::Line,
            PaneView::Trend(_) => PaneId::Trend,
        }
    }

    /// The view as JSON (what `--format json` writes and batch checks read).
    pub fn to_json(&self) -> serde_json::Value {
        serde_json::to_value(self).unwrap_or(serde_json::Value::Null)
    }

    /// The view's main table or series as CSV.
    pub fn to_csv(&self) -> String {
        match self {
            PaneView::Session(v) => v.to_csv(),
            PaneView::Signals(v) => v.to_csv(),
            PaneView::Overlay(v) => v.to_csv(),
            PaneView::Model(v) => v.to_csv(),
            PaneView::Study(v) => v.to_csv(),
            PaneView::Vision(v) => v.to_csv(),
            PaneView::Yield(v) => v.to_csv(),
            PaneView::Methods(v) => v.to_csv(),
            PaneView::Line(v) => v.to_csv(),
            PaneView::Trend(v) => v.to_csv(),
        }
    }

    /// The view's charts as PNG panels (empty for a pane without charts).
    pub fn panels(&self) -> Vec<Panel> {
        match self {
            PaneView::Session(_) => Vec::new(),
            PaneView::Signals(v) => v.charts.iter().map(|c| c.to_panel()).collect(),
            PaneView::Overlay(v) => v.charts().iter().map(|c| c.to_panel()).collect(),
            PaneView::Model(v) => v.chart.iter().map(|c| c.to_panel()).collect(),
            PaneView::Study(v) => v.panels(),
            PaneView::Vision(_) => Vec::new(),
            PaneView::Yield(v) => v.panels(),
            PaneView::Methods(v) => v.panels.clone(),
            PaneView::Line(v) => v.chart.iter().map(|c| c.to_panel()).collect(),
            PaneView::Trend(v) => v.report.as_ref().map_or_else(Vec::new, |r| r.panels()),
        }
    }
}

/// Computes a pane's view.
pub fn view(pane: PaneId, session: &Session, ui: &PaneState) -> PaneView {
    match pane {
        PaneId::Session => PaneView::Session(session_pane::view(session, ui)),
        PaneId::Signals => PaneView::Signals(signals::view(session, ui)),
        PaneId::Overlay => PaneView::Overlay(overlay::view(session, ui)),
        PaneId::Model => PaneView::Model(model::view(session, ui)),
        PaneId::Study => PaneView::Study(study::view(session, ui)),
        PaneId::Vision => PaneView::Vision(vision::view(session, ui)),
        PaneId::Yield => PaneView::Yield(yields::view(session, ui)),
        PaneId::Methods => PaneView::Methods(methods::view(session, ui)),
        PaneId::Line => PaneView::Line(line::view(session, ui)),
        PaneId::Trend => PaneView::Trend(trend::view(session, ui)),
    }
}

/// CSV quoting of one field.
pub(crate) fn csv_field(s: &str) -> String {
    if s.contains([',', '"', '\n']) {
        format!("\"{}\"", s.replace('"', "\"\""))
    } else {
        s.to_string()
    }
}

/// A CSV document from a header and rows.
pub(crate) fn csv_table<R: AsRef<[String]>>(
    header: &[&str],
    rows: impl IntoIterator<Item = R>,
) -> String {
    let mut out = header.join(",");
    out.push('\n');
    for r in rows {
        let line: Vec<String> = r.as_ref().iter().map(|f| csv_field(f)).collect();
        out.push_str(&line.join(","));
        out.push('\n');
    }
    out
}

/// A number for CSV cells: empty for None, else `{:.prec$}`.
pub(crate) fn csv_num(x: Option<f64>, prec: usize) -> String {
    x.map(|v| format!("{v:.prec$}")).unwrap_or_default()
}

/// A number for tables: empty for NaN/None, else `{:.prec$}`.
pub(crate) fn fmt_opt(x: Option<f64>, prec: usize) -> String {
    match x {
        Some(v) if v.is_finite() => format!("{v:.prec$}"),
        _ => "–".into(),
    }
}
