//! ROS 2: `ros2msg` schema text (the message definition with its
//! dependencies after `====` / `MSG: pkg/Type` separators, parsed by
//! `re_ros_msg`) and `cdr` messages: a 4-byte encapsulation header, then
//! plain CDR, little- or big-endian (read with `re_cdr`). XCDR2 and
//! parameter-list encapsulations are refused with their name.

use super::{Leaf, Num, Slot};
use crate::rig::mcap_read::SchemaDef;
use re_cdr::{BigEndian, ByteOrder, CdrReader, LittleEndian};
use re_ros_msg::MessageSchema;
use re_ros_msg::message_spec::{ArraySize, BuiltInType, ComplexType, MessageSpecification, Type};
use std::collections::HashMap;
use std::sync::Arc;

/// Deepest nesting of message types compiled.
const MAX_DEPTH: usize = 32;

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Prim {
    Bool,
    U8,
    I8,
    I16,
    U16,
    I32,
    U32,
    I64,
    U64,
    F32,
    F64,
}

impl Prim {
    fn size(self) -> usize {
        match self {
            Prim::Bool | Prim::U8 | Prim::I8 => 1,
            Prim::I16 | Prim::U16 => 2,
            Prim::I32 | Prim::U32 | Prim::F32 => 4,
            Prim::I64 | Prim::U64 | Prim::F64 => 8,
        }
    }
}

#[derive(Debug, Clone)]
enum Ty {
    Prim(Prim),
    Str,
    Array { elem: Box<Ty>, fixed: Option<usize> },
    Struct(Arc<Struct>),
}

#[derive(Debug)]
struct Struct {
    name: String,
    fields: Vec<(String, Ty)>,
}

#[derive(Debug, Clone, Default)]
struct Want {
    slot: Option<usize>,
    child: Option<Node>,
}

/// Wanted fields of one message level, by field position.
#[derive(Debug, Clone, Default)]
struct Node {
    by_field: Vec<Option<Want>>,
}

#[derive(Debug)]
pub struct Walker {
    root: Arc<Struct>,
    node: Node,
}

/// `pkg/msg/Type` and `pkg/Type` name the same type.
fn normal(name: &str) -> String {
    name.replace("/msg/", "/")
}

fn prim(b: &BuiltInType) -> Option<Prim> {
    Some(match b {
        BuiltInType::Bool => Prim::Bool,
        BuiltInType::Byte | BuiltInType::Char | BuiltInType::UInt8 => Prim::U8,
        BuiltInType::Int8 => Prim::I8,
        BuiltInType::Int16 => Prim::I16,
        BuiltInType::UInt16 => Prim::U16,
        BuiltInType::Int32 => Prim::I32,
        BuiltInType::UInt32 => Prim::U32,
        BuiltInType::Int64 => Prim::I64,
        BuiltInType::UInt64 => Prim::U64,
        BuiltInType::Float32 => Prim::F32,
        BuiltInType::Float64 => Prim::F64,
        BuiltInType::String(_) | BuiltInType::WString(_) => return None,
    })
}

struct Compiler<'a> {
    specs: HashMap<String, &'a MessageSpecification>,
}

impl Compiler<'_> {
    fn builtin(b: &BuiltInType) -> Result<Ty, String> {
        match b {
            BuiltInType::WString(_) => Err("wstring fields are not supported".into()),
            BuiltInType::String(_) => Ok(Ty::Str),
            other => Ok(Ty::Prim(prim(other).expect("a number type"))),
        }
    }

    fn ty(&self, scope: &str, t: &Type, depth: usize) -> Result<Ty, String> {
        Ok(match t {
            Type::BuiltIn(b) => Self::builtin(b)?,
            Type::Array { ty, size } => Ty::Array {
                elem: Box::new(self.ty(scope, ty, depth)?),
                fixed: match size {
                    ArraySize::Fixed(n) => Some(*n),
                    _ => None,
                },
            },
            Type::Complex(c) => {
                let name = match c {
                    ComplexType::Absolute { package, name } => format!("{package}/{name}"),
                    ComplexType::Relative { name } if name == "Header" => "std_msgs/Header".into(),
                    ComplexType::Relative { name } => match scope.split_once('/') {
                        Some((pkg, _)) => format!("{pkg}/{name}"),
                        None => name.clone(),
                    },
                };
                let spec = self.specs.get(&normal(&name)).ok_or_else(|| {
                    format!("type '{name}' is used in '{scope}' but not defined in the schema")
                })?;
                match spec.underlying_type_if_enum_like() {
                    Ok(Some(b)) => Self::builtin(b)?,
                    _ => Ty::Struct(self.structure(spec, depth + 1)?),
                }
            }
        })
    }

    fn structure(&self, spec: &MessageSpecification, depth: usize) -> Result<Arc<Struct>, String> {
        if depth > MAX_DEPTH {
            return Err(format!(
                "message types nested deeper than {MAX_DEPTH} (a cycle?) at '{}'",
                spec.name
            ));
        }
        let fields = spec
            .fields
            .iter()
            .map(|f| Ok((f.name.clone(), self.ty(&spec.name, &f.ty, depth)?)))
            .collect::<Result<Vec<_>, String>>()?;
        Ok(Arc::new(Struct {
            name: spec.name.clone(),
            fields,
        }))
    }
}

impl Walker {
    pub fn new(schema: &SchemaDef) -> Result<Self, String> {
        let text = std::str::from_utf8(&schema.data)
            .map_err(|_| format!("ros2msg schema '{}' is not UTF-8 text", schema.name))?;
        let parsed = MessageSchema::parse(&schema.name, text)
            .map_err(|e| format!("ros2msg schema '{}' does not parse: {e:#}", schema.name))?;
        let mut specs = HashMap::new();
        for s in std::iter::once(&parsed.spec).chain(&parsed.dependencies) {
            specs.insert(normal(&s.name), s);
        }
        let root = Compiler { specs }
            .structure(&parsed.spec, 0)
            .map_err(|e| format!("ros2msg schema '{}': {e}", schema.name))?;
        Ok(Walker {
            root,
            node: Node::default(),
        })
    }

    pub fn want(&mut self, fields: &[String], slot: usize) -> Result<Leaf, String> {
        let mut st = self.root.clone();
        let mut node = &mut self.node;
        for (depth, name) in fields.iter().enumerate() {
            let Some(i) = st.fields.iter().position(|(n, _)| n == name) else {
                let names: Vec<&str> = st.fields.iter().map(|(n, _)| n.as_str()).collect();
                return Err(format!(
                    "message '{}' has no field '{name}' (fields: {})",
                    st.name,
                    names.join(", ")
                ));
            };
            if node.by_field.len() < st.fields.len() {
                node.by_field.resize(st.fields.len(), None);
            }
            let ty = st.fields[i].1.clone();
            let w = node.by_field[i].get_or_insert_with(Want::default);
            if depth + 1 == fields.len() {
                w.slot = Some(slot);
                let (repeated, elem) = match &ty {
                    Ty::Array { elem, .. } => (true, elem.as_ref()),
                    t => (false, t),
                };
                let numeric = match elem {
                    Ty::Prim(Prim::U8) if repeated => false, // uint8[]: bytes
                    Ty::Prim(_) => true,
                    Ty::Str => false,
                    _ => return Err(format!("field '{name}' is a message, not a value")),
                };
                return Ok(Leaf {
                    slot,
                    repeated,
                    numeric,
                    presence: true,
                });
            }
            let Ty::Struct(s) = ty else {
                return Err(format!(
                    "field '{name}' of '{}' is not a message, so it has no field '{}'",
                    st.name,
                    fields[depth + 1]
                ));
            };
            st = s;
            node = w.child.get_or_insert_with(Node::default);
        }
        Err("empty field path".into())
    }

    pub fn walk(&self, data: &[u8], slots: &mut [Slot]) -> Result<(), String> {
        if data.len() < 4 {
            return Err("cdr: message shorter than its 4-byte encapsulation header".into());
        }
        let body = &data[4..];
        let r = match u16::from_be_bytes([data[0], data[1]]) {
            0x0000 => walk_struct(
                &self.root,
                Some(&self.node),
                &mut CdrReader::<BigEndian>::new(body),
                slots,
            ),
            0x0001 => walk_struct(
                &self.root,
                Some(&self.node),
                &mut CdrReader::<LittleEndian>::new(body),
                slots,
            ),
            id => {
                let name = match id {
                    0x0002 | 0x0003 => "PL_CDR (parameter list)",
                    0x0006..=0x000b | 0x0010..=0x0015 => "XCDR2",
                    _ => "unknown",
                };
                return Err(format!(
                    "cdr: encapsulation 0x{id:04x} ({name}) is not supported; pinsight reads plain CDR (0x0000 big-endian, 0x0001 little-endian)"
                ));
            }
        };
        r.map_err(|e| format!("cdr: {e} (the message does not match its schema)"))
    }
}

type R<T> = Result<T, String>;

fn err(e: re_cdr::Error) -> String {
    e.to_string()
}

fn walk_struct<B: ByteOrder>(
    st: &Struct,
    node: Option<&Node>,
    r: &mut CdrReader<'_, B>,
    slots: &mut [Slot],
) -> R<()> {
    if let Some(n) = node {
        for w in n.by_field.iter().flatten() {
            if let Some(s) = w.slot {
                slots[s].parent_seen = true;
            }
        }
    }
    for (i, (_, ty)) in st.fields.iter().enumerate() {
        let want = node
            .and_then(|n| n.by_field.get(i))
            .and_then(Option::as_ref);
        match want {
            None => skip(ty, r)?,
            Some(w) => match (&w.child, ty) {
                (Some(child), Ty::Struct(s)) => walk_struct(s, Some(child), r, slots)?,
                _ => match w.slot {
                    Some(k) => read_into(ty, r, &mut slots[k])?,
                    None => skip(ty, r)?,
                },
            },
        }
    }
    Ok(())
}

fn read_prim<B: ByteOrder>(p: Prim, r: &mut CdrReader<'_, B>) -> R<Num> {
    Ok(match p {
        Prim::Bool => Num::U(r.read_u8().map_err(err)? as u64),
        Prim::U8 => Num::U(r.read_u8().map_err(err)? as u64),
        Prim::I8 => Num::I(r.read_i8().map_err(err)? as i64),
        Prim::I16 => Num::I(r.read_i16().map_err(err)? as i64),
        Prim::U16 => Num::U(r.read_u16().map_err(err)? as u64),
        Prim::I32 => Num::I(r.read_i32().map_err(err)? as i64),
        Prim::U32 => Num::U(r.read_u32().map_err(err)? as u64),
        Prim::I64 => Num::I(r.read_i64().map_err(err)?),
        Prim::U64 => Num::U(r.read_u64().map_err(err)?),
        Prim::F32 => Num::F(r.read_f32().map_err(err)? as f64),
        Prim::F64 => Num::F(r.read_f64().map_err(err)?),
    })
}

fn count<B: ByteOrder>(fixed: Option<usize>, r: &mut CdrReader<'_, B>) -> R<usize> {
    let n = match fixed {
        Some(n) => n,
        None => r.read_sequence_length().map_err(err)?,
    };
    // Every element takes at least one byte.
    if n > r.remaining() {
        return Err(format!(
            "an array of {n} elements where {} bytes remain",
            r.remaining()
        ));
    }
    Ok(n)
}

fn read_into<B: ByteOrder>(ty: &Ty, r: &mut CdrReader<'_, B>, slot: &mut Slot) -> R<()> {
    slot.seen = true;
    match ty {
        Ty::Prim(p) => slot.nums.push(read_prim(*p, r)?),
        Ty::Str => {
            let s = r.read_str().map_err(err)?;
            slot.push_bytes(s.as_bytes());
        }
        Ty::Array { elem, fixed } => {
            let n = count(*fixed, r)?;
            match elem.as_ref() {
                Ty::Prim(Prim::U8) => {
                    let b = r.read_bytes(n).map_err(err)?;
                    slot.push_bytes(b);
                }
                Ty::Prim(p) => {
                    for _ in 0..n {
                        slot.nums.push(read_prim(*p, r)?);
                    }
                }
                Ty::Str => {
                    for _ in 0..n {
                        let s = r.read_str().map_err(err)?;
                        slot.push_bytes(s.as_bytes());
                    }
                }
                _ => return Err("an array of messages cannot be a value".into()),
            }
        }
        Ty::Struct(_) => return Err("a message cannot be a value".into()),
    }
    Ok(())
}

fn skip<B: ByteOrder>(ty: &Ty, r: &mut CdrReader<'_, B>) -> R<()> {
    match ty {
        Ty::Prim(p) => {
            r.align(p.size()).map_err(err)?;
            r.read_bytes(p.size()).map_err(err)?;
        }
        Ty::Str => {
            let n = r.read_u32().map_err(err)? as usize;
            r.read_bytes(n).map_err(err)?;
        }
        Ty::Array { elem, fixed } => {
            let n = count(*fixed, r)?;
            match elem.as_ref() {
                Ty::Prim(p) if n > 0 => {
                    r.align(p.size()).map_err(err)?;
                    let bytes = n.checked_mul(p.size()).ok_or("array size overflows")?;
                    r.read_bytes(bytes).map_err(err)?;
                }
                e => {
                    for _ in 0..n {
                        skip(e, r)?;
                    }
                }
            }
        }
        Ty::Struct(s) => walk_struct(s, None, r, &mut [])?,
    }
    Ok(())
}
