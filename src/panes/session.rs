//! The session: every file the user opened, the parameters in force, and the
//! latest results the panes show.
//!
//! Loading goes through one function, [`load_path`], that never panics:
//! it recognises rig logs (`.mcap`), connector images, recipe TOML files
//! (`part_number` and `view`), parameter TOML files and folders (their
//! files, one level deep), and records a [`FileEntry`] with the error for
//! every file it could not use. Loading is a pure function returning
//! [`Loaded`] items so the TUI can run it on a worker thread and merge the
//! result with [`Session::absorb`] on the UI thread; batch mode calls the
//! same two functions in a row.
//!
//! Long computations ([`run_model`], [`run_study`]) are plain functions too,
//! taking a [`Progress`] for a gauge and cancellation; their results enter
//! the session through [`Session::set_model_run`] / [`Session::set_study`].

use crate::model::kinematics::Geometry;
use crate::model::params::Params;
use crate::progress::Progress;
use crate::rig::cycles::{CycleOptions, CycleSet, analyse};
use crate::rig::{LoadOptions, LoadStatus, RigLog, Severity};
use crate::sim::fidelity::{FidelityReport, SceneResolution, assess};
use crate::sim::sweep::{SweepGrid, SweepResult, run_sweep};
use crate::sim::{Level, LevelChoice, SimOptions, SimResult, simulate};
use crate::solver::Method;
use crate::vision::batch::ItemMeta;
use serde::Serialize;
use std::borrow::Cow;
use std::path::{Path, PathBuf};
use std::sync::Arc;

/// What a file is.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum FileKind {
    RigLog,
    Image,
    Recipe,
    Params,
    Folder,
    Unknown,
}

impl FileKind {
    pub fn name(self) -> &'static str {
        match self {
            FileKind::RigLog => "rig log",
            FileKind::Image => "image",
            FileKind::Recipe => "recipe",
            FileKind::Params => "parameters",
            FileKind::Folder => "folder",
            FileKind::Unknown => "unknown",
        }
    }
}

/// Whether a file could be used.
#[derive(Debug, Clone, PartialEq, Serialize)]
#[serde(tag = "status", content = "message", rename_all = "snake_case")]
pub enum FileStatus {
    Loaded,
    /// Used, with problems worth reading (a log with gaps …).
    Warning(String),
    Error(String),
    /// Deliberately not used (a ground-truth JSON beside an image …).
    Skipped(String),
}

impl FileStatus {
    pub fn is_error(&self) -> bool {
        matches!(self, FileStatus::Error(_))
    }
}

/// One opened file as the Session pane lists it.
#[derive(Debug, Clone, Serialize)]
pub struct FileEntry {
    pub path: String,
    pub kind: FileKind,
    #[serde(flatten)]
    pub status: FileStatus,
    /// One line on what it holds (size, channels, part number …).
    pub detail: String,
}

/// One channel of a log as the Signals pane draws it: time in seconds from
/// the log's start, values in the channel's unit.
#[derive(Debug, Clone, Serialize)]
pub struct Channel {
    pub name: String,
    pub unit: String,
    #[serde(skip)]
    pub t_s: Vec<f64>,
    #[serde(skip)]
    pub values: Vec<f64>,
    /// Block extremes of `values`, built on first use (long channels).
    #[serde(skip)]
    pub blocks: std::sync::OnceLock<super::chart::MinMaxBlocks>,
}

impl Channel {
    pub fn new(
        name: impl Into<String>,
        unit: impl Into<String>,
        t_s: Vec<f64>,
        values: Vec<f64>,
    ) -> Self {
        Self {
            name: name.into(),
            unit: unit.into(),
            t_s,
            values,
            blocks: std::sync::OnceLock::new(),
        }
    }

    /// The block extremes (built once; None for short channels, where a
    /// plain scan is as fast).
    pub fn blocks(&self) -> Option<&super::chart::MinMaxBlocks> {
        (self.values.len() >= 16 * super::chart::BLOCK).then(|| {
            self.blocks
                .get_or_init(|| super::chart::MinMaxBlocks::new(&self.values))
        })
    }
}

/// A time series source for the Signals pane: a rig log's channels, or the
/// model's prediction over time when no log is loaded.
#[derive(Debug, Clone, Serialize)]
pub struct SignalSet {
    pub source: String,
    pub channels: Vec<Channel>,
    /// Cycle starts: (time s, cycle index).
    pub cycles: Vec<(f64, u64)>,
    /// Metadata shown on the Session pane (rig, lot, part, clearance, speed …).
    pub meta: Vec<(String, String)>,
}

impl SignalSet {
    pub fn duration_s(&self) -> f64 {
        let mut lo = f64::INFINITY;
        let mut hi = f64::NEG_INFINITY;
        for c in &self.channels {
            if let (Some(a), Some(b)) = (c.t_s.first(), c.t_s.last()) {
                lo = lo.min(*a);
                hi = hi.max(*b);
            }
        }
        if lo.is_finite() { hi - lo } else { 0.0 }
    }
    pub fn t_range(&self) -> [f64; 2] {
        let mut lo = f64::INFINITY;
        let mut hi = f64::NEG_INFINITY;
        for c in &self.channels {
            if let (Some(a), Some(b)) = (c.t_s.first(), c.t_s.last()) {
                lo = lo.min(*a);
                hi = hi.max(*b);
            }
        }
        if lo.is_finite() && hi > lo {
            [lo, hi]
        } else if lo.is_finite() {
            [lo, lo + 1.0]
        } else {
            [0.0, 1.0]
        }
    }
}

/// A loaded rig log: the channels as the Signals pane draws them and the
/// library's plain data ([`crate::rig::RigLog`] and its [`CycleSet`], for
/// the Overlay pane; None for a synthetic set of channels).
#[derive(Debug, Clone)]
pub struct LogEntry {
    pub path: String,
    pub signals: SignalSet,
    pub rig: Option<(Arc<RigLog>, Arc<CycleSet>)>,
}

/// A vision recipe (from a file or a log's attachment), parsed and validated.
#[derive(Debug, Clone, Serialize)]
pub struct RecipeEntry {
    pub path: String,
    pub part_number: String,
    pub view: String,
    #[serde(skip)]
    pub recipe: crate::vision::Recipe,
}

/// Where an image's bytes are.
#[derive(Debug, Clone)]
pub enum ImageSource {
    File(PathBuf),
    /// Embedded (demo) or extracted from a rig log.
    Bytes(Arc<Vec<u8>>),
}

/// A connector image.
#[derive(Debug, Clone)]
pub struct ImageEntry {
    pub name: String,
    pub source: ImageSource,
    pub width: u32,
    pub height: u32,
    /// The decoded image, for display (kept small: at most 1024 px wide).
    pub preview: Option<Arc<image::RgbImage>>,
    /// Where it came from (part number, lot, speed, cycle of a rig log's image).
    pub meta: ItemMeta,
}

/// The latest model run: what was run and what came out.
#[derive(Debug, Clone, Serialize)]
pub struct ModelRun {
    pub params: Params,
    pub choice: String,
    pub level: Level,
    /// Why this level (forced by the user, or the fidelity chooser's reason).
    pub level_reason: String,
    pub options: SimOptions,
    pub result: SimResult,
    pub fidelity: Option<FidelityReport>,
}

/// Options of the study run from the Study pane or a batch step.
#[derive(Debug, Clone, Serialize)]
pub struct StudySetup {
    pub grid: SweepGrid,
    pub warmup: f64,
    pub revs: f64,
}

impl Default for StudySetup {
    /// The paper's study with the default protocol (2 warm-up + 3 reported
    /// revolutions per case).
    fn default() -> Self {
        Self {
            grid: SweepGrid::default(),
            warmup: 2.0,
            revs: 3.0,
        }
    }
}

/// The state every pane is computed from.
#[derive(Debug, Clone)]
pub struct Session {
    /// What this session is ("demo (embedded)", or the files opened).
    pub title: String,
    pub files: Vec<FileEntry>,
    pub params: Params,
    /// Where the parameters come from (preset, file, edits).
    pub params_source: String,
    pub level: LevelChoice,
    pub model: Option<ModelRun>,
    pub model_error: Option<String>,
    pub study_setup: StudySetup,
    pub study: Option<SweepResult>,
    pub study_error: Option<String>,
    pub logs: Vec<LogEntry>,
    pub recipes: Vec<RecipeEntry>,
    pub images: Vec<ImageEntry>,
    /// How the session is displayed (set by the front end: colours, image
    /// protocol), shown on the Session pane.
    pub display: Option<String>,
    /// The methods lab (quick effort: dynamics and vision), once run.
    pub methods: Option<MethodsLab>,
    pub methods_error: Option<String>,
    /// Vision inspections by image index (run on demand: the image shown).
    pub inspections: std::collections::BTreeMap<usize, super::analysis::Inspected>,
    /// The batch yield over every image (None: not run, or images changed since).
    pub yields: Option<super::analysis::YieldRun>,
    /// Measured-vs-predicted comparisons by log index.
    pub overlays: std::collections::BTreeMap<usize, super::analysis::OverlayRun>,
}

impl Default for Session {
    fn default() -> Self {
        Self::new("empty session")
    }
}

impl Session {
    /// An empty session on the `paper` preset.
    pub fn new(title: impl Into<String>) -> Self {
        Self {
            title: title.into(),
            files: Vec::new(),
            params: Params::paper(),
            params_source: "preset paper".into(),
            level: LevelChoice::Fixed(Level::Clearance),
            model: None,
            model_error: None,
            study_setup: StudySetup::default(),
            study: None,
            study_error: None,
            logs: Vec::new(),
            recipes: Vec::new(),
            images: Vec::new(),
            display: None,
            methods: None,
            methods_error: None,
            inspections: Default::default(),
            yields: None,
            overlays: Default::default(),
        }
    }

    /// The embedded demo session (see [`super::demo`]).
    pub fn demo() -> Self {
        super::demo::session()
    }

    /// Opens paths (synchronously) and merges them.
    pub fn open_paths<P: AsRef<Path>>(&mut self, paths: &[P]) {
        for p in paths {
            let items = load_path(p.as_ref(), &Progress::hidden());
            self.absorb(items);
        }
    }

    /// Merges loaded items. A parameter file replaces the parameters in
    /// force (the model must then be re-run); everything else is added.
    /// Returns whether the parameters changed.
    pub fn absorb(&mut self, items: Vec<Loaded>) -> bool {
        let mut params_changed = false;
        for item in items {
            match item {
                Loaded::Entry(e) => self.files.push(e),
                Loaded::Params(e, p) => {
                    self.params_source = e.path.clone();
                    self.params = *p;
                    self.files.push(e);
                    params_changed = true;
                }
                Loaded::Log(e, log) => {
                    self.files.push(e);
                    self.logs.push(*log);
                }
                Loaded::Recipe(e, r) => {
                    self.files.push(e);
                    self.recipes.push(*r);
                    // Another recipe can change which one an image gets.
                    self.inspections.clear();
                    self.yields = None;
                }
                Loaded::Image(e, img) => {
                    self.files.push(e);
                    self.images.push(*img);
                    self.yields = None;
                }
            }
        }
        params_changed
    }

    /// Errors found while loading (file, message).
    pub fn load_errors(&self) -> Vec<(&str, &str)> {
        self.files
            .iter()
            .filter_map(|f| match &f.status {
                FileStatus::Error(m) => Some((f.path.as_str(), m.as_str())),
                _ => None,
            })
            .collect()
    }

    /// Records a finished model run (or its error).
    pub fn set_model_run(&mut self, r: Result<ModelRun, String>) {
        match r {
            Ok(run) => {
                self.model = Some(run);
                self.model_error = None;
            }
            Err(e) => self.model_error = Some(e),
        }
    }

    /// Records a finished study.
    pub fn set_study(&mut self, r: SweepResult) {
        self.study_error = None;
        self.study = Some(r);
    }

    /// Runs the model now (batch mode and tests; the TUI runs [`run_model`]
    /// on its worker).
    pub fn run_model_now(&mut self) {
        let r = run_model(&self.params, self.level, &Progress::hidden());
        self.set_model_run(r);
    }

    /// Runs the quick methods lab now.
    pub fn run_methods_now(&mut self) {
        self.methods = Some(run_methods(&Progress::hidden()));
        self.methods_error = None;
    }

    /// Runs the study now.
    pub fn run_study_now(&mut self) {
        let r = run_study(&self.params, &self.study_setup, &Progress::hidden());
        self.set_study(r);
    }

    /// The signals to show: the first loaded log, else the model's
    /// prediction over time (None when neither exists).
    pub fn signal_set(&self, log: usize) -> Option<Cow<'_, SignalSet>> {
        if let Some(l) = self.logs.get(log).or_else(|| self.logs.first()) {
            return Some(Cow::Borrowed(&l.signals));
        }
        self.model
            .as_ref()
            .map(|m| Cow::Owned(predicted_signals(m)))
    }
}

/// The model's predicted channels over time (stroke, load-cell force, drive
/// torque, pin-bar speed), for the Signals pane when no log is loaded.
pub fn predicted_signals(run: &ModelRun) -> SignalSet {
    let mut channels = Vec::new();
    let mut cycles = Vec::new();
    if let Some(c) = &run.result.curves {
        let t0 = c.t_s.first().copied().unwrap_or(0.0);
        let t: Vec<f64> = c.t_s.iter().map(|t| t - t0).collect();
        let ch =
            |name: &str, unit: &str, v: &Vec<f64>| Channel::new(name, unit, t.clone(), v.clone());
        channels.push(ch("stroke", "mm", &c.stroke_mm));
        channels.push(ch("force", "N", &c.process_force_n));
        channels.push(ch("torque", "N·m", &c.torque_nm));
        channels.push(ch("speed", "m/s", &c.vel_mps));
        // A cycle starts at top dead centre, where the wrapped crank angle
        // passes the TDC angle (180° for zero offset; the smallest stroke).
        let period = run.params.period();
        if period > 0.0 && !t.is_empty() {
            // Find the first TDC (minimum stroke in the first period).
            let n1 = t.iter().take_while(|&&x| x < period).count().max(1);
            let i0 = (0..n1.min(c.stroke_mm.len()))
                .min_by(|&a, &b| c.stroke_mm[a].total_cmp(&c.stroke_mm[b]))
                .unwrap_or(0);
            let mut k = 0u64;
            let mut tc = t[i0];
            let end = t.last().copied().unwrap_or(0.0);
            while tc <= end + 1e-12 {
                cycles.push((tc, k));
                k += 1;
                tc = t[i0] + k as f64 * period;
            }
        }
    }
    SignalSet {
        source: format!(
            "model prediction ({} level, {}): no rig log loaded",
            run.level.name(),
            run.result.summary.view
        ),
        channels,
        cycles,
        meta: vec![
            ("preset".into(), run.params.preset.clone()),
            (
                "clearance".into(),
                format!("{} mm", run.params.clearance * 1e3),
            ),
            ("speed".into(), format!("{} rpm", run.params.motor_rpm)),
        ],
    }
}

/// What loading one path produced.
#[derive(Debug, Clone)]
pub enum Loaded {
    /// A file listed but not used (or not usable: its entry says why).
    Entry(FileEntry),
    Params(FileEntry, Box<Params>),
    Log(FileEntry, Box<LogEntry>),
    Recipe(FileEntry, Box<RecipeEntry>),
    Image(FileEntry, Box<ImageEntry>),
}

impl Loaded {
    pub fn entry(&self) -> &FileEntry {
        match self {
            Loaded::Entry(e)
            | Loaded::Params(e, _)
            | Loaded::Log(e, _)
            | Loaded::Recipe(e, _)
            | Loaded::Image(e, _) => e,
        }
    }
}

fn entry(path: &str, kind: FileKind, status: FileStatus, detail: impl Into<String>) -> FileEntry {
    FileEntry {
        path: path.to_string(),
        kind,
        status,
        detail: detail.into(),
    }
}

const IMAGE_EXTS: [&str; 7] = ["png", "jpg", "jpeg", "bmp", "tif", "tiff", "pgm"];

/// Loads one path (a folder: its files, sorted, one level deep). Never
/// panics; every problem becomes a [`FileStatus::Error`] naming the file.
pub fn load_path(path: &Path, progress: &Progress) -> Vec<Loaded> {
    let shown = path.display().to_string();
    let meta = match std::fs::metadata(path) {
        Ok(m) => m,
        Err(e) => {
            return vec![Loaded::Entry(entry(
                &shown,
                FileKind::Unknown,
                FileStatus::Error(format!("cannot open: {e}")),
                "",
            ))];
        }
    };
    if meta.is_dir() {
        let mut files: Vec<PathBuf> = match std::fs::read_dir(path) {
            Ok(rd) => rd
                .filter_map(|e| e.ok().map(|e| e.path()))
                .filter(|p| p.is_file())
                .collect(),
            Err(e) => {
                return vec![Loaded::Entry(entry(
                    &shown,
                    FileKind::Folder,
                    FileStatus::Error(format!("cannot list: {e}")),
                    "",
                ))];
            }
        };
        files.sort();
        progress.set_total(files.len() as u64);
        let mut out = Vec::new();
        for f in files {
            if progress.is_cancelled() {
                out.push(Loaded::Entry(entry(
                    &shown,
                    FileKind::Folder,
                    FileStatus::Warning("loading cancelled: some files were not opened".into()),
                    "",
                )));
                break;
            }
            let ext = ext_of(&f);
            // Inside a folder, files pinsight has no use for are skipped quietly
            // (ground truth beside images, notes …); named explicitly they are errors.
            if ext == "json" || ext == "md" || ext == "txt" {
                progress.inc(1);
                continue;
            }
            out.extend(load_file(&f, progress));
            progress.inc(1);
        }
        return out;
    }
    load_file(path, progress)
}

fn ext_of(p: &Path) -> String {
    p.extension()
        .and_then(|e| e.to_str())
        .map(|e| e.to_ascii_lowercase())
        .unwrap_or_default()
}

fn load_file(path: &Path, progress: &Progress) -> Vec<Loaded> {
    let shown = path.display().to_string();
    let ext = ext_of(path);
    match ext.as_str() {
        "mcap" => load_log(path, progress),
        e if IMAGE_EXTS.contains(&e) => match std::fs::read(path) {
            Ok(bytes) => vec![load_image_bytes(
                &shown,
                ImageSource::File(path.to_path_buf()),
                &bytes,
            )],
            Err(e) => vec![Loaded::Entry(entry(
                &shown,
                FileKind::Image,
                FileStatus::Error(format!("cannot read: {e}")),
                "",
            ))],
        },
        "toml" => match std::fs::read_to_string(path) {
            Ok(text) => vec![load_toml_text(&shown, &text)],
            Err(e) => vec![Loaded::Entry(entry(
                &shown,
                FileKind::Unknown,
                FileStatus::Error(format!("cannot read: {e}")),
                "",
            ))],
        },
        _ => vec![Loaded::Entry(entry(
            &shown,
            FileKind::Unknown,
            FileStatus::Error(format!(
                "unknown file type `.{ext}` (pinsight opens .mcap rig logs, images ({}), recipe and parameter .toml files, and folders of them)",
                IMAGE_EXTS.join(", ")
            )),
            "",
        ))],
    }
}

/// A rig log, through [`crate::rig::load`] (crash-proof on corrupt files:
/// a file that cannot be read as MCAP at all becomes an error entry; a
/// partial file loads what it can and says what it lost). Its cycles are
/// analysed at once ([`crate::rig::cycles::analyse`], preset `paper`
/// geometry), its camera images become image entries, its attached recipes
/// recipe entries.
fn load_log(path: &Path, progress: &Progress) -> Vec<Loaded> {
    let shown = path.display().to_string();
    progress.set_message(format!("reading {shown}"));
    match crate::rig::load(path, &LoadOptions::default(), progress) {
        Ok(log) => log_items(&shown, log, Some(path)),
        Err(e) => vec![Loaded::Entry(entry(
            &shown,
            FileKind::RigLog,
            FileStatus::Error(one_line(&strip_file(&e.to_string(), &shown))),
            "",
        ))],
    }
}

/// A rig log held in memory (the embedded demo log).
pub fn load_log_bytes(name: &str, bytes: &[u8]) -> Vec<Loaded> {
    let src = crate::rig::mcap_read::Source::from_vec(name, bytes.to_vec());
    match crate::rig::load_source(&src, &LoadOptions::default(), &Progress::hidden()) {
        Ok(log) => log_items(name, log, None),
        Err(e) => vec![Loaded::Entry(entry(
            name,
            FileKind::RigLog,
            FileStatus::Error(one_line(&e.to_string())),
            "",
        ))],
    }
}

/// Signals pane names of the rig signals.
fn channel_name(k: crate::rig::SignalKind) -> &'static str {
    use crate::rig::SignalKind as K;
    match k {
        K::Angle => "angle",
        K::Speed => "speed",
        K::Force => "force",
        K::Displacement => "displacement",
        K::Cycle => "cycle",
    }
}

/// The entries of a loaded log: the log itself (status from its load
/// report and cycle findings), its images (decoded from `path` when the
/// log is a file), its attached recipes.
fn log_items(shown: &str, log: RigLog, path: Option<&Path>) -> Vec<Loaded> {
    let mut out = Vec::new();
    let copts = CycleOptions {
        geometry: Geometry::of(&Params::paper()),
        ..CycleOptions::default()
    };
    let cycles = analyse(&log, &copts);
    let t0 = log.log_start_ns.unwrap_or(0);
    let secs = |t: i64| (t - t0) as f64 * 1e-9;
    let mut channels = Vec::new();
    for k in crate::rig::SignalKind::ALL {
        if k == crate::rig::SignalKind::Cycle {
            continue; // shown as cycle markers
        }
        if let Some(sig) = log.signals.get(k) {
            channels.push(Channel::new(
                channel_name(k),
                sig.unit.clone(),
                sig.t_ns.iter().map(|&t| secs(t)).collect(),
                sig.values.clone(),
            ));
        }
    }
    let cycle_marks: Vec<(f64, u64)> = cycles
        .cycles
        .iter()
        .map(|c| (secs(c.t_start_ns), c.index))
        .collect();
    let m = &log.meta;
    let mut meta: Vec<(String, String)> = Vec::new();
    let mut put = |k: &str, v: Option<String>| {
        if let Some(v) = v {
            meta.push((k.to_string(), v));
        }
    };
    put("rig", m.rig_id.clone());
    put("lot", m.lot.clone());
    put("part", m.part_number.clone());
    put("clearance", m.clearance_mm.map(|c| format!("{c} mm")));
    put("speed", m.motor_rpm.map(|r| format!("{r} rpm")));
    put("material", m.material.clone());
    put("standoff", m.standoff_mm.map(|c| format!("{c} mm")));
    put("gear ratio", m.gear_ratio.map(|g| g.to_string()));
    put(
        "cycles",
        Some(format!(
            "{} ({} usable), {}",
            cycles.cycles.len(),
            cycles.usable().count(),
            match cycles.source {
                crate::rig::cycles::CycleSource::Marks => "from the cycle marks",
                crate::rig::cycles::CycleSource::Angle => "from the crank angle",
                crate::rig::cycles::CycleSource::None => "no crank angle",
            }
        )),
    );
    if cycles.crank.motor_rpm_mean.is_finite() && cycles.crank.motor_rpm_mean > 0.0 {
        put(
            "measured speed",
            Some(format!("{:.1} rpm", cycles.crank.motor_rpm_mean)),
        );
    }
    // Findings worth a technician's attention, per channel: the entry's
    // message lists them; the status is the worst of load and cycles.
    let findings: Vec<&crate::rig::Finding> = log
        .report
        .findings
        .iter()
        .chain(cycles.findings.iter())
        .filter(|f| f.severity >= Severity::Warning)
        .collect();
    let worst = findings.iter().map(|f| f.severity).max();
    let listed: Vec<String> = findings
        .iter()
        .map(|f| {
            let m = one_line(&strip_file(&f.message, &log.file));
            match f.channel.as_deref() {
                Some(ch) if !m.starts_with(ch) => format!("{ch}: {m}"),
                _ => m,
            }
        })
        .collect();
    let status = match (log.report.status, worst) {
        (LoadStatus::Error, _) => FileStatus::Error(if listed.is_empty() {
            "nothing usable in the log".into()
        } else {
            listed.join(FINDING_SEP)
        }),
        (_, Some(Severity::DataLoss | Severity::Error)) => {
            FileStatus::Warning(format!("partial: {}", listed.join(FINDING_SEP)))
        }
        (_, Some(_)) => FileStatus::Warning(listed.join(FINDING_SEP)),
        (_, None) => FileStatus::Loaded,
    };
    let detail = format!(
        "{:.2} s, {} channels, {} cycles, {} images, {}",
        log.duration_s(),
        channels.len(),
        cycles.cycles.len(),
        log.images.len(),
        log.report.status.as_str()
    );
    let source = format!(
        "rig log {shown}{}",
        m.rig_id
            .as_ref()
            .map(|r| format!(" (rig {r})"))
            .unwrap_or_default()
    );
    let usable = !status.is_error();
    let item_meta = ItemMeta {
        lot: m.lot.clone(),
        part_number: m.part_number.clone(),
        rig_id: m.rig_id.clone(),
        motor_rpm: m.motor_rpm,
        clearance_mm: m.clearance_mm,
        cycle: None,
        log: Some(shown.to_string()),
    };
    let image_refs = log.images.clone();
    let attachments: Vec<(String, String)> = log
        .attachments
        .iter()
        .filter(|a| a.kind == crate::rig::load::AttachmentKind::Recipe)
        .filter_map(|a| a.text.clone().map(|t| (a.name.clone(), t)))
        .collect();
    let e = entry(shown, FileKind::RigLog, status, detail);
    if usable {
        out.push(Loaded::Log(
            e,
            Box::new(LogEntry {
                path: shown.to_string(),
                signals: SignalSet {
                    source,
                    channels,
                    cycles: cycle_marks,
                    meta,
                },
                rig: Some((Arc::new(log), Arc::new(cycles))),
            }),
        ));
    } else {
        out.push(Loaded::Entry(e));
    }
    for (name, text) in attachments {
        out.push(load_toml_text(&format!("{shown}#{name}"), &text));
    }
    for (i, r) in image_refs.iter().enumerate() {
        let name = match r.cycle {
            Some(c) => format!("{shown}#cycle-{c}"),
            None => format!("{shown}#{i}"),
        };
        let meta = ItemMeta {
            cycle: r.cycle,
            ..item_meta.clone()
        };
        let read = match path {
            Some(p) => crate::rig::images::read_image(p, r).map_err(|e| one_line(&e.to_string())),
            None => Err("images of an in-memory log are not decoded".to_string()),
        };
        match read {
            Ok(img) => {
                let bytes = Arc::new(img.data);
                let mut l = load_image_bytes(&name, ImageSource::Bytes(bytes.clone()), &bytes);
                if let Loaded::Image(_, e) = &mut l {
                    e.meta = meta;
                }
                out.push(l);
            }
            Err(m) => out.push(Loaded::Entry(entry(
                &name,
                FileKind::Image,
                FileStatus::Error(m),
                "",
            ))),
        }
    }
    out
}

/// Separates a log's findings in its entry's message (one finding may hold
/// semicolons of its own).
pub const FINDING_SEP: &str = " | ";

/// A finding's message without the file name it starts with (the Session
/// pane lists it under the file already).
fn strip_file(msg: &str, file: &str) -> String {
    msg.strip_prefix(file)
        .map(|r| r.trim_start_matches([':', ' ']).to_string())
        .unwrap_or_else(|| msg.to_string())
}

/// Decodes an image (bytes from a file, the demo or a log) into an entry
/// with a display preview.
pub fn load_image_bytes(name: &str, source: ImageSource, bytes: &[u8]) -> Loaded {
    let decoded = std::panic::catch_unwind(|| image::load_from_memory(bytes));
    match decoded {
        Ok(Ok(img)) => {
            let (w, h) = (img.width(), img.height());
            let preview = if w > 1024 {
                img.resize(
                    1024,
                    1024 * h / w.max(1),
                    image::imageops::FilterType::Triangle,
                )
            } else {
                img
            };
            let detail = format!("{w}×{h} px");
            Loaded::Image(
                entry(name, FileKind::Image, FileStatus::Loaded, detail),
                Box::new(ImageEntry {
                    name: name.to_string(),
                    source,
                    width: w,
                    height: h,
                    preview: Some(Arc::new(preview.to_rgb8())),
                    meta: ItemMeta::default(),
                }),
            )
        }
        Ok(Err(e)) => Loaded::Entry(entry(
            name,
            FileKind::Image,
            FileStatus::Error(format!("cannot decode image: {e}")),
            "",
        )),
        Err(_) => Loaded::Entry(entry(
            name,
            FileKind::Image,
            FileStatus::Error("cannot decode image: the decoder failed".into()),
            "",
        )),
    }
}

/// A TOML file: a recipe (`part_number` and `view`), a parameter file, or
/// an error that says which it looked like.
pub fn load_toml_text(name: &str, text: &str) -> Loaded {
    let table: toml::Table = match text.parse() {
        Ok(t) => t,
        Err(e) => {
            return Loaded::Entry(entry(
                name,
                FileKind::Unknown,
                FileStatus::Error(format!("not valid TOML: {}", one_line(&e.to_string()))),
                "",
            ));
        }
    };
    if table.contains_key("step") {
        return Loaded::Entry(entry(
            name,
            FileKind::Unknown,
            FileStatus::Error("this is a batch script: run it with `pinsight batch FILE`".into()),
            "",
        ));
    }
    if table.contains_key("part_number") || table.contains_key("view") {
        return match crate::vision::Recipe::from_toml_str(text, name) {
            Ok(r) => {
                let view = format!("{:?}", r.view).to_ascii_lowercase();
                Loaded::Recipe(
                    entry(
                        name,
                        FileKind::Recipe,
                        FileStatus::Loaded,
                        format!(
                            "part {}, {view} view, {}×{} pins",
                            r.part_number, r.rows, r.cols
                        ),
                    ),
                    Box::new(RecipeEntry {
                        path: name.to_string(),
                        part_number: r.part_number.clone(),
                        view,
                        recipe: r,
                    }),
                )
            }
            Err(e) => Loaded::Entry(entry(
                name,
                FileKind::Recipe,
                FileStatus::Error(one_line(&e.msg)),
                "",
            )),
        };
    }
    match Params::from_toml_str(text) {
        Ok(p) => {
            let detail = format!(
                "preset {}, {} keys set: clearance {} mm, {} rpm, {}",
                p.preset,
                table.len(),
                p.clearance * 1e3,
                p.motor_rpm,
                p.material_name()
            );
            Loaded::Params(
                entry(name, FileKind::Params, FileStatus::Loaded, detail),
                Box::new(p),
            )
        }
        Err(e) => Loaded::Entry(entry(
            name,
            FileKind::Params,
            FileStatus::Error(one_line(&e.to_string())),
            "",
        )),
    }
}

fn one_line(s: &str) -> String {
    s.split_whitespace().collect::<Vec<_>>().join(" ")
}

/// Runs the model for the Model, Overlay and Signals panes: the fidelity
/// assessment (so the user sees which level the scene needs and why), then
/// the chosen or forced level over the default protocol (2 warm-up + 3
/// reported revolutions) with curves on a 0.5° grid.
pub fn run_model(
    params: &Params,
    choice: LevelChoice,
    progress: &Progress,
) -> Result<ModelRun, String> {
    params.validate().map_err(|e| e.to_string())?;
    progress.set_total(2);
    progress.set_done(0);
    progress.set_message("fidelity assessment");
    let fidelity = assess(params, SceneResolution::default(), Method::Dop853);
    progress.inc(1);
    if progress.is_cancelled() {
        return Err("cancelled".into());
    }
    let (level, level_reason, fidelity) = match (choice, fidelity) {
        (LevelChoice::Fixed(l), f) => (l, "forced by the user".to_string(), f.ok()),
        (LevelChoice::Auto, Ok(f)) => (f.chosen, f.reason.clone(), Some(f)),
        (LevelChoice::Auto, Err(e)) => (
            Level::Clearance,
            format!("the fidelity assessment failed ({e}); running the clearance level"),
            None,
        ),
    };
    let options = SimOptions {
        level,
        grid_deg: Some(0.5),
        record_events: true,
        ..SimOptions::default()
    };
    progress.set_message(format!("simulating ({} level)", level.name()));
    let result = simulate(params, &options, progress).map_err(|e| e.to_string())?;
    progress.inc(1);
    Ok(ModelRun {
        params: params.clone(),
        choice: match choice {
            LevelChoice::Auto => "auto".into(),
            LevelChoice::Fixed(l) => l.name().into(),
        },
        level,
        level_reason,
        options,
        result,
        fidelity,
    })
}

/// Runs the study (the paper's sweep by default) in parallel.
pub fn run_study(params: &Params, setup: &StudySetup, progress: &Progress) -> SweepResult {
    let opts = SimOptions {
        warmup: setup.warmup,
        revs: setup.revs,
        ..SimOptions::default()
    };
    progress.set_message(format!("study: {} cases", setup.grid.len()));
    run_sweep(params, &setup.grid, &opts, progress)
}

/// Runs the quick methods lab (seconds): work–precision, stability, long
/// run, step budgets, fidelity map; then the vision lab (localisers' speed
/// against error, where the pipeline breaks).
pub fn run_methods(progress: &Progress) -> MethodsLab {
    let dynamics =
        crate::methods::dynamics::run_dynamics_lab(crate::methods::Effort::Quick, None, progress);
    // The vision lab resets the progress total; cancelling stops it too.
    let vision = if progress.is_cancelled() {
        None
    } else {
        Some(crate::vision::lab::run_lab(
            crate::vision::lab::LabMode::Quick,
            progress,
        ))
    };
    MethodsLab { dynamics, vision }
}

/// Both labs of the Methods pane (the quick effort of `pinsight methods
/// dynamics` and `pinsight methods vision`).
#[derive(Debug, Clone)]
pub struct MethodsLab {
    pub dynamics: crate::methods::dynamics::DynamicsLab,
    /// None when the run was cancelled before the vision lab.
    pub vision: Option<crate::vision::lab::VisionLab>,
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn toml_kinds_are_told_apart_and_errors_name_the_problem() {
        let recipe = std::fs::read_to_string(
            Path::new(env!("CARGO_MANIFEST_DIR")).join("fixtures/vision/hdr-2x10.toml"),
        )
        .unwrap();
        match load_toml_text("r.toml", &recipe) {
            Loaded::Recipe(e, r) => {
                assert_eq!(e.kind, FileKind::Recipe);
                assert_eq!(r.part_number, "HDR-2x10-2.54");
            }
            other => panic!("{other:?}"),
        }
        match load_toml_text("p.toml", "preset = \"paper\"\nclearance_mm = 0.3") {
            Loaded::Params(_, p) => assert!((p.clearance - 0.3e-3).abs() < 1e-12),
            other => panic!("{other:?}"),
        }
        let e = load_toml_text("bad.toml", "clearance_mm = -1");
        assert!(e.entry().status.is_error(), "{e:?}");
        let e = load_toml_text("bad.toml", "clearnce_mm = 1");
        match &e.entry().status {
            FileStatus::Error(m) => assert!(m.contains("clearance_mm"), "{m}"),
            s => panic!("{s:?}"),
        }
        assert!(load_toml_text("x.toml", "= =").entry().status.is_error());
        assert!(
            load_toml_text("s.toml", "[[step]]\nkind=\"load\"")
                .entry()
                .status
                .is_error()
        );
    }

    #[test]
    fn missing_unknown_and_corrupt_files_become_errors() {
        let dir = tempfile::tempdir().unwrap();
        let missing = dir.path().join("nope.mcap");
        let r = load_path(&missing, &Progress::hidden());
        assert_eq!(r.len(), 1);
        assert!(r[0].entry().status.is_error());
        let odd = dir.path().join("a.xyz");
        std::fs::write(&odd, b"hello").unwrap();
        let r = load_path(&odd, &Progress::hidden());
        assert!(r[0].entry().status.is_error());
        let png = dir.path().join("broken.png");
        std::fs::write(&png, b"\x89PNG\r\n\x1a\nnot really").unwrap();
        let r = load_path(&png, &Progress::hidden());
        match &r[0].entry().status {
            FileStatus::Error(m) => assert!(m.contains("decode"), "{m}"),
            s => panic!("{s:?}"),
        }
        // A folder lists its files; ground-truth JSON is skipped quietly.
        std::fs::write(dir.path().join("truth.json"), b"{}").unwrap();
        let r = load_path(dir.path(), &Progress::hidden());
        assert_eq!(r.len(), 2, "{r:?}");
        let mut s = Session::default();
        s.absorb(r);
        assert_eq!(s.load_errors().len(), 2);
    }
}
