//! Inspected connectors as MCAP: each image with its annotations, so
//! Foxglove's Image panel shows the verdict on the part.
//!
//! Topics:
//! - `/camera/connector` (`foxglove.CompressedImage`): the image as
//!   inspected (the file's bytes, or the rig log's message data);
//!   `frame_id` is the item's name.
//! - `/camera/connector/annotations` (`foxglove.ImageAnnotations`): per
//!   grid position a circle of the position tolerance around the fitted
//!   nominal point (green ok, red defective, orange missing) and a dot at
//!   the measured centre; the fitted grid as a line list through the
//!   nominal points of each row and column; extras as magenta circles; the
//!   verdict and each defect's status as text.
//! - `/pinsight/inspection` (`pinsight.Inspection`, JSON): the item's
//!   status, verdict, status counts and where it came from.
//!
//! Times: a rig log's image keeps its log_time; an image file is stamped
//! one second after the previous item, from the Unix epoch (an image folder
//! has no clock; Foxglove steps through the items in order).

use super::{McapOut, timestamp};
use crate::vision::batch::{Item, ItemResult, Source};
use crate::vision::result::{Inspection, PinStatus};
use foxglove::messages::{
    CircleAnnotation, Color, CompressedImage, ImageAnnotations, Point2, PointsAnnotation,
    TextAnnotation, points_annotation,
};
use serde::Serialize;

/// One inspected image to write.
pub struct Frame<'a> {
    pub result: &'a ItemResult,
    /// The image's encoded bytes and format (`png`, `jpeg`, …), when readable.
    pub image: Option<(Vec<u8>, String)>,
    /// The rig log's log_time of the image, if it came from one.
    pub log_time_ns: Option<u64>,
}

impl<'a> Frame<'a> {
    /// The frame of an inspected item: its image bytes read again (a file)
    /// or shared (a rig log's image), and its log time. `item` is None for
    /// an input that never became an image (it gets no image message).
    pub fn of(item: Option<&Item>, result: &'a ItemResult) -> Frame<'a> {
        let bytes = item.and_then(|it| match &it.source {
            Source::Path(p) => crate::input::read_bounded(p, crate::input::IMAGE_MAX_BYTES).ok(),
            Source::Bytes(b) => Some(b.as_ref().clone()),
        });
        let image = bytes.map(|b| {
            let format = image::guess_format(&b)
                .ok()
                .and_then(|f| f.extensions_str().first().copied())
                .map_or_else(
                    || "unknown".to_string(),
                    |e| {
                        if e == "jpg" {
                            "jpeg".into()
                        } else {
                            e.to_string()
                        }
                    },
                );
            (b, format)
        });
        Frame {
            result,
            image,
            log_time_ns: result.meta.log_time_ns,
        }
    }
}

/// A colour from its red, green, blue and alpha in [0, 1].
const fn rgba(r: f64, g: f64, b: f64, a: f64) -> Color {
    Color { r, g, b, a }
}

const GREEN: Color = rgba(0.1, 0.8, 0.2, 1.0);
const RED: Color = rgba(0.95, 0.15, 0.1, 1.0);
const ORANGE: Color = rgba(1.0, 0.6, 0.0, 1.0);
const MAGENTA: Color = rgba(0.9, 0.1, 0.9, 1.0);
const CYAN: Color = rgba(0.1, 0.7, 0.9, 0.8);
const CLEAR: Color = rgba(0.0, 0.0, 0.0, 0.0);
const BACKDROP: Color = rgba(0.0, 0.0, 0.0, 0.6);

fn colour(s: PinStatus) -> Color {
    match s {
        PinStatus::Ok => GREEN,
        PinStatus::Missing => ORANGE,
        _ => RED,
    }
}

fn point(x: f64, y: f64) -> Option<Point2> {
    Some(Point2 { x, y })
}

/// The annotations of one inspection (pixel coordinates of the image).
pub fn annotations(ins: &Inspection, t_ns: u64) -> ImageAnnotations {
    let ts = Some(timestamp(t_ns));
    let mm_px = ins.grid.mm_per_px.max(1e-9);
    let tol_d = 2.0 * ins.tolerance.position_mm / mm_px;
    let mut circles = Vec::new();
    let mut texts = Vec::new();
    let mut dots = Vec::new();
    let mut dot_colours = Vec::new();
    for p in &ins.pins {
        let c = colour(p.status);
        circles.push(CircleAnnotation {
            timestamp: ts,
            position: point(p.nominal_x_px, p.nominal_y_px),
            diameter: tol_d,
            thickness: 1.5,
            fill_color: Some(CLEAR),
            outline_color: Some(c),
            metadata: Vec::new(),
        });
        if let (Some(x), Some(y)) = (p.x_px, p.y_px) {
            dots.push(Point2 { x, y });
            dot_colours.push(c);
        }
        if p.status != PinStatus::Ok {
            texts.push(TextAnnotation {
                timestamp: ts,
                position: point(p.nominal_x_px + 0.6 * tol_d, p.nominal_y_px),
                text: format!("r{}c{} {}", p.row, p.col, p.status.as_str()),
                font_size: 12.0,
                text_color: Some(c),
                background_color: Some(BACKDROP),
                metadata: Vec::new(),
            });
        }
    }
    for e in &ins.extras {
        circles.push(CircleAnnotation {
            timestamp: ts,
            position: point(e.x_px, e.y_px),
            diameter: tol_d,
            thickness: 2.0,
            fill_color: Some(CLEAR),
            outline_color: Some(MAGENTA),
            metadata: Vec::new(),
        });
    }
    let mut points = vec![PointsAnnotation {
        timestamp: ts,
        r#type: points_annotation::Type::Points as i32,
        points: dots,
        outline_color: None,
        outline_colors: dot_colours,
        fill_color: None,
        thickness: 4.0,
        metadata: Vec::new(),
    }];
    // The fitted grid: a segment along each row and each column.
    let mut lines = Vec::new();
    let rows: std::collections::BTreeSet<u32> = ins.pins.iter().map(|p| p.row).collect();
    let cols: std::collections::BTreeSet<u32> = ins.pins.iter().map(|p| p.col).collect();
    let ends = |sel: &dyn Fn(&&crate::vision::result::PinResult) -> bool,
                key: &dyn Fn(&crate::vision::result::PinResult) -> u32| {
        let mut on: Vec<_> = ins.pins.iter().filter(sel).collect();
        on.sort_by_key(|p| key(p));
        match (on.first(), on.last()) {
            (Some(a), Some(b)) if on.len() > 1 => Some([
                Point2 {
                    x: a.nominal_x_px,
                    y: a.nominal_y_px,
                },
                Point2 {
                    x: b.nominal_x_px,
                    y: b.nominal_y_px,
                },
            ]),
            _ => None,
        }
    };
    for r in &rows {
        lines.extend(ends(&|p| p.row == *r, &|p| p.col).into_iter().flatten());
    }
    for c in &cols {
        lines.extend(ends(&|p| p.col == *c, &|p| p.row).into_iter().flatten());
    }
    points.push(PointsAnnotation {
        timestamp: ts,
        r#type: points_annotation::Type::LineList as i32,
        points: lines,
        outline_color: Some(CYAN),
        outline_colors: Vec::new(),
        fill_color: None,
        thickness: 1.0,
        metadata: Vec::new(),
    });
    let c = &ins.counts;
    texts.push(TextAnnotation {
        timestamp: ts,
        position: point(8.0, 20.0),
        text: format!(
            "{} {}: {} pins ok of {}, {} extras",
            ins.part_number,
            if ins.verdict == crate::vision::result::Verdict::Pass {
                "PASS"
            } else {
                "FAIL"
            },
            c.ok,
            ins.pins.len(),
            ins.extras.len()
        ),
        font_size: 16.0,
        text_color: Some(if ins.verdict == crate::vision::result::Verdict::Pass {
            GREEN
        } else {
            RED
        }),
        background_color: Some(BACKDROP),
        metadata: Vec::new(),
    });
    ImageAnnotations {
        timestamp: ts,
        circles,
        points,
        texts,
        metadata: Vec::new(),
    }
}

#[derive(Serialize)]
struct Summary<'a> {
    name: &'a str,
    status: &'a crate::vision::batch::ItemStatus,
    verdict: Option<&'a crate::vision::result::Verdict>,
    part_number: Option<&'a str>,
    counts: Option<&'a crate::vision::result::StatusCounts>,
    extras: usize,
    error: Option<&'a str>,
    meta: &'a crate::vision::batch::ItemMeta,
}

/// Builds the MCAP of a batch of inspected images (in the order given).
pub fn inspections_mcap(frames: &[Frame<'_>]) -> Result<Vec<u8>, String> {
    let mut out = McapOut::new()?;
    let images = out.channel::<CompressedImage>("/camera/connector");
    let notes = out.channel::<ImageAnnotations>("/camera/connector/annotations");
    let mut clock = 0u64;
    for f in frames {
        let r = f.result;
        let t = f.log_time_ns.unwrap_or_else(|| {
            clock += 1_000_000_000;
            clock
        });
        if let Some((bytes, format)) = &f.image {
            images.log_with_time(
                &CompressedImage {
                    timestamp: Some(timestamp(t)),
                    frame_id: r.name.clone(),
                    data: bytes.clone().into(),
                    format: format.clone(),
                },
                t,
            );
        }
        if let Some(ins) = &r.inspection {
            notes.log_with_time(&annotations(ins, t), t);
        }
        let ins = r.inspection.as_ref();
        out.log_json(
            "/pinsight/inspection",
            "pinsight.Inspection",
            &Summary {
                name: &r.name,
                status: &r.status,
                verdict: ins.map(|i| &i.verdict),
                part_number: ins.map(|i| i.part_number.as_str()),
                counts: ins.map(|i| &i.counts),
                extras: ins.map_or(0, |i| i.extras.len()),
                error: r.error.as_ref().map(|e| e.message.as_str()),
                meta: &r.meta,
            },
            t,
        )?;
    }
    out.finish()
}
