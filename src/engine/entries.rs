//! What loading produces: one [`FileEntry`] per opened file (its kind,
//! whether it could be used and why not) and the typed entries the jobs
//! and panes work on — rig logs with their cycles, recipes, images.
//!
//! These are the engine's inputs: the loaders in [`super::load`] make
//! them, the jobs in [`super::model`], [`super::vision`] and
//! [`super::overlay`] consume them, and the session (`panes::session`)
//! keeps them.

use super::signals::SignalSet;
use crate::model::params::Params;
use crate::rig::RigLog;
use crate::rig::cycles::CycleSet;
use crate::vision::batch::{ItemError, ItemMeta};
use serde::Serialize;
use std::path::PathBuf;
use std::sync::Arc;

/// What a file is.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum FileKind {
    RigLog,
    Image,
    Recipe,
    ProcessRecipe,
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
            FileKind::ProcessRecipe => "process",
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
    /// Why it could not be read or decoded (then `preview` is None). The
    /// image stays in the session so that every job counts it as an
    /// `error` item, as `pinsight yield` does, instead of dropping it.
    pub load_error: Option<ItemError>,
}

/// What loading one path produced.
#[derive(Debug, Clone)]
pub enum Loaded {
    /// A file listed but not used (or not usable: its entry says why).
    Entry(FileEntry),
    Params(FileEntry, Box<Params>),
    Log(FileEntry, Box<LogEntry>),
    Recipe(FileEntry, Box<RecipeEntry>),
    /// A process recipe (evaluation objects of a part's press-in curve).
    Process(FileEntry, Box<crate::process::ProcessRecipe>),
    Image(FileEntry, Box<ImageEntry>),
}

impl Loaded {
    pub fn entry(&self) -> &FileEntry {
        match self {
            Loaded::Entry(e)
            | Loaded::Params(e, _)
            | Loaded::Log(e, _)
            | Loaded::Recipe(e, _)
            | Loaded::Process(e, _)
            | Loaded::Image(e, _) => e,
        }
    }
}

pub(crate) fn entry(
    path: &str,
    kind: FileKind,
    status: FileStatus,
    detail: impl Into<String>,
) -> FileEntry {
    FileEntry {
        path: path.to_string(),
        kind,
        status,
        detail: detail.into(),
    }
}

/// Separates a log's findings in its entry's message (one finding may hold
/// semicolons of its own).
pub const FINDING_SEP: &str = " | ";
