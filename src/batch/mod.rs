//! Headless panes and batch scripts.
//!
//! - [`render_text`]: a pane exactly as the TUI draws it (same view model,
//!   same drawing code, into an off-screen buffer), as text.
//! - [`export`]: a pane's view model as JSON, CSV or PNG (charts through
//!   [`crate::plot`], or the connector image for Vision).
//! - [`script`]: `pinsight batch SCRIPT.toml` — load, set, run, export and
//!   check steps, with a summary of every check and a failing exit code.
//! - [`figure`]: reads a figure of a view model by a dotted path.

pub mod export_path;
pub mod report;
pub mod script;

use crate::panes::{self, PaneId, PaneState, PaneView, Session};
use crate::tui::draw::{Chrome, ImageCache};
use crate::tui::theme::Theme;
use serde_json::Value;
use std::path::Path;

/// Output formats of `render` and `export` steps.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Format {
    Text,
    Json,
    Csv,
    Png,
}

impl Format {
    pub fn parse(s: &str) -> Option<Self> {
        match s.trim().to_ascii_lowercase().as_str() {
            "text" | "txt" => Some(Format::Text),
            "json" => Some(Format::Json),
            "csv" => Some(Format::Csv),
            "png" => Some(Format::Png),
            _ => None,
        }
    }
    /// From a file name's extension.
    pub fn from_path(p: &Path) -> Option<Self> {
        p.extension().and_then(|e| e.to_str()).and_then(Self::parse)
    }
}

/// Parses `WxH` (e.g. `120x40`); each side at least 20×6 and at most 1000.
pub fn parse_size(s: &str) -> Result<(u16, u16), String> {
    let (w, h) = s
        .trim()
        .split_once(['x', 'X', '×'])
        .ok_or_else(|| format!("size `{s}`: expected WIDTHxHEIGHT, e.g. 120x40"))?;
    // Parsed wide, so that a large number is "too large", not "not a number".
    let num = |x: &str, what: &str| -> Result<u64, String> {
        x.trim()
            .parse::<u64>()
            .map_err(|_| format!("size `{s}`: {what} `{}` is not a whole number", x.trim()))
    };
    let (w, h) = (num(w, "width")?, num(h, "height")?);
    if !(20..=1000).contains(&w) || !(6..=1000).contains(&h) {
        return Err(format!(
            "size `{s}`: allowed 20–1000 columns and 6–1000 rows"
        ));
    }
    let (w, h) = (w as u16, h as u16);
    Ok((w, h))
}

/// The pane drawn as the TUI draws it, in a `width`×`height` screen, as
/// text. Images are drawn with half-blocks (deterministic).
pub fn render_text(session: &Session, pane: PaneId, ui: &PaneState) -> String {
    let view = panes::view(pane, session, ui);
    render_view_text(session, &view, ui.width, ui.height)
}

/// A computed view drawn as text.
pub fn render_view_text(session: &Session, view: &PaneView, width: u16, height: u16) -> String {
    let chrome = Chrome::new(view.pane(), session.title.clone());
    let mut img = ImageCache::halfblocks();
    let buf = crate::tui::render_view(&chrome, view, width, height, &Theme::ansi16(), &mut img);
    crate::tui::buffer_text(&buf)
}

/// Writes a view in a format. Text needs the session (for the chrome) and
/// the screen size.
pub fn export(
    session: &Session,
    view: &PaneView,
    format: Format,
    size: (u16, u16),
    path: &Path,
) -> Result<String, String> {
    let write = |bytes: &[u8]| crate::output::write_file(path, bytes).map_err(|e| e.to_string());
    match format {
        Format::Text => {
            write(render_view_text(session, view, size.0, size.1).as_bytes())?;
            Ok(format!("text {}×{}", size.0, size.1))
        }
        Format::Json => {
            let text =
                serde_json::to_string_pretty(&view.to_json()).map_err(|e| format!("JSON: {e}"))?;
            write(text.as_bytes())?;
            Ok("JSON view model".into())
        }
        Format::Csv => {
            write(view.to_csv().as_bytes())?;
            Ok("CSV table".into())
        }
        Format::Png => {
            let bytes = png(view)?;
            write(&bytes)?;
            Ok("PNG".into())
        }
    }
}

/// The view as PNG: its charts, or the (annotated) connector image.
pub fn png(view: &PaneView) -> Result<Vec<u8>, String> {
    if let PaneView::Vision(v) = view {
        let img = v
            .image
            .as_ref()
            .ok_or_else(|| "the Vision pane has no image to write".to_string())?;
        let mut out = std::io::Cursor::new(Vec::new());
        img.write_to(&mut out, image::ImageFormat::Png)
            .map_err(|e| format!("PNG: {e}"))?;
        return Ok(out.into_inner());
    }
    let panels = view.panels();
    if panels.is_empty() {
        return Err(format!(
            "the {} pane has no chart to draw as PNG (use json, csv or text)",
            view.pane().name()
        ));
    }
    let cols = if panels.len() >= 4 { 2 } else { 1 };
    let rows = panels.len().div_ceil(cols) as u32;
    let (w, h) = (1000 * cols as u32, (360 * rows).max(500));
    crate::plot::render_png(&panels, cols, w, h).map_err(|e| e.to_string())
}

/// A figure of a view model by a dotted path: `summary.disp_dev_mean_mm`,
/// `rows.3.value`, `cycles[2].stroke_rms_mm`, `files.len` (the length of an
/// array or object when it has no field `len`).
pub fn figure<'a>(json: &'a Value, path: &str) -> Result<Figure<'a>, String> {
    let mut cur = json;
    let norm = path.replace('[', ".").replace(']', "");
    let parts: Vec<&str> = norm.split('.').filter(|s| !s.is_empty()).collect();
    if parts.is_empty() {
        return Err("empty figure path".into());
    }
    for (i, part) in parts.iter().enumerate() {
        let here = parts[..i].join(".");
        let next = match cur {
            Value::Object(m) => match m.get(*part) {
                Some(v) => v,
                None if *part == "len" && i + 1 == parts.len() => {
                    return Ok(Figure::Len(m.len()));
                }
                None => {
                    let keys: Vec<&str> = m.keys().map(|k| k.as_str()).collect();
                    return Err(format!(
                        "no `{part}` in `{}` (has: {})",
                        if here.is_empty() { "the view" } else { &here },
                        keys.join(", ")
                    ));
                }
            },
            Value::Array(a) => {
                if *part == "len" && i + 1 == parts.len() {
                    return Ok(Figure::Len(a.len()));
                }
                let k: usize = part.parse().map_err(|_| {
                    format!(
                        "`{here}` is a list: use an index (0–{}) or len",
                        a.len().saturating_sub(1)
                    )
                })?;
                a.get(k)
                    .ok_or_else(|| format!("`{here}` has {} entries, no index {k}", a.len()))?
            }
            other => {
                return Err(format!(
                    "`{here}` is {} and has no `{part}`",
                    kind_of(other)
                ));
            }
        };
        cur = next;
    }
    Ok(Figure::Value(cur))
}

/// What a figure path found.
#[derive(Debug, Clone, PartialEq)]
pub enum Figure<'a> {
    Value(&'a Value),
    Len(usize),
}

impl Figure<'_> {
    pub fn as_f64(&self) -> Option<f64> {
        match self {
            Figure::Value(v) => match v {
                Value::Number(n) => n.as_f64(),
                Value::Bool(b) => Some(f64::from(u8::from(*b))),
                Value::String(s) => s.trim().parse().ok(),
                _ => None,
            },
            Figure::Len(n) => Some(*n as f64),
        }
    }
    pub fn show(&self) -> String {
        match self {
            Figure::Value(Value::String(s)) => s.clone(),
            Figure::Value(Value::Number(n)) => {
                let x = n.as_f64().unwrap_or(f64::NAN);
                crate::tui::widgets::format_value(x)
            }
            Figure::Value(v) => {
                let s = v.to_string();
                if s.len() > 40 {
                    format!(
                        "{}…",
                        &s[..s.char_indices().nth(39).map(|c| c.0).unwrap_or(s.len())]
                    )
                } else {
                    s
                }
            }
            Figure::Len(n) => n.to_string(),
        }
    }
}

fn kind_of(v: &Value) -> &'static str {
    match v {
        Value::Null => "null (not available)",
        Value::Bool(_) => "a boolean",
        Value::Number(_) => "a number",
        Value::String(_) => "a string",
        Value::Array(_) => "a list",
        Value::Object(_) => "a table",
    }
}

/// A job run on every log of the session (batch `run overlay`, `run
/// calibrate`): `job` gives each log's detail line, its error, or nothing
/// (the log was not run); an error when no log is loaded or any failed,
/// every log's line either way.
fn each_log(
    session: &mut Session,
    mut job: impl FnMut(&mut Session, usize) -> Option<Result<String, String>>,
) -> Result<String, String> {
    if session.logs.is_empty() {
        return Err("no rig log loaded".into());
    }
    let mut msgs = Vec::new();
    let mut failed = false;
    for i in 0..session.logs.len() {
        match job(session, i) {
            Some(Ok(m)) => msgs.push(m),
            Some(Err(e)) => {
                failed = true;
                msgs.push(e);
            }
            None => {}
        }
    }
    if failed {
        Err(msgs.join("; "))
    } else {
        Ok(msgs.join("; "))
    }
}

/// A batch `run overlay` step: every log of the session compared with the
/// model; the detail line per log (cycles, stroke RMS residual, time).
pub fn run_overlay_step(session: &mut Session) -> Result<String, String> {
    each_log(session, |s, i| {
        s.run_overlay_now(i);
        let r = s.overlay_of(i)?;
        Some(match &r.report {
            Ok(rep) => Ok(format!(
                "{}: {} cycles, stroke RMS {:.4} mm, {:.0} ms",
                s.logs[i].path, rep.run.cycles, rep.run.stroke_rms_err_mm, r.wall_ms
            )),
            Err(e) => Err(e.clone()),
        })
    })
}

/// A batch `run calibrate` step: every log of the session calibrated
/// against the model (as `pinsight calibrate LOG` with no options; the
/// Overlay pane shows the result); the detail line per log (clearance ±
/// U95, standoff, residual of the mean stroke before → after, time).
pub fn run_calibrate_step(
    session: &mut Session,
    progress: &crate::progress::Progress,
) -> Result<String, String> {
    each_log(session, |s, i| {
        s.run_calibration_with(i, progress);
        let r = s.calibration_of(i)?;
        let rep = match &r.report {
            Ok(rep) => rep,
            Err(e) => return Some(Err(e.clone())),
        };
        let est = |name: &str| {
            rep.estimates
                .iter()
                .find(|e| e.name == name)
                .map_or("–".to_string(), |e| {
                    format!("{:.4} ± {:.4}", e.value, e.u95)
                })
        };
        Some(Ok(format!(
            "{}: clearance {} mm, standoff {} mm, stroke mean RMS {:.4} → {:.4} mm, {:.0} ms",
            s.logs[i].path,
            est("clearance"),
            est("standoff"),
            rep.before.stroke_mean_rms_mm,
            rep.after.stroke_mean_rms_mm,
            r.wall_ms
        )))
    })
}

/// A batch `run trend` step: the wear trend over the session's logs; the
/// detail line (logs, calibrations, each head's verdict), an error when a
/// log was left out or the trend could not run.
pub fn run_trend_step(
    session: &mut Session,
    progress: &crate::progress::Progress,
) -> Result<String, String> {
    session.run_trend_with(progress);
    let t = match &session.trend {
        Some(Ok(t)) => t,
        Some(Err(e)) => return Err(e.clone()),
        None => return Err("the trend did not run".into()),
    };
    let heads: Vec<String> = t
        .heads
        .iter()
        .map(|h| format!("{}: {}", h.rig, h.verdict))
        .collect();
    let d = format!(
        "{} log(s), {} calibrated; {}",
        t.logs,
        t.calibrated,
        heads.join("; ")
    );
    if t.errors.is_empty() {
        return Ok(d);
    }
    let left: Vec<String> = t
        .errors
        .iter()
        .map(|e| format!("{}: {}", e.file, e.error))
        .collect();
    Err(format!("{d}; left out: {}", left.join("; ")))
}

#[cfg(test)]
mod tests {
    use super::*;
    use serde_json::json;

    #[test]
    fn figure_paths() {
        let v =
            json!({"summary": {"x": 1.5, "name": "a"}, "rows": [{"v": 2}, {"v": 3}], "n": null});
        assert_eq!(figure(&v, "summary.x").unwrap().as_f64(), Some(1.5));
        assert_eq!(figure(&v, "rows.1.v").unwrap().as_f64(), Some(3.0));
        assert_eq!(figure(&v, "rows[0].v").unwrap().as_f64(), Some(2.0));
        assert_eq!(figure(&v, "rows.len").unwrap().as_f64(), Some(2.0));
        assert_eq!(figure(&v, "summary.len").unwrap().as_f64(), Some(2.0));
        let e = figure(&v, "summary.y").unwrap_err();
        assert!(
            e.contains("has: name, x") || e.contains("has: x, name"),
            "{e}"
        );
        assert!(figure(&v, "rows.7.v").unwrap_err().contains("2 entries"));
        assert!(figure(&v, "n.x").unwrap_err().contains("null"));
        assert!(figure(&v, "").is_err());
        assert_eq!(parse_size("80x24").unwrap(), (80, 24));
        assert!(parse_size("8x24").is_err());
        assert!(parse_size("80").is_err());
    }
}
