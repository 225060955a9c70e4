//! A small in-memory FBX node tree and its encoding through `fbxcel`'s FBX 7.4 binary writer.
//!
//! The scene is assembled as plain [`Node`]s first (names, attribute values, children) so the
//! scene code reads like the file's structure; [`encode`] then hands every node and attribute to
//! [`fbxcel::writer::v7400::binary::Writer`], which does the byte-level work (node headers, end
//! offsets, null records, array encodings, the footer).

use fbxcel::low::FbxVersion;
use fbxcel::low::v7400::{ArrayAttributeEncoding, AttributeValue};
use fbxcel::writer::v7400::binary::{FbxFooter, Writer};
use std::io::{Cursor, Seek, Write};

/// Arrays at least this many bytes long are zlib-compressed, as the FBX SDK does for bulk data
/// (vertices, key times); shorter ones are stored directly, where compression would not pay.
const COMPRESS_MIN_BYTES: usize = 128;

/// The `FileId` / `CreationTime` / footer-id triple of the FBX SDK's files. The SDK derives the
/// footer id from the other two; a writer that cannot reproduce that derivation uses one triple
/// that belongs together. This is the one Blender's exporter (and assimp's, SmallFBX's) writes,
/// whose files the SDK and every other reader accept.
pub(super) const FILE_ID: [u8; 16] = [
    0x28, 0xb3, 0x2a, 0xeb, 0xb6, 0x24, 0xcc, 0xc2, 0xbf, 0xc8, 0xb0, 0x2a, 0xa9, 0x2b, 0xfc, 0xf1,
];
/// See [`FILE_ID`].
pub(super) const CREATION_TIME: &str = "1970-01-01 10:00:00:000";
/// See [`FILE_ID`]; written as the first 16 bytes of the footer.
const FOOTER_ID: [u8; 16] = [
    0xfa, 0xbc, 0xab, 0x09, 0xd0, 0xc8, 0xd4, 0x66, 0xb1, 0x76, 0xfb, 0x83, 0x1c, 0xf7, 0x26, 0x7e,
];

/// One FBX node: a name, its attribute values and its child nodes.
#[derive(Debug, Clone)]
pub(super) struct Node {
    pub name: &'static str,
    pub attrs: Vec<AttributeValue>,
    pub children: Vec<Node>,
}

impl Node {
    /// A node with attributes and no children (`Version: 100`).
    pub fn leaf<A: Into<AttributeValue>>(
        name: &'static str,
        attrs: impl IntoIterator<Item = A>,
    ) -> Node {
        Node {
            name,
            attrs: attrs.into_iter().map(Into::into).collect(),
            children: Vec::new(),
        }
    }

    /// A node with one attribute.
    pub fn value(name: &'static str, v: impl Into<AttributeValue>) -> Node {
        Node {
            name,
            attrs: vec![v.into()],
            children: Vec::new(),
        }
    }

    /// A node without attributes whose content is its children (`Objects: { … }`).
    pub fn group(name: &'static str, children: Vec<Node>) -> Node {
        Node {
            name,
            attrs: Vec::new(),
            children,
        }
    }

    /// A node with attributes and children (`Model: id, "name", "LimbNode" { … }`).
    pub fn with(name: &'static str, attrs: Vec<AttributeValue>, children: Vec<Node>) -> Node {
        Node {
            name,
            attrs,
            children,
        }
    }
}

/// An object's name attribute as the binary format spells it: `name \0 \x01 class` (ASCII files
/// write `class::name`; readers split on the separator).
pub(super) fn object_name(name: &str, class: &str) -> AttributeValue {
    AttributeValue::String(format!("{name}\u{0}\u{1}{class}"))
}

/// A string attribute.
pub(super) fn s(v: &str) -> AttributeValue {
    AttributeValue::String(v.to_string())
}

// ---- Properties70 entries: `P: name, type, label, flags, value…` --------------------------------

/// One `P` entry.
pub(super) fn p(
    name: &str,
    ty: &str,
    label: &str,
    flags: &str,
    values: impl IntoIterator<Item = AttributeValue>,
) -> Node {
    let mut attrs = vec![s(name), s(ty), s(label), s(flags)];
    attrs.extend(values);
    Node::with("P", attrs, Vec::new())
}

pub(super) fn p_int(name: &str, v: i32) -> Node {
    p(name, "int", "Integer", "", [v.into()])
}

pub(super) fn p_enum(name: &str, v: i32) -> Node {
    p(name, "enum", "", "", [v.into()])
}

pub(super) fn p_bool(name: &str, v: bool) -> Node {
    p(name, "bool", "", "", [i32::from(v).into()])
}

pub(super) fn p_double(name: &str, v: f64) -> Node {
    p(name, "double", "Number", "", [v.into()])
}

/// An animatable scalar (`Number`, flag `A`), e.g. a curve node's `d|X`.
pub(super) fn p_number(name: &str, v: f64) -> Node {
    p(name, "Number", "", "A", [v.into()])
}

pub(super) fn p_ktime(name: &str, v: i64) -> Node {
    p(name, "KTime", "Time", "", [v.into()])
}

pub(super) fn p_string(name: &str, v: &str) -> Node {
    p(name, "KString", "", "", [s(v)])
}

pub(super) fn p_color(name: &str, c: [f64; 3]) -> Node {
    p(name, "ColorRGB", "Color", "", c.map(AttributeValue::F64))
}

/// An animatable colour (`Color`, flag `A`), as materials carry them.
pub(super) fn p_color_a(name: &str, c: [f64; 3]) -> Node {
    p(name, "Color", "", "A", c.map(AttributeValue::F64))
}

/// A node transform channel (`Lcl Translation`, `Lcl Rotation`, `Lcl Scaling`).
pub(super) fn p_lcl(name: &str, v: [f64; 3]) -> Node {
    p(name, name, "", "A", v.map(AttributeValue::F64))
}

/// Encodes the tree (the file's top-level nodes) as FBX 7.4 binary.
pub(super) fn encode(top: &[Node]) -> Result<Vec<u8>, fbxcel::writer::v7400::binary::Error> {
    let mut writer = Writer::new(Cursor::new(Vec::new()), FbxVersion::V7_4)?;
    for node in top {
        write_node(&mut writer, node)?;
    }
    let footer = FbxFooter {
        unknown1: Some(&FOOTER_ID),
        ..FbxFooter::default()
    };
    Ok(writer.finalize_and_flush(&footer)?.into_inner())
}

fn write_node<W: Write + Seek>(
    writer: &mut Writer<W>,
    node: &Node,
) -> Result<(), fbxcel::writer::v7400::binary::Error> {
    {
        let mut a = writer.new_node(node.name)?;
        for attr in &node.attrs {
            let enc = |bytes: usize| {
                if bytes >= COMPRESS_MIN_BYTES {
                    ArrayAttributeEncoding::Zlib
                } else {
                    ArrayAttributeEncoding::Direct
                }
            };
            match attr {
                AttributeValue::Bool(v) => a.append_bool(*v)?,
                AttributeValue::I16(v) => a.append_i16(*v)?,
                AttributeValue::I32(v) => a.append_i32(*v)?,
                AttributeValue::I64(v) => a.append_i64(*v)?,
                AttributeValue::F32(v) => a.append_f32(*v)?,
                AttributeValue::F64(v) => a.append_f64(*v)?,
                AttributeValue::ArrBool(v) => {
                    a.append_arr_bool_from_iter(enc(v.len()), v.iter().copied())?
                }
                AttributeValue::ArrI32(v) => {
                    a.append_arr_i32_from_iter(enc(4 * v.len()), v.iter().copied())?
                }
                AttributeValue::ArrI64(v) => {
                    a.append_arr_i64_from_iter(enc(8 * v.len()), v.iter().copied())?
                }
                AttributeValue::ArrF32(v) => {
                    a.append_arr_f32_from_iter(enc(4 * v.len()), v.iter().copied())?
                }
                AttributeValue::ArrF64(v) => {
                    a.append_arr_f64_from_iter(enc(8 * v.len()), v.iter().copied())?
                }
                AttributeValue::Binary(v) => a.append_binary_direct(v)?,
                AttributeValue::String(v) => a.append_string_direct(v)?,
            }
        }
    }
    for child in &node.children {
        write_node(writer, child)?;
    }
    writer.close_node()
}
