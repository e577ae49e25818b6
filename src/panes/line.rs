//! The Line pane: the process monitor in a line engineer's terms — the
//! cycles as OK/NOK with their reasons, the selected cycle's press curve
//! against its evaluation objects, the SPC table with Cpk bands, the
//! Western Electric alarms, and (with the connectors' photographs) the
//! confusion of process NOK against vision fail.
//!
//! The monitor itself ([`crate::engine::process::monitor_session`]) runs on
//! the TUI's worker or in a batch `run monitor` step; this view only reads
//! its result from the session.

use super::PaneState;
use super::chart::{ChartView, SeriesKind, SeriesView};
use super::session::Session;
use crate::process::monitor::{Characteristic, CycleStatus, CycleVerdict, MonitorReport};
use crate::process::recipe::{Axis, ProcessRecipe};
use crate::process::report::{PIN_SPC_LISTED, band_counts, by_cpk};
use crate::process::run::{LogMonitor, MonitorRun};
use crate::process::spc::cpk_band;
use crate::process::story::{Confusion, ConnectorStory};
use crate::rig::cycles::CycleSet;
use crate::vision::batch::ItemStatus;
use serde::Serialize;

/// UI state of the Line pane: the selected cycle (row of the cycle list;
/// None: the latest) and the log.
#[derive(Debug, Clone, Default, Serialize)]
pub struct LineUi {
    pub cycle: Option<usize>,
    pub log: usize,
}

impl LineUi {
    pub fn set(&mut self, k: &str, v: &str) -> Result<(), String> {
        match k {
            "cycle" => {
                self.cycle = if v.trim() == "latest" {
                    None
                } else {
                    Some(super::parse_usize(v)?)
                }
            }
            "log" => self.log = super::parse_usize(v)?,
            _ => return Err(format!("no option `{k}`")),
        }
        Ok(())
    }
}

/// One cycle in the list.
#[derive(Debug, Clone, Serialize)]
pub struct CycleRow {
    pub index: u64,
    /// `ok`, `nok` or `not_evaluated`.
    pub status: &'static str,
    /// The failed objects with their reasons, or why not evaluated.
    pub reasons: Vec<String>,
}

/// One characteristic of the SPC table.
#[derive(Debug, Clone, Serialize)]
pub struct SpcRow {
    pub name: String,
    pub unit: &'static str,
    pub n: usize,
    pub mean: Option<f64>,
    pub sigma_within: Option<f64>,
    pub cp: Option<f64>,
    pub cpk: Option<f64>,
    pub ppk: Option<f64>,
    /// `capable` (Cpk ≥ 1.33), `adequate` (1.00–1.33), `inadequate`, or
    /// `–` when there is no Cpk (a limit missing, fewer than two values).
    pub band: &'static str,
    pub alarms: usize,
}

/// The Line pane's view.
#[derive(Debug, Clone, Serialize)]
pub struct LineView {
    pub part_number: Option<String>,
    pub log: Option<String>,
    pub logs: usize,
    pub ok: usize,
    pub nok: usize,
    pub not_evaluated: usize,
    /// NOK / evaluated cycles.
    pub nok_fraction: Option<f64>,
    pub cycles: Vec<CycleRow>,
    /// Row of [`LineView::cycles`] shown in the chart.
    pub selected: usize,
    /// The selected cycle's force against its objects' x axis.
    pub chart: Option<ChartView>,
    pub spc: Vec<SpcRow>,
    /// The pins' positions: the characteristics with the lowest Cpk (up to
    /// [`crate::process::report::PIN_SPC_LISTED`]), and how many pin
    /// characteristics fall in each band.
    pub pin_spc: Vec<SpcRow>,
    pub pin_summary: Option<String>,
    /// The selected cycle's connector: its photograph's verdict with
    /// reasons and the model's band, when the run has stories.
    pub connector: Option<String>,
    /// Run-rule alarms ("peak force: rule 1: point 3 beyond 3σ …").
    pub alarms: Vec<String>,
    pub confusion: Option<Confusion>,
    /// Connectors where process and vision disagree (cycle and both reasons).
    pub disagreements: Vec<String>,
    /// Logs not monitored, with why.
    pub not_monitored: Vec<String>,
    pub pending: bool,
    pub message: Option<String>,
    /// The monitor's whole result (what `pinsight monitor --json` prints).
    pub run: Option<std::sync::Arc<MonitorRun>>,
}

impl LineView {
    /// One row per cycle of the log shown.
    pub fn to_csv(&self) -> String {
        let row = |c: &CycleRow| {
            vec![
                c.index.to_string(),
                c.status.to_string(),
                c.reasons.join("; "),
            ]
        };
        super::csv_table(&["cycle", "status", "reasons"], self.cycles.iter().map(row))
    }
}

fn empty(message: String, pending: bool, s: &Session) -> LineView {
    LineView {
        part_number: s.process_recipes.first().map(|r| r.part_number.clone()),
        log: None,
        logs: s.logs.len(),
        ok: 0,
        nok: 0,
        not_evaluated: 0,
        nok_fraction: None,
        cycles: Vec::new(),
        selected: 0,
        chart: None,
        spc: Vec::new(),
        pin_spc: Vec::new(),
        pin_summary: None,
        connector: None,
        alarms: Vec::new(),
        confusion: None,
        disagreements: Vec::new(),
        not_monitored: Vec::new(),
        pending,
        message: Some(message),
        run: None,
    }
}

fn spc_row(c: &Characteristic) -> SpcRow {
    let k = c.capability.as_ref();
    SpcRow {
        name: c.name.clone(),
        unit: c.unit,
        n: k.map_or(0, |k| k.n),
        mean: k.map(|k| k.mean),
        sigma_within: k.map(|k| k.sigma_within),
        cp: k.and_then(|k| k.cp),
        cpk: k.and_then(|k| k.cpk),
        ppk: k.and_then(|k| k.ppk),
        band: k.and_then(|k| k.cpk).map_or("–", cpk_band),
        alarms: c.chart.as_ref().map_or(0, |ch| ch.alarms.len()),
    }
}

/// A connector's photograph and model band on one line.
fn connector_line(c: &ConnectorStory) -> String {
    let vision = match c.vision {
        Some(ItemStatus::Pass) => "vision pass".to_string(),
        Some(ItemStatus::Fail) => format!("vision fail: {}", c.vision_reasons.join("; ")),
        Some(ItemStatus::Error) => format!("image error: {}", c.vision_reasons.join("; ")),
        None => "no photograph".to_string(),
    };
    match &c.band {
        Some(b) => format!(
            "{vision}; model band: stroke {:.0} % inside, force {:.0} % inside, BDC {:+.3} mm",
            100.0 * b.stroke_in_band,
            100.0 * b.force_in_band,
            b.stroke_err_bdc_mm
        ),
        None => vision,
    }
}

/// The chart of one cycle: force against the axis of the recipe's first
/// curve object (stroke unless every object is on the crank angle), with
/// the learned envelope's band and the windows' boxes.
fn cycle_chart(
    r: &ProcessRecipe,
    cs: &CycleSet,
    v: &CycleVerdict,
    cols: usize,
) -> Option<ChartView> {
    let c = cs.cycles.iter().find(|c| c.index == v.index)?;
    let curve = crate::process::curve::CycleCurve::new(cs, c);
    let axis = r
        .window
        .first()
        .map(|w| w.x)
        .or(r.threshold.first().map(|t| t.x))
        .or(r.envelope.first().map(|e| e.x))
        .unwrap_or(Axis::Stroke);
    let branch = r.window.first().map(|w| w.branch).unwrap_or_default();
    let mut series = vec![SeriesView {
        name: format!("cycle {} ({})", v.index, v.status.name()),
        color: if v.status == CycleStatus::Nok { 1 } else { 2 },
        kind: SeriesKind::Line,
        points: curve.points(axis, branch),
    }];
    for e in r
        .envelope
        .iter()
        .filter(|e| e.x == axis && !e.x_grid.is_empty())
    {
        for (name, ys) in [("lo", &e.lo), ("hi", &e.hi)] {
            series.push(SeriesView {
                name: format!("{} {name}", e.name),
                color: 4,
                kind: SeriesKind::Reference,
                points: e.x_grid.iter().copied().zip(ys.iter().copied()).collect(),
            });
        }
    }
    for w in r.window.iter().filter(|w| w.x == axis) {
        let ([x0, x1], [y0, y1]) = (w.x_range, w.y_range);
        series.push(SeriesView {
            name: format!("window {}", w.name),
            color: 3,
            kind: SeriesKind::Reference,
            points: vec![(x0, y0), (x1, y0), (x1, y1), (x0, y1), (x0, y0)],
        });
    }
    for t in r.threshold.iter().filter(|t| t.x == axis) {
        series.push(SeriesView {
            name: format!("threshold {}", t.name),
            color: 5,
            kind: SeriesKind::Reference,
            points: vec![(t.x_range[0], t.level), (t.x_range[1], t.level)],
        });
    }
    let x_label = match axis {
        Axis::Stroke => "stroke from TDC [mm]",
        Axis::Angle => "crank angle from TDC [°]",
    };
    // Zoom on the objects (a quarter of their span on each side); the whole
    // curve when there are none on this axis.
    let spans: Vec<[f64; 2]> = r
        .window
        .iter()
        .filter(|w| w.x == axis)
        .map(|w| w.x_range)
        .chain(
            r.threshold
                .iter()
                .filter(|t| t.x == axis)
                .map(|t| t.x_range),
        )
        .chain(r.envelope.iter().filter(|e| e.x == axis).map(|e| e.x_range))
        .collect();
    let xb = if spans.is_empty() {
        super::chart::finite_bounds(series.iter().flat_map(|s| s.points.iter().map(|p| p.0)))
    } else {
        let lo = spans.iter().map(|s| s[0]).fold(f64::INFINITY, f64::min);
        let hi = spans.iter().map(|s| s[1]).fold(f64::NEG_INFINITY, f64::max);
        let pad = 0.25 * (hi - lo).max(1e-9);
        [lo - pad, hi + pad]
    };
    for s in &mut series {
        s.points.retain(|p| p.0 >= xb[0] && p.0 <= xb[1]);
        if s.points.len() > cols * 2 {
            s.points = super::chart::decimate_points(&s.points, xb[0], xb[1], cols);
        }
    }
    Some(ChartView::new(
        "press curve",
        x_label,
        "force N",
        series,
        Some(xb),
    ))
}

/// The log the pane shows (`line.log` among the logs that could be
/// monitored) and its report.
fn shown_log<'a>(
    run: &'a MonitorRun,
    ui: &PaneState,
) -> Option<(&'a LogMonitor, &'a MonitorReport)> {
    let monitored: Vec<_> = run
        .logs
        .iter()
        .filter_map(|l| l.report.as_ref().ok().map(|r| (l, r)))
        .collect();
    monitored
        .get(ui.line.log.min(monitored.len().saturating_sub(1)))
        .copied()
}

/// Rows of the cycle list (what `j`/`k` move through), without building the view.
pub fn cycle_count(s: &Session, ui: &PaneState) -> usize {
    match &s.monitor {
        Some(Ok(run)) => shown_log(run, ui).map_or(0, |(_, r)| r.cycles.len()),
        _ => 0,
    }
}

pub fn view(s: &Session, ui: &PaneState) -> LineView {
    if s.process_recipes.is_empty() {
        return empty(
            "no process recipe loaded: open a process recipe (a TOML with part_number and \
             [[window]]/[[threshold]]/[[envelope]]/[[value]] objects) and a rig log (o)"
                .into(),
            false,
            s,
        );
    }
    if s.logs.is_empty() {
        return empty("no rig log loaded (o opens one)".into(), false, s);
    }
    let run = match &s.monitor {
        None => {
            return empty(
                format!(
                    "monitor over {} log(s) not run yet (r runs it)",
                    s.logs.len()
                ),
                true,
                s,
            );
        }
        Some(Err(e)) => return empty(format!("monitor: {e}"), false, s),
        Some(Ok(run)) => run,
    };
    let not_monitored = run
        .logs
        .iter()
        .filter_map(|l| l.report.as_ref().err().map(|e| format!("{}: {e}", l.file)))
        .collect();
    let mut v = empty(String::new(), false, s);
    v.message = None;
    v.run = Some(std::sync::Arc::clone(run));
    v.part_number = Some(run.part_number.clone());
    v.ok = run.ok;
    v.nok = run.nok;
    v.not_evaluated = run.not_evaluated;
    let evaluated = run.ok + run.nok;
    v.nok_fraction = (evaluated > 0).then(|| run.nok as f64 / evaluated as f64);
    v.not_monitored = not_monitored;
    v.confusion = run.confusion;
    v.spc = run.spc.iter().map(spc_row).collect();
    v.pin_spc = by_cpk(&run.pin_spc)
        .into_iter()
        .take(PIN_SPC_LISTED)
        .map(spc_row)
        .collect();
    if !run.pin_spc.is_empty() {
        let [c, a, i] = band_counts(&run.pin_spc);
        v.pin_summary = Some(format!(
            "{} pin characteristics: {c} capable, {a} adequate, {i} inadequate",
            run.pin_spc.len()
        ));
    }
    v.alarms = run
        .spc
        .iter()
        .chain(&run.pin_spc)
        .flat_map(|c| {
            c.chart
                .iter()
                .flat_map(|ch| ch.alarms.iter())
                .map(move |a| format!("{}: rule {}: {}", c.name, a.rule, a.text))
        })
        .collect();
    let Some((lm, rep)) = shown_log(run, ui) else {
        v.message = Some("no log could be monitored".into());
        return v;
    };
    v.log = Some(lm.file.clone());
    v.logs = run.logs.len();
    v.cycles = rep
        .cycles
        .iter()
        .map(|c| CycleRow {
            index: c.index,
            status: c.status.name(),
            reasons: c.reasons(),
        })
        .collect();
    v.selected = ui
        .line
        .cycle
        .unwrap_or(usize::MAX)
        .min(v.cycles.len().saturating_sub(1));
    if let (Some(st), Some(c)) = (&lm.story, v.cycles.get(v.selected)) {
        v.connector = st
            .connectors
            .iter()
            .find(|k| k.cycle == c.index)
            .map(connector_line);
    }
    if let Some(st) = &lm.story {
        v.disagreements = st
            .disagreements()
            .map(|c| {
                format!(
                    "cycle {}: process {}, vision {}: {}",
                    c.cycle,
                    c.process.map_or("–", CycleStatus::name),
                    match c.vision {
                        Some(ItemStatus::Fail) => "fail",
                        Some(ItemStatus::Pass) => "pass",
                        _ => "–",
                    },
                    c.why()
                )
            })
            .collect();
    }
    // The chart: the selected cycle on the session log of that name.
    let recipe = crate::engine::process::recipe_for(&s.process_recipes, Some(&run.part_number));
    let cs = s
        .logs
        .iter()
        .find(|l| l.path == lm.file)
        .and_then(|l| l.rig.as_ref())
        .map(|(_, cs)| cs);
    if let (Some(r), Some(cs), Some(c)) = (recipe, cs, rep.cycles.get(v.selected)) {
        v.chart = cycle_chart(r, cs, c, ui.chart_columns(0.6));
    }
    v
}
