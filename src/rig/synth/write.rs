//! Writing a synthetic log as MCAP: chunked or not, compressed or not,
//! streamed or held in memory.

use super::*;
use mcap::records::{MessageHeader, Metadata};
use mcap::{Attachment, Compression, McapError, WriteOptions};
use std::borrow::Cow;
use std::collections::BTreeMap;
use std::io::{Seek, Write};

/// How to write the container.
#[derive(Debug, Clone, Copy)]
pub struct WriteSettings {
    pub compression: Option<Compression>,
    pub chunked: bool,
    pub chunk_size: u64,
}

impl Default for WriteSettings {
    fn default() -> Self {
        WriteSettings {
            compression: Some(Compression::Zstd),
            chunked: true,
            chunk_size: 256 * 1024,
        }
    }
}

pub(super) fn options(settings: &WriteSettings, profile: &str) -> WriteOptions {
    WriteOptions::new()
        .compression(settings.compression)
        .use_chunks(settings.chunked)
        .chunk_size(Some(settings.chunk_size))
        .profile(profile)
        .library(format!("pinsight-synth/{}", env!("CARGO_PKG_VERSION")))
}

pub(super) struct Ids {
    pub(super) channels: Vec<u16>,
    pub(super) seq: Vec<u32>,
}

pub(super) fn add_channels<W: Write + Seek>(
    w: &mut mcap::Writer<W>,
    channels: &[SynthChannel],
) -> Result<Ids, McapError> {
    let mut ids = Vec::new();
    for c in channels {
        let sid = if c.schema_name.is_empty() {
            0
        } else {
            w.add_schema(&c.schema_name, &c.schema_encoding, c.schema.as_bytes())?
        };
        ids.push(w.add_channel(sid, &c.topic, &c.message_encoding, &BTreeMap::new())?);
    }
    Ok(Ids {
        seq: vec![0; ids.len()],
        channels: ids,
    })
}

/// Writes an in-memory log (messages in the order given).
pub fn write<W: Write + Seek>(
    log: &SynthLog,
    out: W,
    settings: &WriteSettings,
) -> Result<(), McapError> {
    let mut w = options(settings, &log.profile).create(out)?;
    for (name, map) in &log.metadata {
        w.write_metadata(&Metadata {
            name: name.clone(),
            metadata: map.clone(),
        })?;
    }
    for (name, media, data) in &log.attachments {
        w.attach(&Attachment {
            log_time: log.messages.first().map_or(0, |m| m.log_time),
            create_time: 0,
            name: name.clone(),
            media_type: media.clone(),
            data: Cow::Borrowed(data),
        })?;
    }
    let mut ids = add_channels(&mut w, &log.channels)?;
    for m in &log.messages {
        let seq = &mut ids.seq[m.channel];
        *seq += 1;
        w.write_to_known_channel(
            &MessageHeader {
                channel_id: ids.channels[m.channel],
                sequence: *seq,
                log_time: m.log_time,
                publish_time: m.publish_time,
            },
            &m.data,
        )?;
    }
    w.finish()?;
    Ok(())
}

/// Writes a run straight to a file without holding it in memory (large logs).
pub fn write_streaming<W: Write + Seek>(
    cfg: &SynthConfig,
    truth: &dyn Truth,
    out: W,
    settings: &WriteSettings,
) -> Result<u64, McapError> {
    let mut w = options(settings, "").create(out)?;
    w.write_metadata(&Metadata {
        name: "rig".into(),
        metadata: cfg.rig_metadata(),
    })?;
    let mut chans = default_channels(cfg);
    if !cfg.cycle_topic {
        chans.truncate(3);
    }
    let mut ids = add_channels(&mut w, &chans)?;
    let mut err = None;
    let mut n = 0u64;
    // Blocks leave the generator when full, slightly out of log_time order;
    // that is allowed (readers sort) and exercises the sort.
    generate_with(cfg, truth, |c, lt, pt, d| {
        if err.is_some() || c >= ids.channels.len() {
            return;
        }
        ids.seq[c] += 1;
        n += 1;
        if let Err(e) = w.write_to_known_channel(
            &MessageHeader {
                channel_id: ids.channels[c],
                sequence: ids.seq[c],
                log_time: lt,
                publish_time: pt,
            },
            d,
        ) {
            err = Some(e);
        }
    });
    if let Some(e) = err {
        return Err(e);
    }
    w.finish()?;
    Ok(n)
}
