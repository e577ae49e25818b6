//! Protobuf: the schema is a serialized FileDescriptorSet (read with
//! `prost-reflect`) naming the message type; messages are walked on the wire
//! format, copying only the wanted fields.

use super::{Leaf, Num, Slot};
use crate::rig::mcap_read::SchemaDef;
use prost::bytes::Buf;
use prost::encoding::{WireType, decode_key, decode_varint};
use prost_reflect::{DescriptorPool, Kind, MessageDescriptor};

/// Deepest nesting walked (a hostile message cannot recurse without end).
const MAX_DEPTH: usize = 64;

#[derive(Debug, Clone)]
struct Want {
    number: u32,
    kind: Kind,
    slot: Option<usize>,
    child: Option<Node>,
}

/// The wanted fields of one message level.
#[derive(Debug, Clone, Default)]
struct Node {
    fields: Vec<Want>,
}

#[derive(Debug)]
pub struct Walker {
    root: MessageDescriptor,
    node: Node,
}

impl Walker {
    pub fn new(schema: &SchemaDef) -> Result<Self, String> {
        let pool = DescriptorPool::decode(schema.data.as_ref()).map_err(|e| {
            format!(
                "protobuf schema '{}' is not a valid FileDescriptorSet: {e}",
                schema.name
            )
        })?;
        let root = pool.get_message_by_name(&schema.name).ok_or_else(|| {
            format!(
                "protobuf schema '{}': the descriptor set has no message of that name",
                schema.name
            )
        })?;
        Ok(Walker {
            root,
            node: Node::default(),
        })
    }

    pub fn want(&mut self, fields: &[String], slot: usize) -> Result<Leaf, String> {
        let mut desc = self.root.clone();
        let mut node = &mut self.node;
        for (depth, name) in fields.iter().enumerate() {
            let f = desc.get_field_by_name(name).ok_or_else(|| {
                let names: Vec<String> = desc.fields().map(|f| f.name().to_string()).collect();
                format!(
                    "message '{}' has no field '{name}' (fields: {})",
                    desc.full_name(),
                    names.join(", ")
                )
            })?;
            let last = depth + 1 == fields.len();
            let pos = match node.fields.iter().position(|w| w.number == f.number()) {
                Some(p) => p,
                None => {
                    node.fields.push(Want {
                        number: f.number(),
                        kind: f.kind(),
                        slot: None,
                        child: None,
                    });
                    node.fields.len() - 1
                }
            };
            let w = &mut node.fields[pos];
            if last {
                w.slot = Some(slot);
                let numeric = !matches!(f.kind(), Kind::String | Kind::Bytes | Kind::Message(_));
                return Ok(Leaf {
                    slot,
                    repeated: f.is_list(),
                    numeric,
                    presence: f.supports_presence(),
                });
            }
            let Kind::Message(m) = f.kind() else {
                return Err(format!(
                    "field '{name}' of '{}' is not a message, so it has no field '{}'",
                    desc.full_name(),
                    fields[depth + 1]
                ));
            };
            if f.is_list() {
                return Err(format!(
                    "field '{name}' is repeated; only the last field of a path may be"
                ));
            }
            desc = m;
            node = w.child.get_or_insert_with(Node::default);
        }
        Err("empty field path".into())
    }

    pub fn walk(&self, data: &[u8], slots: &mut [Slot]) -> Result<(), String> {
        walk_node(&self.node, data, slots, 0).map_err(|e| format!("protobuf: {e}"))
    }
}

fn walk_node(node: &Node, mut buf: &[u8], slots: &mut [Slot], depth: usize) -> Result<(), String> {
    if depth > MAX_DEPTH {
        return Err("message nested too deep".into());
    }
    for w in &node.fields {
        if let Some(s) = w.slot {
            slots[s].parent_seen = true;
        }
    }
    while buf.has_remaining() {
        let (number, wire) = decode_key(&mut buf).map_err(|e| e.to_string())?;
        let Some(w) = node.fields.iter().find(|w| w.number == number) else {
            skip(wire, &mut buf)?;
            continue;
        };
        if let Some(child) = &w.child {
            let sub = len_delimited(wire, &mut buf)?;
            walk_node(child, sub, slots, depth + 1)?;
            continue;
        }
        let Some(s) = w.slot else {
            skip(wire, &mut buf)?;
            continue;
        };
        let slot = &mut slots[s];
        slot.seen = true;
        match &w.kind {
            Kind::String | Kind::Bytes => {
                let b = len_delimited(wire, &mut buf)?;
                slot.push_bytes(b);
            }
            Kind::Message(_) => {
                len_delimited(wire, &mut buf)?;
            }
            kind => {
                if wire == WireType::LengthDelimited {
                    // Packed repeated numbers.
                    let mut packed = len_delimited(wire, &mut buf)?;
                    let elem = element_wire(kind);
                    while packed.has_remaining() {
                        slot.nums.push(read_number(kind, elem, &mut packed)?);
                    }
                } else {
                    slot.nums.push(read_number(kind, wire, &mut buf)?);
                }
            }
        }
    }
    Ok(())
}

fn element_wire(kind: &Kind) -> WireType {
    match kind {
        Kind::Double | Kind::Fixed64 | Kind::Sfixed64 => WireType::SixtyFourBit,
        Kind::Float | Kind::Fixed32 | Kind::Sfixed32 => WireType::ThirtyTwoBit,
        _ => WireType::Varint,
    }
}

fn read_number(kind: &Kind, wire: WireType, buf: &mut &[u8]) -> Result<Num, String> {
    if wire != element_wire(kind) {
        return Err(format!(
            "a {kind:?} field sent with wire type {wire:?} (the message does not match its schema)"
        ));
    }
    let need = |n: usize, buf: &&[u8]| {
        if buf.remaining() < n {
            Err("message ends inside a number".to_string())
        } else {
            Ok(())
        }
    };
    Ok(match kind {
        Kind::Double => {
            need(8, buf)?;
            Num::F(buf.get_f64_le())
        }
        Kind::Float => {
            need(4, buf)?;
            Num::F(buf.get_f32_le() as f64)
        }
        Kind::Fixed64 => {
            need(8, buf)?;
            Num::U(buf.get_u64_le())
        }
        Kind::Sfixed64 => {
            need(8, buf)?;
            Num::I(buf.get_i64_le())
        }
        Kind::Fixed32 => {
            need(4, buf)?;
            Num::U(buf.get_u32_le() as u64)
        }
        Kind::Sfixed32 => {
            need(4, buf)?;
            Num::I(buf.get_i32_le() as i64)
        }
        _ => {
            let v = decode_varint(buf).map_err(|e| e.to_string())?;
            match kind {
                Kind::Uint64 | Kind::Uint32 => Num::U(v),
                Kind::Sint32 | Kind::Sint64 => Num::I(((v >> 1) as i64) ^ -((v & 1) as i64)),
                Kind::Bool => Num::U((v != 0) as u64),
                Kind::Int32 | Kind::Enum(_) => Num::I(v as i32 as i64),
                _ => Num::I(v as i64),
            }
        }
    })
}

fn len_delimited<'a>(wire: WireType, buf: &mut &'a [u8]) -> Result<&'a [u8], String> {
    if wire != WireType::LengthDelimited {
        return Err(format!(
            "expected a length-delimited field, found wire type {wire:?} (the message does not match its schema)"
        ));
    }
    let n = decode_varint(buf).map_err(|e| e.to_string())?;
    if n > buf.len() as u64 {
        return Err(format!(
            "a field claims {n} bytes where {} remain",
            buf.len()
        ));
    }
    let (head, rest) = buf.split_at(n as usize);
    *buf = rest;
    Ok(head)
}

fn skip(wire: WireType, buf: &mut &[u8]) -> Result<(), String> {
    match wire {
        WireType::Varint => {
            decode_varint(buf).map_err(|e| e.to_string())?;
        }
        WireType::SixtyFourBit | WireType::ThirtyTwoBit => {
            let n = if wire == WireType::SixtyFourBit { 8 } else { 4 };
            if buf.len() < n {
                return Err("message ends inside a field".into());
            }
            buf.advance(n);
        }
        WireType::LengthDelimited => {
            len_delimited(wire, buf)?;
        }
        WireType::StartGroup | WireType::EndGroup => {
            return Err("protobuf groups (proto2, deprecated) are not supported".into());
        }
    }
    Ok(())
}
