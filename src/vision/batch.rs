//! Batch inspection: inputs (image files, folders, rig logs) become items
//! `{ name, source, meta }`, each item is inspected against the recipe for
//! its part number, in parallel (rayon) with progress and cancellation.
//! An item that cannot be read or analysed becomes an `error` result with
//! its name and reason; nothing is dropped.

use super::error::{ErrorKind, VisionError};
use super::gray::Gray;
use super::recipe::Recipe;
use super::result::{Inspection, Verdict};
use super::{InspectOptions, image_io, inspect_gray};
use crate::progress::Progress;
use crate::rig::images::CAMERA_TOPIC;
use crate::rig::report::Severity;
use rayon::prelude::*;
use serde::Serialize;
use std::path::{Path, PathBuf};
use std::sync::Arc;

/// Where an item's image bytes come from.
#[derive(Debug, Clone)]
pub enum Source {
    /// An image file, read when the item is inspected.
    Path(PathBuf),
    /// Bytes in memory (e.g. a rig log's `CompressedImage.data`).
    Bytes(Arc<Vec<u8>>),
}

/// What is known about where an image came from (all optional; rig logs
/// fill them from their `rig` metadata record and `frame_id`).
#[derive(Debug, Clone, Default, PartialEq, Serialize)]
pub struct ItemMeta {
    pub lot: Option<String>,
    pub part_number: Option<String>,
    pub rig_id: Option<String>,
    pub motor_rpm: Option<f64>,
    pub clearance_mm: Option<f64>,
    pub cycle: Option<u64>,
    /// The rig log the image came from.
    pub log: Option<String>,
    /// The image's log_time in that log (ns since the Unix epoch); not in
    /// the reports (the cycle names the image there), used to stamp it in
    /// an MCAP export.
    #[serde(skip)]
    pub log_time_ns: Option<u64>,
}

/// One image to inspect.
#[derive(Debug, Clone)]
pub struct Item {
    pub name: String,
    pub source: Source,
    pub meta: ItemMeta,
}

/// Pass, fail or error.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ItemStatus {
    Pass,
    Fail,
    Error,
}

/// Why an item is `error`.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ItemError {
    pub kind: ErrorKind,
    pub message: String,
}

/// Result for one item.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ItemResult {
    pub name: String,
    pub meta: ItemMeta,
    pub status: ItemStatus,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub error: Option<ItemError>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub inspection: Option<Inspection>,
}

impl ItemResult {
    pub fn from_error(name: String, meta: ItemMeta, e: &VisionError) -> ItemResult {
        ItemResult {
            name,
            meta,
            status: ItemStatus::Error,
            error: Some(ItemError {
                kind: e.kind(),
                message: e.to_string(),
            }),
            inspection: None,
        }
    }
}

/// Image file extensions picked up when walking folders.
pub const IMAGE_EXTENSIONS: [&str; 6] = ["png", "jpg", "jpeg", "bmp", "tif", "tiff"];

fn ext_of(p: &Path) -> String {
    p.extension()
        .map(|e| e.to_string_lossy().to_lowercase())
        .unwrap_or_default()
}

/// Turns command-line inputs into items. Folders are walked recursively
/// (image files and `.mcap` logs, sorted by path); a file named
/// explicitly is always an item (so a non-image given by name is reported,
/// not skipped); a `.mcap` file yields one item per camera image. Inputs
/// that cannot be read at all become error results.
pub fn collect_items(inputs: &[PathBuf]) -> (Vec<Item>, Vec<ItemResult>) {
    let mut items = Vec::new();
    let mut errors = Vec::new();
    for input in inputs {
        let name = input.display().to_string();
        match std::fs::metadata(input) {
            Err(e) => errors.push(ItemResult::from_error(
                name,
                ItemMeta::default(),
                &VisionError::Io(e.to_string()),
            )),
            Ok(m) if m.is_dir() => {
                let mut files = Vec::new();
                walk(input, &mut files, &mut errors);
                files.sort();
                for f in files {
                    add_file(&f, &mut items, &mut errors);
                }
            }
            Ok(_) => add_file(input, &mut items, &mut errors),
        }
    }
    (items, errors)
}

fn walk(dir: &Path, files: &mut Vec<PathBuf>, errors: &mut Vec<ItemResult>) {
    let rd = match std::fs::read_dir(dir) {
        Ok(rd) => rd,
        Err(e) => {
            errors.push(ItemResult::from_error(
                dir.display().to_string(),
                ItemMeta::default(),
                &VisionError::Io(e.to_string()),
            ));
            return;
        }
    };
    for entry in rd.flatten() {
        let p = entry.path();
        if p.is_dir() {
            walk(&p, files, errors);
        } else {
            let e = ext_of(&p);
            if IMAGE_EXTENSIONS.contains(&e.as_str()) || e == "mcap" {
                files.push(p);
            }
        }
    }
}

fn add_file(path: &Path, items: &mut Vec<Item>, errors: &mut Vec<ItemResult>) {
    let name = path.display().to_string();
    if ext_of(path) != "mcap" {
        items.push(Item {
            name,
            source: Source::Path(path.to_path_buf()),
            meta: ItemMeta::default(),
        });
        return;
    }
    // The rig module's loader: crash-proof on corrupt files, recovers the
    // images before a truncation and reports what it could not read.
    match crate::rig::images::read_images_with_report(path) {
        Err(e) => errors.push(ItemResult::from_error(
            name,
            ItemMeta::default(),
            &VisionError::Io(e.to_string()),
        )),
        Ok(log) => {
            let problems: Vec<String> = log
                .findings
                .iter()
                .filter(|f| {
                    f.severity >= Severity::DataLoss
                        || f.channel
                            .as_deref()
                            .is_some_and(|c| c.starts_with(CAMERA_TOPIC))
                })
                .filter(|f| f.severity >= Severity::Warning)
                .map(|f| f.message.clone())
                .collect();
            let base = ItemMeta {
                lot: log.meta.lot.clone(),
                part_number: log.meta.part_number.clone(),
                rig_id: log.meta.rig_id.clone(),
                motor_rpm: log.meta.motor_rpm,
                clearance_mm: log.meta.clearance_mm,
                cycle: None,
                log: Some(name.clone()),
                log_time_ns: None,
            };
            if log.images.is_empty() {
                let why = if problems.is_empty() {
                    format!("no images on {CAMERA_TOPIC}")
                } else {
                    problems.join("; ")
                };
                errors.push(ItemResult::from_error(
                    name.clone(),
                    base.clone(),
                    &VisionError::Io(why),
                ));
            } else if !problems.is_empty() {
                // The images read are kept; what could not be read is listed.
                errors.push(ItemResult::from_error(
                    format!("{name} (rest of log)"),
                    base.clone(),
                    &VisionError::Io(problems.join("; ")),
                ));
            }
            for (i, img) in log.images.into_iter().enumerate() {
                let label = match img.cycle {
                    Some(c) => format!("{name}#cycle-{c}"),
                    None => format!("{name}#{i}"),
                };
                items.push(Item {
                    name: label,
                    source: Source::Bytes(Arc::new(img.data)),
                    meta: ItemMeta {
                        cycle: img.cycle,
                        log_time_ns: Some(img.log_time_ns),
                        ..base.clone()
                    },
                });
            }
        }
    }
}

/// The recipes of a run, one per part number, and the recipe files that
/// could not be used (their errors become per-image errors of the images
/// that found no recipe).
#[derive(Debug, Clone, Default)]
pub struct RecipeBook {
    pub recipes: Vec<Recipe>,
    pub invalid: Vec<String>,
}

impl RecipeBook {
    pub fn new(recipes: Vec<Recipe>) -> RecipeBook {
        RecipeBook {
            recipes,
            invalid: Vec::new(),
        }
    }

    /// Loads recipe files; invalid ones are kept as messages. A folder
    /// stands for every `*.toml` file in it (sorted by name, not recursive),
    /// so a line's recipe folder can be given as one argument.
    pub fn load(paths: &[PathBuf]) -> RecipeBook {
        let mut b = RecipeBook::default();
        for p in paths {
            if p.is_dir() {
                match std::fs::read_dir(p) {
                    Err(e) => b
                        .invalid
                        .push(format!("recipe folder {}: {e}", p.display())),
                    Ok(rd) => {
                        let mut files: Vec<PathBuf> = rd
                            .filter_map(|e| e.ok().map(|e| e.path()))
                            .filter(|f| f.is_file() && ext_of(f) == "toml")
                            .collect();
                        files.sort();
                        if files.is_empty() {
                            b.invalid
                                .push(format!("recipe folder {}: no .toml files", p.display()));
                        }
                        for f in files {
                            b.push_file(&f);
                        }
                    }
                }
            } else {
                b.push_file(p);
            }
        }
        b
    }

    fn push_file(&mut self, p: &Path) {
        match Recipe::load(p) {
            Ok(r) => self.recipes.push(r),
            Err(e) => self.invalid.push(e.to_string()),
        }
    }

    /// The recipe for an item: by the part number its log names, or the only
    /// recipe when the item names none. A part number with no recipe is the
    /// wrong part for the recipes given.
    pub fn for_item(&self, meta: &ItemMeta) -> Result<&Recipe, VisionError> {
        if self.recipes.is_empty() {
            return Err(VisionError::Recipe(if self.invalid.is_empty() {
                "no recipe given".into()
            } else {
                self.invalid.join("; ")
            }));
        }
        let also = if self.invalid.is_empty() {
            String::new()
        } else {
            format!(" (not usable: {})", self.invalid.join("; "))
        };
        match &meta.part_number {
            Some(p) => self
                .recipes
                .iter()
                .find(|r| &r.part_number == p)
                .ok_or_else(|| {
                    let have: Vec<&str> = self
                        .recipes
                        .iter()
                        .map(|r| r.part_number.as_str())
                        .collect();
                    VisionError::WrongPart {
                        part: have.join(", "),
                        msg: format!(
                            "the image is of part {p}, for which no recipe was given{also}"
                        ),
                    }
                }),
            None => match self.recipes.as_slice() {
                [r] => Ok(r),
                _ => Err(VisionError::Recipe(format!(
                    "several recipes given and the image names no part number{also}"
                ))),
            },
        }
    }
}

fn decode_item(item: &Item) -> Result<(Gray, super::gray::ImageInfo), VisionError> {
    match &item.source {
        Source::Path(p) => image_io::load_path(p),
        Source::Bytes(b) => image_io::decode_bytes(b),
    }
}

/// Inspects one item; also returns the decoded image (for overlays) when
/// `keep_image` is set and decoding succeeded.
pub fn inspect_item(
    item: &Item,
    book: &RecipeBook,
    opts: &InspectOptions,
    keep_image: bool,
) -> (ItemResult, Option<Gray>) {
    let err = |e: &VisionError| ItemResult::from_error(item.name.clone(), item.meta.clone(), e);
    // Which recipes to try: the one named by the item's part number, the
    // only one, or (several recipes, no part number) all of them.
    let candidates: Vec<&Recipe> = match book.for_item(&item.meta) {
        Ok(r) => vec![r],
        Err(e) => {
            if item.meta.part_number.is_none() && book.recipes.len() > 1 {
                book.recipes.iter().collect()
            } else {
                return (err(&e), None);
            }
        }
    };
    let (gray, info) = match decode_item(item) {
        Ok(g) => g,
        Err(e) => return (err(&e), None),
    };
    let mut best: Option<(&Recipe, Inspection)> = None;
    let mut reasons = Vec::new();
    for recipe in &candidates {
        match inspect_gray(recipe, &gray, info.clone(), opts) {
            Ok(ins) => {
                let better = match &best {
                    None => true,
                    Some((_, b)) => recognition_score(&ins) > recognition_score(b),
                };
                if better {
                    best = Some((recipe, ins));
                }
            }
            Err(e) => reasons.push(if candidates.len() > 1 {
                format!("{}: {e}", recipe.part_number)
            } else {
                e.to_string()
            }),
        }
    }
    let r = match best {
        Some((recipe, mut ins)) => {
            let mut meta = item.meta.clone();
            if meta.part_number.is_none() {
                meta.part_number = Some(recipe.part_number.clone());
            }
            if candidates.len() > 1 {
                ins.warnings.push(format!(
                    "part recognised as {} among {} recipes (most positions holding a pin)",
                    recipe.part_number,
                    candidates.len()
                ));
            }
            ItemResult {
                name: item.name.clone(),
                meta,
                status: match ins.verdict {
                    Verdict::Pass => ItemStatus::Pass,
                    Verdict::Fail => ItemStatus::Fail,
                },
                error: None,
                inspection: Some(ins),
            }
        }
        None => {
            let e = if candidates.len() == 1 {
                // Re-run to keep the typed error of the single recipe.
                match inspect_gray(candidates[0], &gray, info, opts) {
                    Err(e) => e,
                    Ok(_) => VisionError::Recipe(reasons.join("; ")),
                }
            } else {
                VisionError::WrongPart {
                    part: candidates
                        .iter()
                        .map(|r| r.part_number.as_str())
                        .collect::<Vec<_>>()
                        .join(", "),
                    msg: format!("no recipe fits the image: {}", reasons.join("; ")),
                }
            };
            err(&e)
        }
    };
    (r, keep_image.then_some(gray))
}

/// How well an inspection explains the image when the part is not named:
/// fraction of positions holding a pin, then the grid fit's residual.
fn recognition_score(ins: &Inspection) -> (u64, i64) {
    let n = ins.pins.len().max(1) as f64;
    let found = ins.pins.iter().filter(|p| p.x_px.is_some()).count() as f64;
    let inliers = ins.grid.fit_inliers as f64 / n;
    (
        (1000.0 * (found / n).min(1.0) * inliers.min(1.0)).round() as u64,
        -(1000.0 * ins.grid.fit_rms_px.min(1e6)).round() as i64,
    )
}

/// Inspects every item in parallel on rayon's pool, advancing `progress`
/// by one per item. After cancellation the items not yet started are
/// reported as `error` (cancelled), in order, so none is lost.
pub fn run_batch(
    items: &[Item],
    book: &RecipeBook,
    opts: &InspectOptions,
    progress: &Progress,
) -> Vec<ItemResult> {
    progress.set_total(progress.total().max(items.len() as u64));
    items
        .par_iter()
        .map(|item| {
            let r = if progress.is_cancelled() {
                ItemResult::from_error(
                    item.name.clone(),
                    item.meta.clone(),
                    &VisionError::Cancelled,
                )
            } else {
                inspect_item(item, book, opts, false).0
            };
            progress.inc(1);
            r
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn fixtures() -> PathBuf {
        Path::new(env!("CARGO_MANIFEST_DIR")).join("fixtures/interop")
    }

    #[test]
    fn folders_logs_and_missing_paths_become_items_or_errors() {
        let (items, errors) = collect_items(&[
            fixtures().join("images"),
            fixtures().join("logs/run-2000-images.mcap"),
            PathBuf::from("/no/such/dir"),
        ]);
        assert_eq!(
            items
                .iter()
                .filter(|i| matches!(i.source, Source::Path(_)))
                .count(),
            40
        );
        let from_log: Vec<_> = items.iter().filter(|i| i.meta.log.is_some()).collect();
        assert_eq!(from_log.len(), 10);
        assert_eq!(from_log[0].meta.motor_rpm, Some(2000.0));
        assert!(
            from_log[0].name.ends_with("#cycle-0"),
            "{}",
            from_log[0].name
        );
        assert_eq!(errors.len(), 1);
        assert_eq!(errors[0].status, ItemStatus::Error);
        assert!(errors[0].name.contains("/no/such/dir"));
    }

    #[test]
    fn a_recipe_folder_loads_every_recipe_in_it() {
        let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("fixtures/interop/images");
        let book = RecipeBook::load(std::slice::from_ref(&dir));
        let n = std::fs::read_dir(&dir)
            .unwrap()
            .filter(|e| e.as_ref().unwrap().path().extension() == Some("toml".as_ref()))
            .count();
        assert!(n >= 7);
        assert_eq!(book.recipes.len(), n, "{:?}", book.invalid);
        assert!(book.invalid.is_empty());
        let empty = tempfile::tempdir().unwrap();
        let book = RecipeBook::load(&[empty.path().to_path_buf()]);
        assert!(book.recipes.is_empty());
        assert!(
            book.invalid[0].contains("no .toml files"),
            "{:?}",
            book.invalid
        );
    }

    #[test]
    fn recipe_choice_by_part_number() {
        let dir = fixtures().join("images");
        let a = Recipe::load(&dir.join("hdr-2x10.toml")).unwrap();
        let b = Recipe::load(&dir.join("rnd-1x8.toml")).unwrap();
        let book = RecipeBook::new(vec![a.clone(), b]);
        let m = ItemMeta {
            part_number: Some("RND-1x8-1.27".into()),
            ..Default::default()
        };
        assert_eq!(book.for_item(&m).unwrap().part_number, "RND-1x8-1.27");
        let wrong = ItemMeta {
            part_number: Some("XYZ".into()),
            ..Default::default()
        };
        let e = book.for_item(&wrong).unwrap_err();
        assert_eq!(e.kind(), ErrorKind::WrongPart);
        assert!(book.for_item(&ItemMeta::default()).is_err());
        let one = RecipeBook::new(vec![a]);
        assert!(one.for_item(&ItemMeta::default()).is_ok());
        assert!(one.for_item(&wrong).is_err());
    }
}
