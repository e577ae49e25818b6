//! Loading every kind of input into typed entries, never panicking.
//!
//! One function, [`load_path`], recognises rig logs (`.mcap`), connector
//! images, recipe TOML files (`part_number` and `view`), parameter TOML
//! files and folders (their files, one level deep), and records a
//! [`FileEntry`] with the error for every file it could not use. Loading is
//! a pure function returning [`Loaded`] items, so the TUI runs it on a
//! worker thread and merges the result into its session on the UI thread;
//! batch mode and `render` call the same functions in a row.

use super::entries::{
    FINDING_SEP, FileKind, FileStatus, ImageEntry, ImageSource, Loaded, LogEntry, RecipeEntry,
    entry,
};
use super::signals::{Channel, SignalSet};
use crate::model::params::Params;
use crate::progress::Progress;
use crate::rig::cycles::CycleOptions;
use crate::rig::{LoadOptions, LoadStatus, RigLog, Severity};
use crate::vision::VisionError;
use crate::vision::batch::{ItemError, ItemMeta};
use std::path::{Path, PathBuf};
use std::sync::Arc;

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
        e if IMAGE_EXTS.contains(&e) => {
            let source = ImageSource::File(path.to_path_buf());
            match crate::input::read_bounded(path, crate::input::IMAGE_MAX_BYTES) {
                Ok(bytes) => vec![load_image_bytes(&shown, source, &bytes)],
                Err(e) => vec![failed_image(
                    &shown,
                    source,
                    ItemMeta::default(),
                    &VisionError::Io(e.to_string()),
                )],
            }
        }
        "toml" => match crate::input::read_text(path) {
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

/// The entries of a loaded log: the log itself (status from its load
/// report and cycle findings), its images (decoded from `path` when the
/// log is a file), its attached recipes.
fn log_items(shown: &str, log: RigLog, path: Option<&Path>) -> Vec<Loaded> {
    let mut out = Vec::new();
    let cycles = super::overlay::cycles_of(
        &log,
        &Params::paper(),
        CycleOptions::default().points_per_rev,
    );
    let t0 = log.log_start_ns.unwrap_or(0);
    let secs = |t: i64| (t - t0) as f64 * 1e-9;
    let mut channels = Vec::new();
    for k in crate::rig::SignalKind::ALL {
        if k == crate::rig::SignalKind::Cycle {
            continue; // shown as cycle markers
        }
        if let Some(sig) = log.signals.get(k) {
            channels.push(Channel::new(
                k.name(),
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
        log_time_ns: None,
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
            log_time_ns: Some(r.log_time_ns),
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
            Err(m) => out.push(failed_image(
                &name,
                ImageSource::Bytes(Arc::new(Vec::new())),
                meta,
                &VisionError::Io(m),
            )),
        }
    }
    out
}

/// A finding's message without the file name it starts with (the Session
/// pane lists it under the file already).
fn strip_file(msg: &str, file: &str) -> String {
    msg.strip_prefix(file)
        .map(|r| r.trim_start_matches([':', ' ']).to_string())
        .unwrap_or_else(|| msg.to_string())
}

/// Decodes an image (bytes from a file, the demo or a log) into an entry
/// with a display preview. An image that cannot be decoded is still an
/// image entry, carrying the vision library's own reason (the message and
/// kind `pinsight inspect` and `pinsight yield` give), so the yield counts
/// it as an `error` item.
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
                    load_error: None,
                }),
            )
        }
        Ok(Err(_)) | Err(_) => {
            // The vision decoder says why in the words of `inspect`/`yield`
            // (empty file, not an image, what an absurd header claims …).
            let e = match crate::vision::image_io::decode_bytes(bytes) {
                Err(e) => e,
                Ok(_) => VisionError::Decode {
                    format: "image".into(),
                    msg: "the display decoder failed".into(),
                },
            };
            failed_image(name, source, ItemMeta::default(), &e)
        }
    }
}

/// An image that could not be read: an error entry for the Session pane and
/// an image entry that carries the error to every job.
pub fn failed_image(name: &str, source: ImageSource, meta: ItemMeta, e: &VisionError) -> Loaded {
    let message = one_line(&e.to_string());
    Loaded::Image(
        entry(
            name,
            FileKind::Image,
            FileStatus::Error(message.clone()),
            "",
        ),
        Box::new(ImageEntry {
            name: name.to_string(),
            source,
            width: 0,
            height: 0,
            preview: None,
            meta,
            load_error: Some(ItemError {
                kind: e.kind(),
                message,
            }),
        }),
    )
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
    let process_keys = ["window", "threshold", "envelope", "value", "spc"];
    if table.contains_key("part_number")
        && !table.contains_key("view")
        && process_keys.iter().any(|k| table.contains_key(*k))
    {
        return match crate::process::ProcessRecipe::from_toml_str(text, name) {
            Ok(r) => Loaded::Process(
                entry(
                    name,
                    FileKind::ProcessRecipe,
                    FileStatus::Loaded,
                    format!(
                        "process recipe, part {}: {} object(s){}",
                        r.part_number,
                        r.object_count(),
                        if r.envelope.iter().any(|e| e.x_grid.is_empty()) {
                            " (an envelope not learned yet: `pinsight monitor LOG --process FILE --learn N`)"
                        } else {
                            ""
                        }
                    ),
                ),
                Box::new(r),
            ),
            Err(e) => Loaded::Entry(entry(
                name,
                FileKind::ProcessRecipe,
                FileStatus::Error(one_line(&e.to_string())),
                "",
            )),
        };
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
            // The words `pinsight yield` warns with ("invalid recipe FILE: …").
            Err(e) => Loaded::Entry(entry(
                name,
                FileKind::Recipe,
                FileStatus::Error(one_line(&e.to_string())),
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
}
