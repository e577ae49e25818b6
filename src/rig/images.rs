//! Connector images on the camera topic (`/camera/connector`,
//! `foxglove.CompressedImage` in JSON with base64 `data`).
//!
//! [`read_images`] decodes every image of a log (for the vision pipeline);
//! [`crate::rig::load`] only lists them ([`ImageRef`], with the file offset
//! of the chunk holding each) so a large log's images are not all held in
//! memory; [`read_image`] decodes one of them on demand by re-reading just
//! its chunk.

use super::decode::{ChannelPlan, Decoder, ImageEntry, Plans};
use super::error::LogError;
use super::load::{ImageRef, LoadOptions, load_inner};
use super::mcap_read::{self, ReadOptions, Scratch, Source};
use super::meta::RigMeta;
use super::report::{Finding, LoadStatus};
use crate::progress::Progress;
use serde::Serialize;
use std::path::Path;
use std::sync::Arc;

pub use super::channel_map::CAMERA_TOPIC;

/// One decoded image.
#[derive(Debug, Clone, Serialize)]
pub struct LogImage {
    /// Cycle index from `frame_id` = `cycle-<index>`, when the rig knew it.
    pub cycle: Option<u64>,
    /// log_time of the message (ns since the Unix epoch).
    pub log_time_ns: u64,
    pub frame_id: String,
    /// `png`, `jpeg`, ...
    pub format: String,
    /// The image file's bytes (base64-decoded), not serialised.
    #[serde(skip)]
    pub data: Vec<u8>,
}

/// Images of a log with what went wrong reading them.
#[derive(Debug, Clone, Serialize)]
pub struct ImageRead {
    pub meta: RigMeta,
    pub images: Vec<LogImage>,
    /// Load status of the whole file (partial when it is truncated, ...).
    pub status: LoadStatus,
    /// Every finding of the load (unusable images among them).
    pub findings: Vec<Finding>,
}

fn to_image(e: ImageEntry) -> Option<LogImage> {
    let data = e.data?;
    Some(LogImage {
        cycle: e
            .frame_id
            .strip_prefix("cycle-")
            .and_then(|s| s.trim().parse().ok()),
        log_time_ns: e.log_time,
        frame_id: e.frame_id,
        format: e.format,
        data,
    })
}

/// Every image of the log, in log_time order, with the `rig` metadata.
/// Images that cannot be decoded (bad base64, not JSON) are left out; use
/// [`read_images_with_report`] to learn about them.
pub fn read_images(path: &Path) -> Result<(RigMeta, Vec<LogImage>), LogError> {
    let r = read_images_with_report(path)?;
    Ok((r.meta, r.images))
}

/// [`read_images`] with the load report's status and findings.
pub fn read_images_with_report(path: &Path) -> Result<ImageRead, LogError> {
    let src = Source::open(path)?;
    let opts = LoadOptions::default();
    let (log, entries) = load_inner(&src, &opts, &Progress::hidden(), true)?;
    let images = entries.into_iter().filter_map(to_image).collect();
    Ok(ImageRead {
        meta: log.meta,
        images,
        status: log.report.status,
        findings: log.report.findings,
    })
}

/// Decodes one image listed by [`crate::rig::load`] (re-reads only its chunk).
pub fn read_image(path: &Path, r: &ImageRef) -> Result<LogImage, LogError> {
    let src = Source::open(path)?;
    let file = src.name().to_string();
    let b = src.bytes();
    let item = mcap_read::item_at(b, r.item_offset).ok_or_else(|| LogError::NotFound {
        file: file.clone(),
        message: format!("no chunk or message record at byte {}", r.item_offset),
    })?;
    let mut plans = Plans::default();
    plans.insert(
        r.channel_id,
        match &r.codec {
            Some(codec) => ChannelPlan::BinaryImage {
                codec: codec.clone(),
                full: true,
            },
            None => ChannelPlan::Image { full: true },
        },
    );
    let mut dec = Decoder::new(Arc::new(plans), item.offset);
    let out = mcap_read::decode_item(
        b,
        &item,
        &ReadOptions::default(),
        &mut Scratch::default(),
        &mut dec,
    );
    if let Some(p) = out.problem.filter(|p| p.discard) {
        return Err(LogError::Unreadable {
            file,
            message: p.text,
        });
    }
    let entry = dec
        .out
        .images
        .into_iter()
        .find(|e| e.log_time == r.log_time_ns && e.frame_id == r.frame_id)
        .ok_or_else(|| LogError::NotFound {
            file: file.clone(),
            message: format!(
                "no image at log_time {} in the record at byte {}",
                r.log_time_ns, r.item_offset
            ),
        })?;
    if let Some(err) = &entry.error {
        return Err(LogError::Unreadable {
            file,
            message: format!("image at log_time {}: {err}", r.log_time_ns),
        });
    }
    to_image(entry).ok_or_else(|| LogError::NotFound {
        file,
        message: format!("image at log_time {} has no data", r.log_time_ns),
    })
}
