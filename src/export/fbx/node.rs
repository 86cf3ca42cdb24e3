//! The FBX binary container, version 7.4 (32-bit offsets): a 27-byte header, a tree of node
//! records (end offset, property count, property bytes, name, typed properties, nested nodes
//! closed by a 13-byte null record) and the footer, as the Blender Foundation's public FBX
//! binary notes describe it. Arrays are written uncompressed (encoding 0).
use crate::error::{Error, Result};

/// The FBX version written: 7.4.
pub const VERSION: u32 = 7400;

/// One typed property of a node record.
#[derive(Clone, Debug, PartialEq)]
pub enum Prop {
    /// `C`: a boolean byte.
    Bool(bool),
    /// `I`: a 32-bit integer.
    I32(i32),
    /// `L`: a 64-bit integer (object ids, times).
    I64(i64),
    /// `D`: a double.
    F64(f64),
    /// `S`: a byte string (names use `name\0\x01Class`).
    Str(Vec<u8>),
    /// `R`: raw bytes (embedded files).
    Raw(Vec<u8>),
    /// `i`: an array of 32-bit integers.
    I32s(Vec<i32>),
    /// `l`: an array of 64-bit integers (key times).
    I64s(Vec<i64>),
    /// `f`: an array of floats (key values).
    F32s(Vec<f32>),
    /// `d`: an array of doubles.
    F64s(Vec<f64>),
}

/// A string property.
pub fn s(text: &str) -> Prop {
    Prop::Str(text.as_bytes().to_vec())
}

/// An object's name property: `name`, then `\0\x01`, then its class (`Model`, `Geometry`, …).
pub fn object_name(name: &str, class: &str) -> Prop {
    Prop::Str([name.as_bytes(), b"\x00\x01", class.as_bytes()].concat())
}

/// A node record: its name, properties and nested nodes.
#[derive(Clone, Debug, PartialEq)]
pub struct Node {
    /// The record's name (at most 255 bytes).
    pub name: &'static str,
    /// Its properties, in order.
    pub props: Vec<Prop>,
    /// Its nested records.
    pub children: Vec<Node>,
}

impl Node {
    /// A record named `name` with `props` and no nested records.
    pub fn new(name: &'static str, props: Vec<Prop>) -> Node {
        Node { name, props, children: Vec::new() }
    }

    /// This record with `children` nested.
    pub fn with(mut self, children: Vec<Node>) -> Node {
        self.children = children;
        self
    }
}

/// A `Properties70` entry `P`: name, type, label, flags, then the values.
pub fn p(name: &str, kind: &str, label: &str, flags: &str, values: Vec<Prop>) -> Node {
    let mut props = vec![s(name), s(kind), s(label), s(flags)];
    props.extend(values);
    Node::new("P", props)
}

/// The bytes of a whole file holding `nodes` at the top level.
pub fn file_bytes(nodes: &[Node]) -> Result<Vec<u8>> {
    let mut out = Vec::new();
    out.extend_from_slice(b"Kaydara FBX Binary  \x00\x1a\x00");
    out.extend_from_slice(&VERSION.to_le_bytes());
    for n in nodes {
        write_node(&mut out, n)?;
    }
    out.extend_from_slice(&[0u8; 13]);
    footer(&mut out);
    Ok(out)
}

/// The footer: a 16-byte footer id, zeros to the next multiple of 16, 4 zero bytes, the
/// version, 120 zero bytes and the 16-byte closing magic.
fn footer(out: &mut Vec<u8>) {
    out.extend_from_slice(&[
        0xfa, 0xbc, 0xab, 0x09, 0xd0, 0xc8, 0xd4, 0x66, 0xb1, 0x76, 0xfb, 0x83, 0x1c, 0xf7, 0x26, 0x7e,
    ]);
    let pad = (16 - out.len() % 16) % 16;
    out.resize(out.len() + pad, 0);
    out.extend_from_slice(&[0u8; 4]);
    out.extend_from_slice(&VERSION.to_le_bytes());
    out.extend_from_slice(&[0u8; 120]);
    out.extend_from_slice(&[
        0xf8, 0x5a, 0x8c, 0x6a, 0xde, 0xf5, 0xd9, 0x7e, 0xec, 0xe9, 0x0c, 0xe3, 0x75, 0x8f, 0x29, 0x0b,
    ]);
}

fn too_big(what: &str, n: usize) -> Error {
    Error::OutOfRange { name: "fbx size", detail: format!("{what} of {n} exceeds FBX 7.4's 32-bit limit") }
}

fn u32_of(n: usize, what: &str) -> Result<u32> {
    u32::try_from(n).map_err(|_| too_big(what, n))
}

fn patch(out: &mut [u8], at: usize, value: u32) {
    out[at..at + 4].copy_from_slice(&value.to_le_bytes());
}

/// Appends one node record (and its nested records) at the end of `out`, whose length is the
/// file offset.
fn write_node(out: &mut Vec<u8>, node: &Node) -> Result<()> {
    let name_len = u8::try_from(node.name.len()).map_err(|_| too_big("node name", node.name.len()))?;
    let start = out.len();
    out.extend_from_slice(&[0u8; 4]);
    out.extend_from_slice(&u32_of(node.props.len(), "property count")?.to_le_bytes());
    out.extend_from_slice(&[0u8; 4]);
    out.push(name_len);
    out.extend_from_slice(node.name.as_bytes());
    let props_start = out.len();
    for prop in &node.props {
        write_prop(out, prop)?;
    }
    let props_len = u32_of(out.len() - props_start, "property list")?;
    patch(out, start + 8, props_len);
    for child in &node.children {
        write_node(out, child)?;
    }
    if !node.children.is_empty() || node.props.is_empty() {
        out.extend_from_slice(&[0u8; 13]);
    }
    let end = u32_of(out.len(), "file offset")?;
    patch(out, start, end);
    Ok(())
}

fn write_array(out: &mut Vec<u8>, code: u8, count: usize, bytes: impl Iterator<Item = u8>) -> Result<()> {
    out.push(code);
    out.extend_from_slice(&u32_of(count, "array length")?.to_le_bytes());
    out.extend_from_slice(&0u32.to_le_bytes());
    let len_at = out.len();
    out.extend_from_slice(&[0u8; 4]);
    let data_start = out.len();
    out.extend(bytes);
    let len = u32_of(out.len() - data_start, "array bytes")?;
    patch(out, len_at, len);
    Ok(())
}

fn write_prop(out: &mut Vec<u8>, prop: &Prop) -> Result<()> {
    match prop {
        Prop::Bool(v) => out.extend_from_slice(&[b'C', u8::from(*v)]),
        Prop::I32(v) => {
            out.push(b'I');
            out.extend_from_slice(&v.to_le_bytes());
        }
        Prop::I64(v) => {
            out.push(b'L');
            out.extend_from_slice(&v.to_le_bytes());
        }
        Prop::F64(v) => {
            out.push(b'D');
            out.extend_from_slice(&v.to_le_bytes());
        }
        Prop::Str(b) | Prop::Raw(b) => {
            out.push(if matches!(prop, Prop::Str(_)) { b'S' } else { b'R' });
            out.extend_from_slice(&u32_of(b.len(), "string")?.to_le_bytes());
            out.extend_from_slice(b);
        }
        Prop::I32s(v) => write_array(out, b'i', v.len(), v.iter().flat_map(|x| x.to_le_bytes()))?,
        Prop::I64s(v) => write_array(out, b'l', v.len(), v.iter().flat_map(|x| x.to_le_bytes()))?,
        Prop::F32s(v) => write_array(out, b'f', v.len(), v.iter().flat_map(|x| x.to_le_bytes()))?,
        Prop::F64s(v) => write_array(out, b'd', v.len(), v.iter().flat_map(|x| x.to_le_bytes()))?,
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use std::collections::HashSet;

    use super::*;

    /// Whatever the records' length, the file is padded to a multiple of 16 bytes after the
    /// footer id and ends with 4 zero bytes, the version, 120 zero bytes and the closing magic.
    #[test]
    fn the_footer_pads_to_16_bytes_and_closes_the_file() {
        let mut lengths = HashSet::new();
        for n in 0..16 {
            let file = file_bytes(&[Node::new("Name", vec![s(&"x".repeat(n))])]).unwrap();
            assert_eq!(file.len() % 16, 0, "name of {n} bytes: {} bytes", file.len());
            let end = file.len() - 16;
            assert_eq!(file[end], 0xf8);
            assert!(file[end - 120..end].iter().all(|&b| b == 0));
            assert_eq!(file[end - 124..end - 120], VERSION.to_le_bytes());
            assert_eq!(file[end - 128..end - 124], [0; 4]);
            // The footer id follows the 13-byte null record closing the top level; then the zeros.
            let id = file.windows(4).position(|w| w == [0xfa, 0xbc, 0xab, 0x09]).unwrap();
            assert!(file[id + 16..end - 128].iter().all(|&b| b == 0) && end - 128 - (id + 16) < 16);
            lengths.insert(id % 16);
        }
        assert_eq!(lengths.len(), 16, "every padding length was tried");
    }
}
