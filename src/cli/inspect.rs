//! `pinsight inspect`: inspect connector images against a recipe.
//!
//! Prints, per image, the verdict and a row per pin (row, col, status,
//! position, offset, tip area ratio or height) and the extras; `--json`
//! prints the same as JSON; `--out DIR` writes an annotated overlay PNG per
//! image and `inspection.json`.
//!
//! Exit status: 0 every connector passed, 1 at least one failed, 3 at least
//! one image could not be inspected (its reason is printed), 2 the command
//! itself failed.

use crate::vision::batch::{self, ItemResult, ItemStatus, RecipeBook};
use crate::vision::overlay::{OverlayOptions, draw_overlay};
use crate::vision::{InspectOptions, Localiser, View};
use anyhow::Context;
use std::io::Write;
use std::path::PathBuf;
use std::process::ExitCode;

#[derive(Debug, clap::Args)]
pub struct Args {
    /// Recipe (TOML) of the part in the images. Repeat it for several part
    /// numbers: rig-log images pick the recipe of the part their log names.
    #[arg(long, short = 'r', required = true)]
    pub recipe: Vec<PathBuf>,
    /// Images (PNG, JPEG, BMP, TIFF; 8/16 bit, grey or colour), folders of
    /// them, or rig logs (.mcap, images on /camera/connector).
    #[arg(required = true)]
    pub images: Vec<PathBuf>,
    /// Write an annotated overlay per image (NAME.overlay.png) and
    /// inspection.json into this folder.
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// Print JSON (one result per image) instead of tables.
    #[arg(long)]
    pub json: bool,
    /// Magnification of pin offsets in the overlays.
    #[arg(long, default_value_t = 10.0, value_parser = super::common::bounds::magnify)]
    pub magnify: f64,
    /// Centre estimator for top-view tips.
    #[arg(long, value_enum, default_value_t = LocaliserArg::Coverage)]
    pub localiser: LocaliserArg,
    /// Run only shard K of N (K from 0) of the sorted inputs; default from
    /// the cluster's environment (docs/scale.md).
    #[arg(long, value_name = "K/N")]
    pub shard: Option<String>,
    /// Also write every image with its annotations (pins, grid, verdict) as MCAP for Foxglove.
    #[arg(long, value_name = "FILE")]
    pub mcap: Option<PathBuf>,
}

/// Command-line names of the localisers.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum LocaliserArg {
    Centroid,
    Weighted,
    Coverage,
}

impl From<LocaliserArg> for Localiser {
    fn from(a: LocaliserArg) -> Localiser {
        match a {
            LocaliserArg::Centroid => Localiser::Centroid,
            LocaliserArg::Weighted => Localiser::Weighted,
            LocaliserArg::Coverage => Localiser::Coverage,
        }
    }
}

/// A file name for an item's overlay (log items have `#cycle-k` in their name).
fn overlay_name(name: &str) -> String {
    let base = std::path::Path::new(name.split('#').next().unwrap_or(name))
        .file_stem()
        .map(|s| s.to_string_lossy().to_string())
        .unwrap_or_else(|| "image".into());
    match name.split_once('#') {
        Some((_, tail)) => format!("{base}-{}.overlay.png", tail.replace(['/', '\\'], "_")),
        None => format!("{base}.overlay.png"),
    }
}

fn f(v: Option<f64>, d: usize) -> String {
    v.map(|v| format!("{v:.d$}")).unwrap_or_else(|| "–".into())
}

/// Human-readable lines for one result.
pub fn text_report(r: &ItemResult) -> String {
    use std::fmt::Write as _;
    let mut s = String::new();
    let Some(ins) = &r.inspection else {
        let msg = r
            .error
            .as_ref()
            .map(|e| e.message.as_str())
            .unwrap_or("unknown error");
        let _ = writeln!(s, "{}: ERROR {msg}", r.name);
        return s;
    };
    let c = &ins.counts;
    let mut parts = vec![format!("ok {}", c.ok)];
    for (n, v) in [
        ("missing", c.missing),
        ("damaged", c.damaged),
        ("bent", c.bent),
        ("short", c.short),
        ("high", c.high),
    ] {
        if v > 0 {
            parts.push(format!("{n} {v}"));
        }
    }
    let _ = writeln!(
        s,
        "{}: {}  ({}, {} pins: {}; extras {})  grid: rotation {:.2}°, {:.5} mm/px{}, fit rms {:.3} px",
        r.name,
        if matches!(r.status, ItemStatus::Pass) {
            "PASS"
        } else {
            "FAIL"
        },
        ins.part_number,
        ins.pins.len(),
        parts.join(", "),
        ins.extras.len(),
        ins.grid.rotation_deg,
        ins.grid.mm_per_px,
        if ins.grid.mm_per_px_estimated {
            " (estimated)"
        } else {
            ""
        },
        ins.grid.fit_rms_px
    );
    let side = ins.view == View::Side;
    let _ = writeln!(
        s,
        "  row col status      x_px      y_px    dx_mm    dy_mm  {}",
        if side { "height_mm" } else { "area_ratio" }
    );
    for p in &ins.pins {
        let _ = writeln!(
            s,
            "  {:3} {:3} {:8} {:>9} {:>9} {:>8} {:>8}  {:>9}",
            p.row,
            p.col,
            p.status.as_str(),
            f(p.x_px, 3),
            f(p.y_px, 3),
            f(p.dx_mm, 4),
            f(p.dy_mm, 4),
            if side {
                f(p.height_mm, 4)
            } else {
                f(p.area_ratio, 3)
            }
        );
    }
    for e in &ins.extras {
        let _ = writeln!(
            s,
            "  extra at ({:.1}, {:.1}) px, area {:.2} of a tip{}",
            e.x_px,
            e.y_px,
            e.area_ratio,
            e.distance_mm
                .map(|d| format!(", {d:.2} mm from the housing"))
                .unwrap_or_default()
        );
    }
    for w in &ins.failed_because {
        let _ = writeln!(s, "  why: {w}");
    }
    for w in &ins.warnings {
        let _ = writeln!(s, "  note: {w}");
    }
    s
}

pub fn run(args: Args) -> anyhow::Result<ExitCode> {
    let book = RecipeBook::load(&args.recipe);
    for e in &book.invalid {
        eprintln!("warning: {e}");
    }
    let opts = InspectOptions {
        localiser: args.localiser.into(),
    };
    let (items, results) = batch::collect_items(&args.images);
    let shard =
        crate::plant::shard::Shard::resolve(args.shard.as_deref()).map_err(anyhow::Error::msg)?;
    let (items, mut results) = crate::plant::shard::split_collected(shard, items, results);
    let unreadable = results.len();
    if let Some(dir) = &args.out {
        std::fs::create_dir_all(dir).with_context(|| format!("cannot create {}", dir.display()))?;
    }
    let ov = OverlayOptions {
        magnify: args.magnify,
        ..Default::default()
    };
    let mut out = crate::cli::common::stdout();
    for r in &results {
        if !args.json {
            write!(out, "{}", text_report(r))?;
        }
    }
    // Overlays are staged as they are drawn (not held in memory) and
    // replace an older set, with inspection.json, only when all are written.
    let mut report = match &args.out {
        Some(dir) => Some(crate::output::Report::new_in(dir)?),
        None => None,
    };
    let mut used_names = std::collections::HashSet::new();
    for item in &items {
        let (r, gray) = batch::inspect_item(item, &book, &opts, args.out.is_some());
        if let (Some(rep), Some(g), Some(ins)) =
            (report.as_mut(), gray.as_ref(), r.inspection.as_ref())
        {
            let img = draw_overlay(g, ins, &ov);
            // Two inputs with the same stem (a/x.png, b/x.png, x.jpg) must
            // not overwrite each other's overlay.
            let mut name = overlay_name(&r.name);
            let mut k = 2;
            while !used_names.insert(name.clone()) {
                name = format!(
                    "{}-{k}.overlay.png",
                    overlay_name(&r.name).trim_end_matches(".overlay.png")
                );
                k += 1;
            }
            let mut png = std::io::Cursor::new(Vec::new());
            img.write_to(&mut png, image::ImageFormat::Png)
                .with_context(|| format!("cannot encode {name}"))?;
            rep.add(&name, png.get_ref())?;
        }
        if !args.json {
            write!(out, "{}", text_report(&r))?;
        }
        results.push(r);
    }
    if args.json {
        serde_json::to_writer_pretty(&mut out, &results)?;
        writeln!(out)?;
    }
    if let Some(mut rep) = report {
        rep.add("inspection.json", &serde_json::to_vec_pretty(&results)?)?;
        rep.commit()?;
    }
    if let Some(file) = &args.mcap {
        use crate::export::mcap::inspection::{Frame, inspections_mcap};
        // The inputs that never became images come first, then one result per item.
        let frames: Vec<Frame> = results
            .iter()
            .enumerate()
            .map(|(i, r)| Frame::of(i.checked_sub(unreadable).and_then(|k| items.get(k)), r))
            .collect();
        let bytes =
            inspections_mcap(&frames).map_err(|e| anyhow::anyhow!("{}: {e}", file.display()))?;
        crate::output::write_file(file, &bytes)?;
    }
    let errors = results
        .iter()
        .filter(|r| r.status == ItemStatus::Error)
        .count();
    let fails = results
        .iter()
        .filter(|r| r.status == ItemStatus::Fail)
        .count();
    Ok(if errors > 0 {
        ExitCode::from(3)
    } else if fails > 0 {
        ExitCode::from(1)
    } else {
        ExitCode::SUCCESS
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn overlay_names() {
        assert_eq!(overlay_name("dir/a.png"), "a.overlay.png");
        assert_eq!(
            overlay_name("logs/run.mcap#cycle-3"),
            "run-cycle-3.overlay.png"
        );
    }
}
