//! The Session pane: the files loaded, their metadata, the recipes and
//! parameter files in force, and the errors found while loading.

use super::session::{FileStatus, Session};
use super::{PaneState, parse_usize};
use serde::Serialize;

/// UI state: the selected file row.
#[derive(Debug, Clone, Default, Serialize)]
pub struct SessionUi {
    pub selected: usize,
}

impl SessionUi {
    pub fn set(&mut self, k: &str, v: &str) -> Result<(), String> {
        match k {
            "selected" => self.selected = parse_usize(v)?,
            _ => return Err(format!("no option `{k}`")),
        }
        Ok(())
    }
}

/// One file row.
#[derive(Debug, Clone, Serialize)]
pub struct FileRow {
    pub path: String,
    pub kind: String,
    /// `loaded`, `warning`, `error` or `skipped`.
    pub status: String,
    pub detail: String,
    pub message: String,
}

impl super::table::Cells for FileRow {
    const HEADER: &'static [&'static str] = &["path", "kind", "status", "detail", "message"];
    fn cells(&self, _: &dyn Fn(Option<f64>) -> String) -> Vec<String> {
        vec![
            self.path.clone(),
            self.kind.clone(),
            self.status.clone(),
            self.detail.clone(),
            self.message.clone(),
        ]
    }
}

/// A log's metadata block.
#[derive(Debug, Clone, Serialize)]
pub struct LogMeta {
    pub path: String,
    pub source: String,
    pub duration_s: f64,
    pub channels: Vec<String>,
    pub cycles: usize,
    pub meta: Vec<(String, String)>,
}

/// The Session pane's view.
#[derive(Debug, Clone, Serialize)]
pub struct SessionView {
    pub title: String,
    pub files: Vec<FileRow>,
    pub selected: usize,
    pub logs: Vec<LogMeta>,
    pub recipes: Vec<String>,
    pub images: usize,
    pub params_source: String,
    pub preset: String,
    pub level: String,
    /// Key parameters in force, as (name, value with unit).
    pub params: Vec<(String, String)>,
    /// Load errors: (file, message).
    pub errors: Vec<(String, String)>,
    pub model_status: String,
    /// Colours and image protocol of the display.
    pub display: Option<String>,
    /// The live line: counts, raised alarms, recent events (newest first).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub live: Option<LiveView>,
}

/// The live line on the Session pane.
#[derive(Debug, Clone, Serialize)]
pub struct LiveView {
    pub status: String,
    pub following: bool,
    /// Alarm rules raised now.
    pub alarms: Vec<String>,
    pub last_alarm: Option<String>,
    /// Recent events, newest first (NOK cycles, failed connectors, alarms, findings, files).
    pub events: Vec<String>,
}

impl SessionView {
    pub fn to_csv(&self) -> String {
        super::table::csv_of(&self.files, &|_| String::new())
    }
}

pub fn view(s: &Session, ui: &PaneState) -> SessionView {
    let files: Vec<FileRow> = s
        .files
        .iter()
        .map(|f| {
            let (status, message) = match &f.status {
                FileStatus::Loaded => ("loaded", String::new()),
                FileStatus::Warning(m) => ("warning", m.clone()),
                FileStatus::Error(m) => ("error", m.clone()),
                FileStatus::Skipped(m) => ("skipped", m.clone()),
            };
            FileRow {
                path: f.path.clone(),
                kind: f.kind.name().into(),
                status: status.into(),
                detail: f.detail.clone(),
                message,
            }
        })
        .collect();
    let logs = s
        .logs
        .iter()
        .map(|l| LogMeta {
            path: l.path.clone(),
            source: l.signals.source.clone(),
            duration_s: l.signals.duration_s(),
            channels: l
                .signals
                .channels
                .iter()
                .map(|c| format!("{} ({} samples)", c.name, c.t_s.len()))
                .collect(),
            cycles: l.signals.cycles.len(),
            meta: l.signals.meta.clone(),
        })
        .collect();
    let p = &s.params;
    let params = vec![
        ("clearance".into(), format!("{} mm", p.clearance * 1e3)),
        ("motor speed".into(), format!("{} rpm", p.motor_rpm)),
        ("material".into(), p.material_name()),
        (
            "contact".into(),
            format!("{} (ce {})", p.contact_model.name(), p.restitution),
        ),
        ("standoff".into(), format!("{} mm", p.standoff * 1e3)),
    ];
    let model_status = match (&s.model, &s.model_error) {
        (_, Some(e)) => format!("model run failed: {e}"),
        (Some(m), None) => format!(
            "model: {} level ({}), {} impacts in {} revolutions",
            m.level.name(),
            m.level_reason,
            m.result.summary.n_impacts,
            m.result.summary.revs
        ),
        (None, None) => "model: not run yet".into(),
    };
    let n = files.len();
    SessionView {
        title: s.title.clone(),
        selected: if n == 0 {
            0
        } else {
            ui.session.selected.min(n - 1)
        },
        files,
        logs,
        recipes: s
            .recipes
            .iter()
            .map(|r| format!("{} ({} view) — {}", r.part_number, r.view, r.path))
            .collect(),
        images: s.images.len(),
        params_source: s.params_source.clone(),
        preset: p.preset.clone(),
        level: match s.level {
            crate::sim::LevelChoice::Auto => "auto".into(),
            crate::sim::LevelChoice::Fixed(l) => l.name().into(),
        },
        params,
        errors: s
            .load_errors()
            .into_iter()
            .map(|(a, b)| (a.to_string(), b.to_string()))
            .collect(),
        model_status,
        display: s.display.clone(),
        live: s.live.as_ref().map(|l| LiveView {
            status: l.status(s.yields.as_ref().and_then(|y| y.report.yield_frac)),
            following: ui.follow,
            alarms: l.active_alarms.iter().map(|a| a.to_string()).collect(),
            last_alarm: l.last_alarm.clone(),
            events: l.lines.iter().rev().take(50).cloned().collect(),
        }),
    }
}
