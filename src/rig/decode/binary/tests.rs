//! Messages encoded by the ecosystems' own encoders (prost-reflect's
//! `DynamicMessage` for protobuf, re_cdr's `CdrWriter` for CDR), read back
//! through the selective walkers.

use super::*;
use prost_reflect::prost::Message as _;
use prost_reflect::prost_types::{
    DescriptorProto, FieldDescriptorProto, FileDescriptorProto, FileDescriptorSet,
    field_descriptor_proto::{Label, Type},
};
use prost_reflect::{DescriptorPool, DynamicMessage, Value};
use re_cdr::{BigEndian, ByteOrder, CdrWriter, LittleEndian};

fn field(
    name: &str,
    number: i32,
    ty: Type,
    label: Label,
    type_name: Option<&str>,
) -> FieldDescriptorProto {
    FieldDescriptorProto {
        name: Some(name.into()),
        number: Some(number),
        r#type: Some(ty as i32),
        label: Some(label as i32),
        type_name: type_name.map(str::to_string),
        ..Default::default()
    }
}

fn message(name: &str, fields: Vec<FieldDescriptorProto>) -> DescriptorProto {
    DescriptorProto {
        name: Some(name.into()),
        field: fields,
        ..Default::default()
    }
}

/// A proto3 file with the shapes rigs use.
fn descriptor_set() -> Vec<u8> {
    use Label::{Optional as O, Repeated as R};
    let file = FileDescriptorProto {
        name: Some("t.proto".into()),
        package: Some("t".into()),
        syntax: Some("proto3".into()),
        message_type: vec![
            message(
                "Vec3",
                vec![
                    field("x", 1, Type::Double, O, None),
                    field("z", 3, Type::Double, O, None),
                ],
            ),
            message(
                "Wrench",
                vec![field("force", 1, Type::Message, O, Some(".t.Vec3"))],
            ),
            message(
                "Joint",
                vec![
                    field("name", 1, Type::String, R, None),
                    field("position", 2, Type::Double, R, None),
                    field("count", 3, Type::Sint64, O, None),
                ],
            ),
            message(
                "Block",
                vec![
                    field("t0_ns", 1, Type::Uint64, O, None),
                    field("dt_ns", 2, Type::Uint64, O, None),
                    field("force_n", 3, Type::Float, R, None),
                ],
            ),
        ],
        ..Default::default()
    };
    FileDescriptorSet { file: vec![file] }.encode_to_vec()
}

fn pb_channel(msg: &str) -> (ChannelDef, SchemaDef) {
    (
        ChannelDef {
            id: 1,
            schema_id: 1,
            topic: "/t".into(),
            message_encoding: "protobuf".into(),
        },
        SchemaDef {
            id: 1,
            name: msg.into(),
            encoding: "protobuf".into(),
            data: descriptor_set(),
        },
    )
}

fn encode(msg: &str, set: impl FnOnce(&mut DynamicMessage)) -> Vec<u8> {
    let pool = DescriptorPool::decode(descriptor_set().as_slice()).unwrap();
    let mut m = DynamicMessage::new(pool.get_message_by_name(msg).unwrap());
    set(&mut m);
    m.encode_to_vec()
}

fn scalar(c: &BinaryCodec, data: &[u8], i: usize) -> Option<f64> {
    let mut s = Slots::default();
    c.decode(data, &mut s).unwrap();
    match c.signal(i, &s) {
        Extracted::Scalar(x) => Some(x),
        Extracted::Missing => None,
        other => panic!("{other:?}"),
    }
}

#[test]
fn protobuf_nested_fields_and_proto3_defaults() {
    let (ch, sc) = pb_channel("t.Wrench");
    let c = BinaryCodec::for_signals(&ch, Some(&sc), &["force.z", "force.x"]).unwrap();
    let pool = DescriptorPool::decode(descriptor_set().as_slice()).unwrap();
    let vec3 = pool.get_message_by_name("t.Vec3").unwrap();
    let with_force = encode("t.Wrench", |m| {
        let mut v = DynamicMessage::new(vec3.clone());
        v.set_field_by_name("z", Value::F64(-2.5));
        m.set_field_by_name("force", Value::Message(v));
    });
    assert_eq!(scalar(&c, &with_force, 0), Some(-2.5));
    // x is 0, so proto3 leaves it out: it reads as its default.
    assert_eq!(scalar(&c, &with_force, 1), Some(0.0));
    // No force message at all: the value is not there.
    let empty = encode("t.Wrench", |_| {});
    assert_eq!(scalar(&c, &empty, 0), None);
}

#[test]
fn protobuf_lookup_index_zigzag_and_blocks() {
    let (ch, sc) = pb_channel("t.Joint");
    let c = BinaryCodec::for_signals(
        &ch,
        Some(&sc),
        &[
            "position[name=crank]",
            "position[5]",
            "count",
            "position[1]",
        ],
    )
    .unwrap();
    let data = encode("t.Joint", |m| {
        m.set_field_by_name(
            "name",
            Value::List(vec![
                Value::String("rod".into()),
                Value::String("crank".into()),
            ]),
        );
        m.set_field_by_name(
            "position",
            Value::List(vec![Value::F64(0.5), Value::F64(3.25)]),
        );
        m.set_field_by_name("count", Value::I64(-7));
    });
    assert_eq!(scalar(&c, &data, 0), Some(3.25));
    assert_eq!(scalar(&c, &data, 1), None);
    assert_eq!(scalar(&c, &data, 2), Some(-7.0));
    assert_eq!(scalar(&c, &data, 3), Some(3.25));

    let (ch, sc) = pb_channel("t.Block");
    let c = BinaryCodec::for_signals(&ch, Some(&sc), &["force_n"]).unwrap();
    let t0 = 1_795_156_933_118_000_001u64; // beyond f64's exact integers
    let data = encode("t.Block", |m| {
        m.set_field_by_name("t0_ns", Value::U64(t0));
        m.set_field_by_name("dt_ns", Value::U64(100_000));
        m.set_field_by_name(
            "force_n",
            Value::List(vec![Value::F32(1.5), Value::F32(f32::NAN)]),
        );
    });
    let mut s = Slots::default();
    c.decode(&data, &mut s).unwrap();
    let Extracted::Block {
        t0_ns,
        dt_ns,
        values,
    } = c.signal(0, &s)
    else {
        panic!("a block")
    };
    assert_eq!((t0_ns, dt_ns), (Some(t0), Some(100_000)));
    assert_eq!(values[0], Num::F(1.5));
    assert!(values[1].f64().is_nan());
}

#[test]
fn protobuf_bad_schemas_paths_and_messages_are_named() {
    let (ch, mut sc) = pb_channel("t.Wrench");
    let e = BinaryCodec::for_signals(&ch, Some(&sc), &["force.y"]).unwrap_err();
    assert!(e.contains("no field 'y'") && e.contains("x, z"), "{e}");
    let e = BinaryCodec::for_signals(&ch, Some(&sc), &["force"]).unwrap_err();
    assert!(e.contains("not a number"), "{e}");
    let (_, other) = pb_channel("t.Nope");
    assert!(
        BinaryCodec::for_signals(&ch, Some(&other), &["x"])
            .unwrap_err()
            .contains("no message")
    );
    sc.data = b"not a descriptor set".to_vec();
    let e = BinaryCodec::for_signals(&ch, Some(&sc), &["force.z"]).unwrap_err();
    assert!(e.contains("FileDescriptorSet"), "{e}");
    assert!(
        BinaryCodec::for_signals(&ch, None, &["force.z"])
            .unwrap_err()
            .contains("has none")
    );

    // A message that does not match: field 1 (a message) sent as a varint,
    // and a length running past the end.
    let (ch, sc) = pb_channel("t.Wrench");
    let c = BinaryCodec::for_signals(&ch, Some(&sc), &["force.z"]).unwrap();
    let mut s = Slots::default();
    assert!(
        c.decode(&[0x08, 0x01], &mut s)
            .unwrap_err()
            .contains("does not match")
    );
    assert!(
        c.decode(&[0x0a, 0x40, 0x00], &mut s)
            .unwrap_err()
            .contains("claims 64 bytes")
    );
}

const JOINT_STATE: &str = "std_msgs/Header header\nstring[] name\nfloat64[] position\nfloat64[] velocity\nfloat64[] effort\n\
================================================================================\nMSG: std_msgs/Header\nbuiltin_interfaces/Time stamp\nstring frame_id\n\
================================================================================\nMSG: builtin_interfaces/Time\nint32 sec\nuint32 nanosec\n";

fn ros_channel(name: &str, text: &str) -> (ChannelDef, SchemaDef) {
    (
        ChannelDef {
            id: 2,
            schema_id: 2,
            topic: "/joint_states".into(),
            message_encoding: "cdr".into(),
        },
        SchemaDef {
            id: 2,
            name: name.into(),
            encoding: "ros2msg".into(),
            data: text.as_bytes().to_vec(),
        },
    )
}

/// A JointState in CDR with the given encapsulation header.
fn joint_state<B: ByteOrder>(header: [u8; 4]) -> Vec<u8> {
    let mut body = Vec::new();
    let mut w = CdrWriter::<B>::new(&mut body);
    w.write_i32(1);
    w.write_u32(2);
    w.write_string("crank_frame");
    w.write_sequence_length(2);
    w.write_string("rod");
    w.write_string("crank");
    for seq in [&[0.25, 3.5][..], &[1.0, 125.6], &[]] {
        w.write_sequence_length(seq.len());
        for x in seq {
            w.write_f64(*x);
        }
    }
    let mut out = header.to_vec();
    out.extend(body);
    out
}

#[test]
fn ros2_joint_state_both_byte_orders() {
    let (ch, sc) = ros_channel("sensor_msgs/msg/JointState", JOINT_STATE);
    let c = BinaryCodec::for_signals(
        &ch,
        Some(&sc),
        &[
            "position[name=crank]",
            "velocity[name=crank]",
            "header.stamp.nanosec",
            "effort[0]",
        ],
    )
    .unwrap();
    for data in [
        joint_state::<LittleEndian>([0, 1, 0, 0]),
        joint_state::<BigEndian>([0, 0, 0, 0]),
    ] {
        assert_eq!(scalar(&c, &data, 0), Some(3.5));
        assert_eq!(scalar(&c, &data, 1), Some(125.6));
        assert_eq!(scalar(&c, &data, 2), Some(2.0));
        assert_eq!(scalar(&c, &data, 3), None);
    }
}

#[test]
fn ros2_refusals_name_the_problem() {
    let (ch, sc) = ros_channel("sensor_msgs/msg/JointState", JOINT_STATE);
    let c = BinaryCodec::for_signals(&ch, Some(&sc), &["position[name=crank]"]).unwrap();
    let mut s = Slots::default();
    let mut xcdr2 = joint_state::<LittleEndian>([0, 1, 0, 0]);
    xcdr2[1] = 0x07;
    assert!(c.decode(&xcdr2, &mut s).unwrap_err().contains("XCDR2"));
    let ok = joint_state::<LittleEndian>([0, 1, 0, 0]);
    let e = c.decode(&ok[..ok.len() - 20], &mut s).unwrap_err();
    assert!(e.contains("does not match its schema"), "{e}");
    // A hostile sequence length is refused before anything is allocated.
    let mut huge = ok.clone();
    huge[4 + 4 + 4 + 4 + 12..4 + 4 + 4 + 4 + 16].copy_from_slice(&90_000_000u32.to_le_bytes());
    assert!(
        c.decode(&huge, &mut s)
            .unwrap_err()
            .contains("elements where")
    );

    let e = BinaryCodec::for_signals(&ch, Some(&sc), &["header.stamp.year"]).unwrap_err();
    assert!(
        e.contains("no field 'year'") && e.contains("sec, nanosec"),
        "{e}"
    );
    let (ch2, sc2) = ros_channel("pkg/msg/Broken", "float64 x\nnot_a_type[ y\n");
    assert!(
        BinaryCodec::for_signals(&ch2, Some(&sc2), &["x"])
            .unwrap_err()
            .contains("does not parse")
    );
    let (ch3, sc3) = ros_channel("pkg/msg/Dangling", "other_pkg/Missing m\n");
    assert!(
        BinaryCodec::for_signals(&ch3, Some(&sc3), &["m"])
            .unwrap_err()
            .contains("not defined")
    );
    let mut idl = sc.clone();
    idl.encoding = "ros2idl".into();
    assert!(
        BinaryCodec::for_signals(&ch, Some(&idl), &["x"])
            .unwrap_err()
            .contains("ros2idl")
    );
}
