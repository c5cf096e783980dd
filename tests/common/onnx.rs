//! Tiny ONNX models built by the tests: a minimal protobuf writer for ModelProto (onnx.proto3 field
//! numbers), enough for float graphs of elementwise and reduce operators. Models are written to a
//! temporary folder and run by onnxruntime like any user model.
#![allow(dead_code)]

use std::path::{Path, PathBuf};

fn varint(out: &mut Vec<u8>, mut v: u64) {
    loop {
        let b = (v & 0x7f) as u8;
        v >>= 7;
        if v == 0 {
            out.push(b);
            return;
        }
        out.push(b | 0x80);
    }
}

fn key(out: &mut Vec<u8>, field: u32, wire: u32) {
    varint(out, ((field << 3) | wire) as u64);
}

fn int_field(out: &mut Vec<u8>, field: u32, v: i64) {
    key(out, field, 0);
    varint(out, v as u64);
}

fn bytes_field(out: &mut Vec<u8>, field: u32, data: &[u8]) {
    key(out, field, 2);
    varint(out, data.len() as u64);
    out.extend_from_slice(data);
}

fn str_field(out: &mut Vec<u8>, field: u32, s: &str) {
    bytes_field(out, field, s.as_bytes());
}

/// A graph node: op type, inputs, outputs, integer-list attributes.
pub struct Node<'a> {
    pub op: &'a str,
    pub inputs: &'a [&'a str],
    pub outputs: &'a [&'a str],
    pub ints: &'a [(&'a str, &'a [i64])],
    pub int: &'a [(&'a str, i64)],
}

pub fn node<'a>(op: &'a str, inputs: &'a [&'a str], outputs: &'a [&'a str]) -> Node<'a> {
    Node { op, inputs, outputs, ints: &[], int: &[] }
}

/// A float tensor input/output: name and dims (None = symbolic).
pub struct Io<'a> {
    pub name: &'a str,
    pub dims: &'a [Option<i64>],
}

fn value_info(io: &Io) -> Vec<u8> {
    let mut shape = Vec::new();
    for (i, d) in io.dims.iter().enumerate() {
        let mut dim = Vec::new();
        match d {
            Some(v) => int_field(&mut dim, 1, *v),
            None => str_field(&mut dim, 2, &format!("{}_{i}", io.name)),
        }
        bytes_field(&mut shape, 1, &dim);
    }
    let mut tensor_type = Vec::new();
    int_field(&mut tensor_type, 1, 1); // FLOAT
    bytes_field(&mut tensor_type, 2, &shape);
    let mut type_proto = Vec::new();
    bytes_field(&mut type_proto, 1, &tensor_type);
    let mut vi = Vec::new();
    str_field(&mut vi, 1, io.name);
    bytes_field(&mut vi, 2, &type_proto);
    vi
}

/// Encodes a model (opset 13) with float initializers (name, dims, values).
pub fn model(nodes: &[Node], inputs: &[Io], outputs: &[Io], initializers: &[(&str, &[i64], &[f32])]) -> Vec<u8> {
    let mut graph = Vec::new();
    for (i, n) in nodes.iter().enumerate() {
        let mut nb = Vec::new();
        for s in n.inputs {
            str_field(&mut nb, 1, s);
        }
        for s in n.outputs {
            str_field(&mut nb, 2, s);
        }
        str_field(&mut nb, 3, &format!("n{i}"));
        str_field(&mut nb, 4, n.op);
        for (name, values) in n.ints {
            let mut a = Vec::new();
            str_field(&mut a, 1, name);
            for v in *values {
                int_field(&mut a, 8, *v);
            }
            int_field(&mut a, 20, 7); // INTS
            bytes_field(&mut nb, 5, &a);
        }
        for (name, v) in n.int {
            let mut a = Vec::new();
            str_field(&mut a, 1, name);
            int_field(&mut a, 3, *v);
            int_field(&mut a, 20, 2); // INT
            bytes_field(&mut nb, 5, &a);
        }
        bytes_field(&mut graph, 1, &nb);
    }
    str_field(&mut graph, 2, "tiny");
    for (name, dims, values) in initializers {
        let mut t = Vec::new();
        for d in *dims {
            int_field(&mut t, 1, *d);
        }
        int_field(&mut t, 2, 1); // FLOAT
        str_field(&mut t, 8, name);
        let raw: Vec<u8> = values.iter().flat_map(|v| v.to_le_bytes()).collect();
        bytes_field(&mut t, 9, &raw);
        bytes_field(&mut graph, 5, &t);
    }
    for io in inputs {
        bytes_field(&mut graph, 11, &value_info(io));
    }
    for io in outputs {
        bytes_field(&mut graph, 12, &value_info(io));
    }
    let mut m = Vec::new();
    int_field(&mut m, 1, 8); // ir_version
    str_field(&mut m, 2, "cogeo-tests");
    bytes_field(&mut m, 7, &graph);
    let mut opset = Vec::new();
    str_field(&mut opset, 1, "");
    int_field(&mut opset, 2, 13);
    bytes_field(&mut m, 8, &opset);
    m
}

pub fn write(dir: &Path, name: &str, bytes: &[u8]) -> PathBuf {
    std::fs::create_dir_all(dir).unwrap();
    let p = dir.join(name);
    std::fs::write(&p, bytes).unwrap();
    p
}

const N: Option<i64> = None;

/// LaMa contract: output = image (1 - mask) + 0.25 mask.
pub fn tiny_lama() -> Vec<u8> {
    model(
        &[
            node("Sub", &["one", "mask"], &["keep"]),
            node("Mul", &["image", "keep"], &["kept"]),
            node("Mul", &["mask", "fill"], &["filled"]),
            node("Add", &["kept", "filled"], &["output"]),
        ],
        &[
            Io { name: "image", dims: &[Some(1), Some(3), Some(512), Some(512)] },
            Io { name: "mask", dims: &[Some(1), Some(1), Some(512), Some(512)] },
        ],
        &[Io { name: "output", dims: &[Some(1), Some(3), Some(512), Some(512)] }],
        &[("one", &[], &[1.0]), ("fill", &[], &[0.25])],
    )
}

/// A depth model (either contract): the channel mean of its normalized input, [1, H, W].
pub fn tiny_depth() -> Vec<u8> {
    model(
        &[Node {
            op: "ReduceMean",
            inputs: &["pixel_values"],
            outputs: &["predicted_depth"],
            ints: &[("axes", &[1])],
            int: &[("keepdims", 0)],
        }],
        &[Io { name: "pixel_values", dims: &[Some(1), Some(3), N, N] }],
        &[Io { name: "predicted_depth", dims: &[Some(1), N, N] }],
        &[],
    )
}

/// Denoiser contract: predicts the noise of a clean signal 0, eps = sample / sqrt(1 - alpha_bar).
pub fn tiny_denoiser() -> Vec<u8> {
    model(
        &[
            node("Sub", &["one", "alpha_bar"], &["var"]),
            node("Sqrt", &["var"], &["sd"]),
            node("Div", &["sample", "sd"], &["noise"]),
        ],
        &[
            Io { name: "sample", dims: &[Some(1), Some(1), N, N] },
            Io { name: "timestep", dims: &[Some(1)] },
            Io { name: "alpha_bar", dims: &[Some(1)] },
            Io { name: "image", dims: &[Some(1), Some(3), N, N] },
            Io { name: "mask", dims: &[Some(1), Some(1), N, N] },
        ],
        &[Io { name: "noise", dims: &[Some(1), Some(1), N, N] }],
        &[("one", &[], &[1.0])],
    )
}
