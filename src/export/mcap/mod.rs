//! Results as MCAP that Foxglove shows with no configuration (issue 17):
//! `--mcap FILE` on `overlay`, `monitor`, `inspect`, `yield` and `simulate`.
//!
//! Foxglove's own message types (`foxglove.CompressedImage`,
//! `foxglove.ImageAnnotations`) are written with the official Foxglove SDK
//! (the `foxglove` crate: its protobuf schemas, exactly as Foxglove
//! documents them); pinsight's own results (stroke samples, cycle
//! residuals, verdicts, simulation states) are JSON messages with a JSON
//! Schema named `pinsight.*`, which Foxglove's Plot, Raw Messages and
//! State Transitions panels read field by field.
//!
//! A file is built in memory ([`McapOut`]) and handed back as bytes; the
//! command writes it atomically (`crate::output::write_file`).

pub mod inspection;
pub mod monitor;
pub mod overlay;
pub mod simulation;

use foxglove::messages::Timestamp;
use foxglove::{Context, McapWriteOptions, McapWriter, McapWriterHandle, PartialMetadata, Schema};
use serde::Serialize;
use serde_json::Value;
use std::collections::HashMap;
use std::io::Cursor;
use std::sync::Arc;

/// An MCAP file being written in memory.
pub struct McapOut {
    ctx: Arc<Context>,
    writer: Option<McapWriterHandle<Cursor<Vec<u8>>>>,
    json: HashMap<String, Arc<foxglove::RawChannel>>,
}

/// A time as Foxglove's `Timestamp` (ns since the Unix epoch).
pub fn timestamp(ns: u64) -> Timestamp {
    Timestamp::new(
        (ns / 1_000_000_000).min(u32::MAX as u64) as u32,
        (ns % 1_000_000_000) as u32,
    )
}

impl McapOut {
    /// A new file (zstd chunks, with the summary Foxglove seeks with).
    pub fn new() -> Result<Self, String> {
        let ctx = Context::new();
        let options = McapWriteOptions::new()
            .compression(Some(::mcap::Compression::Zstd))
            .profile("")
            .library(format!(
                "pinsight/{} (foxglove-sdk)",
                env!("CARGO_PKG_VERSION")
            ));
        let writer = McapWriter::with_options(options)
            .context(&ctx)
            .create(Cursor::new(Vec::new()))
            .map_err(|e| format!("MCAP writer: {e}"))?;
        Ok(McapOut {
            ctx,
            writer: Some(writer),
            json: HashMap::new(),
        })
    }

    /// A typed channel (a Foxglove message type, protobuf).
    pub fn channel<T: foxglove::Encode>(&self, topic: &str) -> foxglove::Channel<T> {
        self.ctx.channel_builder(topic).build()
    }

    /// Logs a pinsight result as a JSON message on `topic` (schema `name`,
    /// a JSON Schema read from the first message).
    pub fn log_json<T: Serialize>(
        &mut self,
        topic: &str,
        name: &str,
        msg: &T,
        log_time_ns: u64,
    ) -> Result<(), String> {
        let value = serde_json::to_value(msg).map_err(|e| e.to_string())?;
        if !self.json.contains_key(topic) {
            let mut schema = json_schema_of(&value);
            schema["title"] = Value::String(name.into());
            let schema = Schema::new(
                name,
                "jsonschema",
                serde_json::to_vec(&schema).map_err(|e| e.to_string())?,
            );
            let ch = self
                .ctx
                .channel_builder(topic)
                .message_encoding("json")
                .schema(schema)
                .build_raw()
                .map_err(|e| format!("channel {topic}: {e}"))?;
            self.json.insert(topic.to_string(), ch);
        }
        let bytes = serde_json::to_vec(&value).map_err(|e| e.to_string())?;
        self.json[topic].log_with_meta(&bytes, PartialMetadata::with_log_time(log_time_ns));
        Ok(())
    }

    /// Copies records of another MCAP file (its channels and messages) in.
    pub fn copy_messages(&mut self, bytes: &[u8], prefix: &str) -> Result<u64, String> {
        let mut chans: HashMap<u16, Arc<foxglove::RawChannel>> = HashMap::new();
        let mut n = 0;
        for m in ::mcap::MessageStream::new(bytes).map_err(|e| e.to_string())? {
            let m = m.map_err(|e| format!("copying the log's messages: {e}"))?;
            let ch = match chans.entry(m.channel.id) {
                std::collections::hash_map::Entry::Occupied(e) => e.into_mut(),
                std::collections::hash_map::Entry::Vacant(e) => {
                    let mut b = self
                        .ctx
                        .channel_builder(format!("{prefix}{}", m.channel.topic))
                        .message_encoding(m.channel.message_encoding.clone());
                    if let Some(s) = &m.channel.schema {
                        b = b.schema(Schema::new(
                            s.name.clone(),
                            s.encoding.clone(),
                            s.data.to_vec(),
                        ));
                    }
                    e.insert(b.build_raw().map_err(|e| e.to_string())?)
                }
            };
            ch.log_with_meta(&m.data, PartialMetadata::with_log_time(m.log_time));
            n += 1;
        }
        Ok(n)
    }

    /// Closes the file and returns its bytes.
    pub fn finish(mut self) -> Result<Vec<u8>, String> {
        let w = self.writer.take().expect("finished once");
        w.close()
            .map(Cursor::into_inner)
            .map_err(|e| format!("MCAP writer: {e}"))
    }
}

/// A JSON Schema describing a sample message (types of its fields, nested).
fn json_schema_of(v: &Value) -> Value {
    match v {
        Value::Null => serde_json::json!({}),
        Value::Bool(_) => serde_json::json!({"type": "boolean"}),
        Value::Number(n) if n.is_f64() => serde_json::json!({"type": "number"}),
        Value::Number(_) => serde_json::json!({"type": "integer"}),
        Value::String(_) => serde_json::json!({"type": "string"}),
        Value::Array(a) => serde_json::json!({
            "type": "array",
            "items": a.first().map_or(serde_json::json!({}), json_schema_of),
        }),
        Value::Object(o) => serde_json::json!({
            "type": "object",
            "properties": o.iter().map(|(k, v)| (k.clone(), json_schema_of(v))).collect::<serde_json::Map<_, _>>(),
        }),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[derive(Serialize)]
    struct Sample {
        a: f64,
        n: u64,
        name: String,
    }

    #[test]
    fn json_messages_round_trip_through_the_mcap_crate() {
        let mut out = McapOut::new().unwrap();
        for i in 0..3u64 {
            out.log_json(
                "/pinsight/t",
                "pinsight.Sample",
                &Sample {
                    a: 0.5 * i as f64,
                    n: i,
                    name: "x".into(),
                },
                1_000 + i,
            )
            .unwrap();
        }
        let bytes = out.finish().unwrap();
        let msgs: Vec<_> = ::mcap::MessageStream::new(&bytes)
            .unwrap()
            .map(Result::unwrap)
            .collect();
        assert_eq!(msgs.len(), 3);
        assert_eq!(msgs[2].log_time, 1_002);
        let s = msgs[0].channel.schema.as_ref().unwrap();
        assert_eq!(
            (s.name.as_str(), s.encoding.as_str()),
            ("pinsight.Sample", "jsonschema")
        );
        let schema: Value = serde_json::from_slice(&s.data).unwrap();
        assert_eq!(schema["properties"]["n"]["type"], "integer");
        let v: Value = serde_json::from_slice(&msgs[1].data).unwrap();
        assert_eq!(v["a"], 0.5);
    }
}
