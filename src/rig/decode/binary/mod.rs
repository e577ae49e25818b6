//! Binary message encodings: protobuf (`protobuf` schemas, a serialized
//! FileDescriptorSet) and ROS 2 (`ros2msg` schemas, `cdr` messages).
//!
//! A channel's schema and the field paths the channel map asks of it are
//! compiled once into a [`BinaryCodec`]: a tree of the wanted fields, each
//! ending in a numbered *slot*. Per message the codec walks the bytes,
//! skipping every field nobody asked for and copying the wanted ones into
//! the slots (reused scratch: no allocation per message once warm); then each
//! signal reads its value from its slot ([`BinaryCodec::signal`]). The
//! schemas are parsed by `prost-reflect` and `re_ros_msg`, the CDR
//! primitives read by `re_cdr`; what is written here is only the selective
//! walk, which no crate offers (theirs build a whole dynamic message per
//! message, several times slower and unbounded on hostile lengths).
//!
//! What counts as what, the same as for JSON: a path to a single number is
//! one sample per message; a path to a repeated number field without an
//! element is a block of samples when its message also has `t0_ns` and
//! `dt_ns` (sample i at t0_ns + i·dt_ns); an element (`data[3]`,
//! `position[name=crank]`) missing from a message is a missing field. A
//! proto3 number field without presence that is absent reads as its
//! default, 0, as protobuf defines it.

pub mod path;
mod protobuf;
mod ros2;

use crate::rig::mcap_read::{ChannelDef, SchemaDef};
use path::{FieldPath, Select};
use std::collections::HashMap;

/// A number as found on the wire (integers kept exact: times are ns since
/// the epoch, beyond f64's 2^53).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Num {
    F(f64),
    U(u64),
    I(i64),
}

impl Num {
    pub fn f64(self) -> f64 {
        match self {
            Num::F(x) => x,
            Num::U(u) => u as f64,
            Num::I(i) => i as f64,
        }
    }

    pub fn u64(self) -> Option<u64> {
        match self {
            Num::U(u) => Some(u),
            Num::I(i) => u64::try_from(i).ok(),
            Num::F(_) => None,
        }
    }
}

/// What one wanted field held in the current message.
#[derive(Debug, Default, Clone)]
pub struct Slot {
    pub nums: Vec<Num>,
    strs: Vec<Vec<u8>>,
    n_strs: usize,
    /// The field occurred in the message.
    pub seen: bool,
    /// The message holding the field occurred (protobuf may omit a
    /// sub-message; a scalar of a present message without presence is 0).
    pub parent_seen: bool,
}

impl Slot {
    fn clear(&mut self) {
        self.nums.clear();
        self.n_strs = 0;
        self.seen = false;
        self.parent_seen = false;
    }

    /// Keeps a string or bytes value (buffers reused between messages).
    pub fn push_bytes(&mut self, b: &[u8]) {
        if self.strs.len() == self.n_strs {
            self.strs.push(Vec::new());
        }
        let s = &mut self.strs[self.n_strs];
        s.clear();
        s.extend_from_slice(b);
        self.n_strs += 1;
    }

    pub fn strs(&self) -> &[Vec<u8>] {
        &self.strs[..self.n_strs]
    }
}

/// Per-decoder scratch: the slots of the message being decoded.
#[derive(Debug, Default)]
pub struct Slots(pub Vec<Slot>);

impl Slots {
    fn reset(&mut self, n: usize) {
        if self.0.len() < n {
            self.0.resize(n, Slot::default());
        }
        for s in &mut self.0[..n] {
            s.clear();
        }
    }
}

/// Facts about a wanted field, from the schema.
#[derive(Debug, Clone, Copy)]
pub struct Leaf {
    pub slot: usize,
    pub repeated: bool,
    pub numeric: bool,
    /// Absent means "not there" (else absent = the default 0).
    pub presence: bool,
}

/// The selective walk of one encoding.
#[derive(Debug)]
enum Walker {
    Protobuf(protobuf::Walker),
    Ros2(ros2::Walker),
}

impl Walker {
    fn want(&mut self, fields: &[String], slot: usize) -> Result<Leaf, String> {
        match self {
            Walker::Protobuf(w) => w.want(fields, slot),
            Walker::Ros2(w) => w.want(fields, slot),
        }
    }

    fn walk(&self, data: &[u8], slots: &mut [Slot]) -> Result<(), String> {
        match self {
            Walker::Protobuf(w) => w.walk(data, slots),
            Walker::Ros2(w) => w.walk(data, slots),
        }
    }
}

/// How a signal finds its value among the slots.
#[derive(Debug, Clone)]
enum Route {
    Scalar(Leaf),
    Element(Leaf, usize),
    Lookup {
        values: Leaf,
        keys: usize,
        key: Vec<u8>,
    },
    Block {
        values: Leaf,
        t0: usize,
        dt: usize,
    },
    /// A repeated field with no t0_ns/dt_ns beside it: no sample times.
    Untimed,
}

/// One signal's value in the current message.
#[derive(Debug)]
pub enum Extracted<'a> {
    Scalar(f64),
    Block {
        t0_ns: Option<u64>,
        dt_ns: Option<u64>,
        values: &'a [Num],
    },
    Missing,
    WrongShape(&'static str),
}

/// Image fields (foxglove.CompressedImage in protobuf, sensor_msgs/CompressedImage in ROS 2).
#[derive(Debug)]
struct ImageRoutes {
    sec: usize,
    nsec: usize,
    frame_id: usize,
    format: usize,
    data: usize,
}

/// An image message's fields.
#[derive(Debug, Default)]
pub struct ImageFields<'a> {
    pub stamp_ns: Option<u64>,
    pub frame_id: String,
    pub format: String,
    pub data: Option<&'a [u8]>,
}

/// A channel's compiled schema and wanted fields.
#[derive(Debug)]
pub struct BinaryCodec {
    walker: Walker,
    routes: Vec<Route>,
    image: Option<ImageRoutes>,
    n_slots: usize,
    slot_of: HashMap<Vec<String>, Leaf>,
}

/// The encodings this module reads: (message encoding, schema encoding).
pub const SUPPORTED: [(&str, &str); 2] = [("protobuf", "protobuf"), ("cdr", "ros2msg")];

impl BinaryCodec {
    /// True when the channel is in an encoding this module reads.
    pub fn handles(ch: &ChannelDef) -> bool {
        SUPPORTED.iter().any(|(m, _)| *m == ch.message_encoding)
    }

    fn new(ch: &ChannelDef, schema: Option<&SchemaDef>) -> Result<Self, String> {
        let schema = schema.ok_or_else(|| {
            format!(
                "message encoding '{}' needs a schema, and the channel has none",
                ch.message_encoding
            )
        })?;
        let walker = match (ch.message_encoding.as_str(), schema.encoding.as_str()) {
            ("protobuf", "protobuf") => Walker::Protobuf(protobuf::Walker::new(schema)?),
            ("cdr", "ros2msg") => Walker::Ros2(ros2::Walker::new(schema)?),
            ("cdr", other) => {
                return Err(format!(
                    "schema encoding '{other}' with cdr messages is not supported (pinsight reads ros2msg schemas; ros2idl is not)"
                ));
            }
            (m, s) => {
                return Err(format!(
                    "message encoding '{m}' with schema encoding '{s}' is not supported"
                ));
            }
        };
        Ok(BinaryCodec {
            walker,
            routes: Vec::new(),
            image: None,
            n_slots: 0,
            slot_of: HashMap::new(),
        })
    }

    fn leaf(&mut self, fields: &[String]) -> Result<Leaf, String> {
        if let Some(l) = self.slot_of.get(fields) {
            return Ok(*l);
        }
        let l = self.walker.want(fields, self.n_slots)?;
        self.n_slots += 1;
        self.slot_of.insert(fields.to_vec(), l);
        Ok(l)
    }

    /// Compiles a channel carrying signals at the given field paths.
    pub fn for_signals(
        ch: &ChannelDef,
        schema: Option<&SchemaDef>,
        paths: &[&str],
    ) -> Result<Self, String> {
        let mut c = Self::new(ch, schema)?;
        for p in paths {
            let path = FieldPath::parse(p)?;
            let values = c
                .leaf(&path.fields)
                .map_err(|e| format!("field '{p}': {e}"))?;
            if !values.numeric {
                return Err(format!("field '{p}' is not a number field"));
            }
            let route = match path.select {
                Select::Whole if !values.repeated => Route::Scalar(values),
                Select::Whole => {
                    let parent = &path.fields[..path.fields.len() - 1];
                    let sibling = |c: &mut Self, name: &str| {
                        let mut f = parent.to_vec();
                        f.push(name.to_string());
                        c.leaf(&f).ok().filter(|l| l.numeric && !l.repeated)
                    };
                    match (sibling(&mut c, "t0_ns"), sibling(&mut c, "dt_ns")) {
                        (Some(t0), Some(dt)) => Route::Block {
                            values,
                            t0: t0.slot,
                            dt: dt.slot,
                        },
                        _ => Route::Untimed,
                    }
                }
                Select::Index(i) if values.repeated => Route::Element(values, i),
                Select::Lookup { keys, key } if values.repeated => {
                    let mut f = path.fields[..path.fields.len() - 1].to_vec();
                    f.push(keys.clone());
                    let k = c.leaf(&f).map_err(|e| format!("field '{p}': {e}"))?;
                    if k.numeric || !k.repeated {
                        return Err(format!(
                            "field '{p}': '{keys}' is not a repeated string field"
                        ));
                    }
                    Route::Lookup {
                        values,
                        keys: k.slot,
                        key: key.into_bytes(),
                    }
                }
                _ => {
                    return Err(format!(
                        "field '{p}': an element `[...]` of a field that is not repeated"
                    ));
                }
            };
            c.routes.push(route);
        }
        Ok(c)
    }

    /// Compiles an image channel (foxglove.CompressedImage or sensor_msgs/CompressedImage).
    pub fn for_images(ch: &ChannelDef, schema: Option<&SchemaDef>) -> Result<Self, String> {
        let mut c = Self::new(ch, schema)?;
        let ros = matches!(c.walker, Walker::Ros2(_));
        let path = |s: &str| s.split('.').map(str::to_string).collect::<Vec<_>>();
        let (sec, nsec, frame) = if ros {
            (
                "header.stamp.sec",
                "header.stamp.nanosec",
                "header.frame_id",
            )
        } else {
            ("timestamp.seconds", "timestamp.nanos", "frame_id")
        };
        let mut get = |s: &str| c.leaf(&path(s)).map(|l| l.slot);
        let image = ImageRoutes {
            sec: get(sec)?,
            nsec: get(nsec)?,
            frame_id: get(frame)?,
            format: get("format")?,
            data: get("data")?,
        };
        c.image = Some(image);
        Ok(c)
    }

    /// Walks one message into the slots.
    pub fn decode(&self, data: &[u8], slots: &mut Slots) -> Result<(), String> {
        slots.reset(self.n_slots);
        self.walker.walk(data, &mut slots.0[..self.n_slots])
    }

    /// Signal `i`'s value in the message last decoded.
    pub fn signal<'a>(&self, i: usize, slots: &'a Slots) -> Extracted<'a> {
        let s = &slots.0;
        let Some(route) = self.routes.get(i) else {
            return Extracted::Missing;
        };
        match route {
            Route::Scalar(l) => {
                let slot = &s[l.slot];
                match slot.nums.last() {
                    Some(n) => Extracted::Scalar(n.f64()),
                    None if !l.presence && slot.parent_seen => Extracted::Scalar(0.0),
                    None => Extracted::Missing,
                }
            }
            Route::Element(l, i) => s[l.slot]
                .nums
                .get(*i)
                .map_or(Extracted::Missing, |n| Extracted::Scalar(n.f64())),
            Route::Lookup { values, keys, key } => s[*keys]
                .strs()
                .iter()
                .position(|k| k == key)
                .and_then(|i| s[values.slot].nums.get(i))
                .map_or(Extracted::Missing, |n| Extracted::Scalar(n.f64())),
            Route::Block { values, t0, dt } => {
                let time = |k: usize| {
                    s[k].nums
                        .last()
                        .and_then(|n| n.u64())
                        .or((s[k].parent_seen && s[k].nums.is_empty()).then_some(0))
                };
                Extracted::Block {
                    t0_ns: time(*t0),
                    dt_ns: time(*dt),
                    values: &s[values.slot].nums,
                }
            }
            Route::Untimed => Extracted::WrongShape(
                "a repeated field without t0_ns and dt_ns beside it has no sample times; name one element (`data[3]`)",
            ),
        }
    }

    /// The image fields of the message last decoded.
    pub fn image<'a>(&self, slots: &'a Slots) -> ImageFields<'a> {
        let Some(r) = &self.image else {
            return ImageFields::default();
        };
        let s = &slots.0;
        let text = |k: usize| {
            s[k].strs()
                .last()
                .map(|b| String::from_utf8_lossy(b).into_owned())
                .unwrap_or_default()
        };
        let int = |k: usize| s[k].nums.last().map_or(Some(0), |n| n.u64());
        let data = if s[r.data].seen {
            Some(s[r.data].strs().last().map_or(&[][..], |v| v.as_slice()))
        } else {
            None
        };
        ImageFields {
            stamp_ns: int(r.sec)
                .zip(int(r.nsec))
                .and_then(|(a, b)| a.checked_mul(1_000_000_000)?.checked_add(b)),
            frame_id: text(r.frame_id),
            format: text(r.format),
            data,
        }
    }
}

#[cfg(test)]
mod tests;
