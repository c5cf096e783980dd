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
    model_with_ints(nodes, inputs, outputs, initializers, &[])
}

/// As `model`, plus int64 initializers (shapes for Reshape, axes).
pub fn model_with_ints(
    nodes: &[Node],
    inputs: &[Io],
    outputs: &[Io],
    initializers: &[(&str, &[i64], &[f32])],
    int_initializers: &[(&str, &[i64], &[i64])],
) -> Vec<u8> {
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
    for (name, dims, values) in int_initializers {
        let mut t = Vec::new();
        for d in *dims {
            int_field(&mut t, 1, *d);
        }
        int_field(&mut t, 2, 7); // INT64
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

/// A depth model that sees nothing: 0 times the channel mean of its input, [1, H, W].
pub fn flat_depth() -> Vec<u8> {
    model(
        &[
            Node {
                op: "ReduceMean",
                inputs: &["pixel_values"],
                outputs: &["mean"],
                ints: &[("axes", &[1])],
                int: &[("keepdims", 0)],
            },
            node("Mul", &["mean", "zero"], &["predicted_depth"]),
        ],
        &[Io { name: "pixel_values", dims: &[Some(1), Some(3), N, N] }],
        &[Io { name: "predicted_depth", dims: &[Some(1), N, N] }],
        &[("zero", &[], &[0.0])],
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

/// Size of the images the tiny prompt models take.
pub const PROMPT_W: usize = 32;
pub const PROMPT_H: usize = 24;

/// Detector contract on 32x24 images: a prompt's embedding is an RGB weight vector; the pixels where
/// weights . rgb > 0.5 are the object, its box is their bounding box (one box per prompt) and the
/// score is 1 if any pixel matched, else 0.
pub fn tiny_detector() -> Vec<u8> {
    let n = PROMPT_W * PROMPT_H;
    let xs: Vec<f32> = (0..n).map(|i| (i % PROMPT_W) as f32).collect();
    let ys: Vec<f32> = (0..n).map(|i| (i / PROMPT_W) as f32).collect();
    let xs1: Vec<f32> = xs.iter().map(|v| v + 1.0).collect();
    let ys1: Vec<f32> = ys.iter().map(|v| v + 1.0).collect();
    let reduce = |op: &'static str, input: &'static str, output: &'static str| Node {
        op,
        inputs: Box::leak(Box::new([input])),
        outputs: Box::leak(Box::new([output])),
        ints: &[("axes", &[1])],
        int: &[("keepdims", 1)],
    };
    let n64 = n as i64;
    model_with_ints(
        &[
            node("Reshape", &["image", "shape_flat"], &["flat"]),
            node("MatMul", &["text_embeds", "flat"], &["s"]),
            node("Greater", &["s", "thr"], &["hit_b"]),
            Node { op: "Cast", inputs: &["hit_b"], outputs: &["hit"], ints: &[], int: &[("to", 1)] },
            node("Sub", &["one", "hit"], &["miss"]),
            node("Mul", &["miss", "big"], &["far"]),
            node("Mul", &["hit", "xs"], &["hx"]),
            node("Add", &["hx", "far"], &["hx_far"]),
            node("Mul", &["hit", "ys"], &["hy"]),
            node("Add", &["hy", "far"], &["hy_far"]),
            node("Mul", &["hit", "xs1"], &["hx1"]),
            node("Mul", &["hit", "ys1"], &["hy1"]),
            reduce("ReduceMin", "hx_far", "x0"),
            reduce("ReduceMin", "hy_far", "y0"),
            reduce("ReduceMax", "hx1", "x1"),
            reduce("ReduceMax", "hy1", "y1"),
            node("Div", &["x0", "w"], &["x0n"]),
            node("Div", &["x1", "w"], &["x1n"]),
            node("Div", &["y0", "h"], &["y0n"]),
            node("Div", &["y1", "h"], &["y1n"]),
            Node {
                op: "Concat",
                inputs: &["x0n", "y0n", "x1n", "y1n"],
                outputs: &["boxes_2d"],
                ints: &[],
                int: &[("axis", 1)],
            },
            node("Reshape", &["boxes_2d", "shape_boxes"], &["boxes"]),
            reduce("ReduceMax", "hit", "scores"),
        ],
        &[
            Io { name: "image", dims: &[Some(1), Some(3), Some(PROMPT_H as i64), Some(PROMPT_W as i64)] },
            Io { name: "text_embeds", dims: &[N, Some(3)] },
        ],
        &[Io { name: "boxes", dims: &[N, Some(1), Some(4)] }, Io { name: "scores", dims: &[N, Some(1)] }],
        &[
            ("thr", &[], &[0.5]),
            ("one", &[], &[1.0]),
            ("big", &[], &[1.0e6]),
            ("w", &[], &[PROMPT_W as f32]),
            ("h", &[], &[PROMPT_H as f32]),
            ("xs", &[1, n64], &xs),
            ("ys", &[1, n64], &ys),
            ("xs1", &[1, n64], &xs1),
            ("ys1", &[1, n64], &ys1),
        ],
        &[("shape_flat", &[2], &[3, n64]), ("shape_boxes", &[3], &[-1, 1, 4])],
    )
}

/// Segmenter contract on 32x24 images: the mask is the box (logit = signed distance of the pixel
/// center to the box border, positive inside).
pub fn tiny_segmenter() -> Vec<u8> {
    let n = PROMPT_W * PROMPT_H;
    let xc: Vec<f32> = (0..n).map(|i| (i % PROMPT_W) as f32 + 0.5).collect();
    let yc: Vec<f32> = (0..n).map(|i| (i / PROMPT_W) as f32 + 0.5).collect();
    let e = |k: usize| -> Vec<f32> { (0..4).map(|j| (j == k) as u8 as f32).collect() };
    let (e0, e1, e2, e3) = (e(0), e(1), e(2), e(3));
    let (h, w) = (PROMPT_H as i64, PROMPT_W as i64);
    model_with_ints(
        &[
            node("MatMul", &["box", "e0"], &["bx0"]),
            node("MatMul", &["box", "e1"], &["by0"]),
            node("MatMul", &["box", "e2"], &["bx1"]),
            node("MatMul", &["box", "e3"], &["by1"]),
            node("Sub", &["xc", "bx0"], &["a"]),
            node("Sub", &["bx1", "xc"], &["b"]),
            node("Sub", &["yc", "by0"], &["c"]),
            node("Sub", &["by1", "yc"], &["d"]),
            node("Min", &["a", "b", "c", "d"], &["m"]),
            node("Reshape", &["m", "shape_out"], &["mask_logits"]),
        ],
        &[
            Io { name: "image", dims: &[Some(1), Some(3), Some(h), Some(w)] },
            Io { name: "box", dims: &[Some(1), Some(4)] },
        ],
        &[Io { name: "mask_logits", dims: &[Some(1), Some(1), Some(h), Some(w)] }],
        &[
            ("xc", &[h, w], &xc),
            ("yc", &[h, w], &yc),
            ("e0", &[4, 1], &e0),
            ("e1", &[4, 1], &e1),
            ("e2", &[4, 1], &e2),
            ("e3", &[4, 1], &e3),
        ],
        &[("shape_out", &[4], &[1, 1, h, w])],
    )
}
