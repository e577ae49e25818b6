//! Which channel carries what: each channel's plan (a scalar field, blocks,
//! images, ignored) from the channel map and the channel's schema.

use super::binary::BinaryCodec;
use crate::rig::channel_map::{ChannelMap, SignalKind, SignalSource};
use crate::rig::mcap_read::{ChannelDef, SchemaDef};
use std::collections::BTreeMap;
use std::sync::Arc;

/// Schema names of compressed camera images, by encoding.
pub const IMAGE_SCHEMAS: [&str; 3] = [
    "foxglove.CompressedImage",
    "sensor_msgs/msg/CompressedImage",
    "sensor_msgs/CompressedImage",
];

/// How messages of a channel are laid out.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Shape {
    Scalar,
    Block,
    /// No usable schema: decided per message.
    Auto,
}

/// One signal read from a channel.
#[derive(Debug, Clone)]
pub struct SignalPlan {
    pub kind: SignalKind,
    pub src: SignalSource,
}

/// What to do with a channel's messages.
#[derive(Debug, Clone)]
pub enum ChannelPlan {
    Signals {
        shape: Shape,
        /// Schema title (block topics name their field there).
        title: Option<String>,
        signals: Vec<SignalPlan>,
        /// Index of the first signal's buffer among all signal buffers (see [`Plans::slots`]).
        base: usize,
    },
    /// Signals of a protobuf or ROS 2 (CDR) channel.
    Binary {
        codec: Arc<BinaryCodec>,
        signals: Vec<SignalPlan>,
        /// As for `Signals`.
        base: usize,
    },
    /// Camera images (foxglove.CompressedImage in JSON); `full` keeps the decoded bytes.
    Image { full: bool },
    /// Camera images in protobuf (foxglove.CompressedImage) or ROS 2 (sensor_msgs/CompressedImage).
    BinaryImage { codec: Arc<BinaryCodec>, full: bool },
    /// Mapped, but pinsight cannot decode it: the reason (an unknown
    /// encoding, a schema that does not parse, a field the schema lacks).
    Undecodable(String),
    /// Not used: messages are only counted.
    Ignore,
}

/// Plans for all known channels, indexed by channel id (a vector, not a
/// map: one lookup per message), with one buffer slot per decoded signal.
#[derive(Debug, Clone, Default)]
pub struct Plans {
    pub(super) plans: Vec<Option<ChannelPlan>>,
    /// Per signal slot: (channel id, signal plan).
    pub(super) slots: Vec<(u16, SignalPlan)>,
}

/// Facts read from a JSON schema.
#[derive(Debug, Clone, Default)]
pub struct SchemaFacts {
    pub title: Option<String>,
    pub properties: Vec<String>,
}

impl SchemaFacts {
    pub fn from_schema(s: &SchemaDef) -> Option<Self> {
        if s.encoding != "jsonschema" {
            return None;
        }
        let v: serde_json::Value = serde_json::from_slice(&s.data).ok()?;
        let title = v.get("title").and_then(|t| t.as_str()).map(str::to_string);
        let properties = v
            .get("properties")
            .and_then(|p| p.as_object())
            .map(|o| o.keys().cloned().collect())
            .unwrap_or_default();
        Some(SchemaFacts { title, properties })
    }

    pub fn is_block(&self) -> bool {
        let has = |k: &str| self.properties.iter().any(|p| p == k);
        has("values") && (has("t0_ns") || has("dt_ns"))
    }
}

impl Plans {
    /// Builds the plan of one channel.
    pub fn plan_for(
        ch: &ChannelDef,
        schemas: &BTreeMap<u16, SchemaDef>,
        map: &ChannelMap,
        full_images: bool,
    ) -> ChannelPlan {
        let schema = schemas.get(&ch.schema_id);
        let sigs = map.signals_on(&ch.topic);
        let is_image_topic = map.images.as_deref() == Some(ch.topic.as_str());
        if sigs.is_empty() && !is_image_topic {
            return ChannelPlan::Ignore;
        }
        if BinaryCodec::handles(ch) {
            return Self::binary_plan(ch, schema, &sigs, full_images);
        }
        if ch.message_encoding != "json" {
            let schema_enc = schema.map_or("none", |s| s.encoding.as_str());
            return ChannelPlan::Undecodable(format!(
                "message encoding '{}' (schema encoding '{schema_enc}') cannot be decoded (pinsight reads json, protobuf and ros2msg/cdr)",
                ch.message_encoding
            ));
        }
        if sigs.is_empty() {
            return ChannelPlan::Image { full: full_images };
        }
        let facts = schema.and_then(SchemaFacts::from_schema);
        let shape = match &facts {
            Some(f) if f.is_block() => Shape::Block,
            Some(f) if !f.properties.is_empty() => Shape::Scalar,
            _ => Shape::Auto,
        };
        ChannelPlan::Signals {
            shape,
            title: facts.and_then(|f| f.title),
            signals: sigs
                .into_iter()
                .map(|(kind, src)| SignalPlan {
                    kind,
                    src: src.clone(),
                })
                .collect(),
            base: 0,
        }
    }

    /// The plan of a protobuf or ROS 2 channel: its codec, or why there is none.
    fn binary_plan(
        ch: &ChannelDef,
        schema: Option<&SchemaDef>,
        sigs: &[(SignalKind, &SignalSource)],
        full_images: bool,
    ) -> ChannelPlan {
        if sigs.is_empty() {
            return Self::binary_image_plan(ch, schema, full_images);
        }
        let paths: Vec<&str> = sigs.iter().map(|(_, s)| s.field.as_str()).collect();
        match BinaryCodec::for_signals(ch, schema, &paths) {
            Ok(codec) => ChannelPlan::Binary {
                codec: Arc::new(codec),
                signals: sigs
                    .iter()
                    .map(|(kind, src)| SignalPlan {
                        kind: *kind,
                        src: (*src).clone(),
                    })
                    .collect(),
                base: 0,
            },
            Err(e) => ChannelPlan::Undecodable(e),
        }
    }

    /// The plan of a protobuf or ROS 2 image channel.
    pub fn binary_image_plan(
        ch: &ChannelDef,
        schema: Option<&SchemaDef>,
        full_images: bool,
    ) -> ChannelPlan {
        match BinaryCodec::for_images(ch, schema) {
            Ok(codec) => ChannelPlan::BinaryImage {
                codec: Arc::new(codec),
                full: full_images,
            },
            Err(e) => ChannelPlan::Undecodable(format!("camera images: {e}")),
        }
    }

    pub fn build(
        channels: &BTreeMap<u16, ChannelDef>,
        schemas: &BTreeMap<u16, SchemaDef>,
        map: &ChannelMap,
        full_images: bool,
    ) -> Self {
        let mut p = Plans::default();
        for c in channels.values() {
            p.insert(c.id, Self::plan_for(c, schemas, map, full_images));
        }
        p
    }

    /// Sets the plan of a channel (signal slots are assigned here).
    pub fn insert(&mut self, id: u16, mut plan: ChannelPlan) {
        let i = id as usize;
        if self.plans.len() <= i {
            self.plans.resize(i + 1, None);
        }
        if let ChannelPlan::Signals { signals, base, .. }
        | ChannelPlan::Binary { signals, base, .. } = &mut plan
        {
            *base = self.slots.len();
            for s in signals.iter() {
                self.slots.push((id, s.clone()));
            }
        }
        self.plans[i] = Some(plan);
    }

    #[inline]
    pub fn get(&self, id: u16) -> Option<&ChannelPlan> {
        self.plans.get(id as usize).and_then(Option::as_ref)
    }

    pub fn contains(&self, id: u16) -> bool {
        self.get(id).is_some()
    }

    /// One past the largest channel id with a plan.
    pub fn channel_bound(&self) -> usize {
        self.plans.len()
    }

    /// The signal slots: (channel id, signal plan) per buffer index.
    pub fn slots(&self) -> &[(u16, SignalPlan)] {
        &self.slots
    }
}
