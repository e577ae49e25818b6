//! `y`: the selected row or figure of the current pane, copied to the
//! clipboard with OSC 52 (`ESC ] 52 ; c ; base64 BEL`), which terminals
//! forward from a remote shell, so copying works over SSH. tmux passes it
//! on with `set -g set-clipboard on` (its buffer and the outer terminal).
//!
//! The text comes from the pane's view model, never from screen cells: a
//! number copied has its full precision and a label is never the cut or
//! abbreviated form drawn at 80 columns. It is tab-separated — a header
//! line and the row (or several rows for a figure that is a table) — so it
//! pastes into a spreadsheet as cells and into a message as text. A table's
//! row is copied with the columns of the pane's CSV export
//! ([`crate::panes::table::Cells`]), numbers at full precision.

use crate::panes::PaneView;
use crate::panes::table::Cells;
use base64::Engine;

/// What `y` copies.
#[derive(Debug, Clone, PartialEq)]
pub struct Copied {
    /// A short name for the status line (`pin 1,5`, `cycle 3`).
    pub what: String,
    /// The text copied (tab-separated lines).
    pub text: String,
}

fn num(x: Option<f64>) -> String {
    match x {
        Some(v) if v.is_finite() => v.to_string(),
        _ => String::new(),
    }
}

fn tsv(header: &[&str], rows: &[Vec<String>]) -> String {
    let clean = |s: &str| s.replace(['\t', '\n', '\r'], " ");
    let mut out = header.join("\t");
    for r in rows {
        out.push('\n');
        out.push_str(&r.iter().map(|c| clean(c)).collect::<Vec<_>>().join("\t"));
    }
    out.push('\n');
    out
}

/// One row of a pane's table with the export's header (full precision),
/// after `context` columns naming where it comes from.
fn row<R: Cells>(what: String, r: &R, context: &[(&str, String)]) -> Copied {
    let mut header: Vec<&str> = context.iter().map(|c| c.0).collect();
    header.extend_from_slice(R::HEADER);
    let mut cells: Vec<String> = context.iter().map(|c| c.1.clone()).collect();
    cells.extend(r.cells(&num));
    Copied {
        what,
        text: tsv(&header, &[cells]),
    }
}

/// All the rows of a pane's table with the export's header (full precision).
fn rows<R: Cells>(all: &[R]) -> String {
    let cells: Vec<Vec<String>> = all.iter().map(|r| r.cells(&num)).collect();
    tsv(R::HEADER, &cells)
}

/// The selected row or figure of a view, or None when it has nothing
/// selected (an empty pane, no run yet).
pub fn selection(view: &PaneView) -> Option<Copied> {
    let one = |what: String, header: &[&str], row: Vec<String>| Copied {
        what,
        text: tsv(header, &[row]),
    };
    match view {
        PaneView::Session(v) => {
            let f = v.files.get(v.selected)?;
            Some(row(f.path.clone(), f, &[]))
        }
        PaneView::Signals(v) => {
            let c = v.channels.iter().find(|c| c.selected)?;
            Some(one(
                format!("{} at {} s", c.name, v.cursor),
                &[
                    "channel",
                    "unit",
                    "time_s",
                    "value",
                    "min_in_view",
                    "max_in_view",
                    "source",
                ],
                vec![
                    c.name.clone(),
                    c.unit.clone(),
                    v.cursor.to_string(),
                    num(c.at_cursor),
                    num(c.min),
                    num(c.max),
                    v.source.clone(),
                ],
            ))
        }
        PaneView::Overlay(v) => match v.selected.and_then(|i| v.cycles.get(i)) {
            Some(c) => Some(row(format!("cycle {}", c.index), c, &[])),
            None if !v.figures.is_empty() => Some(Copied {
                what: format!("run figures ({})", v.showing),
                text: tsv(
                    &["figure", "value"],
                    &v.figures
                        .iter()
                        .map(|(k, x)| vec![k.clone(), num(Some(*x))])
                        .collect::<Vec<_>>(),
                ),
            }),
            None => None,
        },
        PaneView::Model(v) => {
            let r = v.rows.get(v.selected)?;
            Some(one(
                r.key.clone(),
                &["key", "value", "allowed"],
                vec![r.key.clone(), r.value.clone(), r.range.clone()],
            ))
        }
        PaneView::Study(v) => {
            if v.line.is_empty() {
                return None;
            }
            Some(Copied {
                what: format!("the study by {} ({} cases)", v.factor, v.line.len()),
                text: rows(&v.line),
            })
        }
        PaneView::Vision(v) => {
            let p = v.pins.get(v.selected)?;
            let image = v.name.clone().unwrap_or_default();
            Some(row(
                format!("pin {},{}", p.row, p.col),
                p,
                &[("image", image)],
            ))
        }
        PaneView::Yield(v) => {
            let it = v.items.get(v.selected)?;
            Some(one(
                it.name.clone(),
                &["image", "result", "part", "note"],
                vec![
                    it.name.clone(),
                    it.status.clone(),
                    it.part_number.clone().unwrap_or_default(),
                    it.note.clone(),
                ],
            ))
        }
        PaneView::Methods(v) => {
            let c = v.chart.as_ref()?;
            let rows: Vec<Vec<String>> = c
                .series
                .iter()
                .flat_map(|s| {
                    s.points
                        .iter()
                        .filter(|p| p.0.is_finite() && p.1.is_finite())
                        .map(|p| {
                            let un = |v: f64, log: bool| if log { 10f64.powf(v) } else { v };
                            vec![
                                s.name.clone(),
                                un(p.0, c.log_x).to_string(),
                                un(p.1, c.log_y).to_string(),
                            ]
                        })
                })
                .collect();
            Some(Copied {
                what: format!("chart “{}” ({} points)", c.title, rows.len()),
                text: tsv(&["series", &c.x_label, &c.y_label], &rows),
            })
        }
        PaneView::Line(v) => {
            let c = v.cycles.get(v.selected)?;
            Some(one(
                format!("cycle {}", c.index),
                &["log", "cycle", "status", "reasons"],
                vec![
                    v.log.clone().unwrap_or_default(),
                    c.index.to_string(),
                    c.status.to_string(),
                    c.reasons.join("; "),
                ],
            ))
        }
        PaneView::Trend(v) => {
            let rig = v.rig.clone()?;
            let mut rows = vec![vec!["head".to_string(), rig.clone()]];
            if let Some(vd) = &v.verdict {
                rows.push(vec!["verdict".into(), vd.clone()]);
            }
            rows.extend(v.facts.iter().map(|f| vec!["fact".into(), f.clone()]));
            if let Some(d) = v.days_to_limit {
                rows.push(vec!["days_to_limit".into(), d.to_string()]);
            }
            Some(Copied {
                what: format!("the trend of {rig}"),
                text: tsv(&["figure", "value"], &rows),
            })
        }
    }
}

/// The OSC 52 sequence that puts `text` on the system clipboard.
pub fn osc52(text: &str) -> String {
    let b64 = base64::engine::general_purpose::STANDARD.encode(text.as_bytes());
    format!("\x1b]52;c;{b64}\x07")
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::panes::model::{ModelView, ParamRow};

    #[test]
    fn osc52_is_base64_of_the_text() {
        assert_eq!(osc52("hi\tthere\n"), "\x1b]52;c;aGkJdGhlcmUK\x07");
        assert_eq!(osc52(""), "\x1b]52;c;\x07");
    }

    #[test]
    fn the_selected_row_with_a_header() {
        let mut v: ModelView = crate::panes::model::view(
            &crate::panes::Session::default(),
            &crate::panes::PaneState::new(80, 24),
        );
        v.rows = vec![
            ParamRow {
                key: "r_mm".into(),
                value: "8".into(),
                range: "0.1 … 1000 mm".into(),
                group: String::new(),
                help: String::new(),
                changed: false,
            },
            ParamRow {
                key: "clearance_mm".into(),
                value: "0.1\t".into(),
                range: "0 … 5 mm".into(),
                group: String::new(),
                help: String::new(),
                changed: false,
            },
        ];
        v.selected = 1;
        let c = selection(&PaneView::Model(v)).unwrap();
        assert_eq!(c.what, "clearance_mm");
        assert_eq!(
            c.text,
            "key\tvalue\tallowed\nclearance_mm\t0.1 \t0 … 5 mm\n"
        );
    }
}
