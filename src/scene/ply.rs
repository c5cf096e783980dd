//! INRIA 3DGS PLY reading and writing (conventions.md "PLY"). Reads ascii and binary (either
//! endianness), any property order, SH degree 0..3, and keeps unknown properties; writes
//! binary_little_endian in the INRIA order followed by the extra properties.

use super::{sh_coeffs, ExtraProperty, GaussianScene, PlyType};
use crate::io::write_atomic;
use anyhow::{anyhow, bail, Context, Result};
use std::io::{BufRead, BufReader, Write};
use std::path::Path;

impl PlyType {
    fn parse(s: &str) -> Option<PlyType> {
        Some(match s {
            "char" | "int8" => PlyType::I8,
            "uchar" | "uint8" => PlyType::U8,
            "short" | "int16" => PlyType::I16,
            "ushort" | "uint16" => PlyType::U16,
            "int" | "int32" => PlyType::I32,
            "uint" | "uint32" => PlyType::U32,
            "float" | "float32" => PlyType::F32,
            "double" | "float64" => PlyType::F64,
            _ => return None,
        })
    }

    fn name(self) -> &'static str {
        match self {
            PlyType::I8 => "char",
            PlyType::U8 => "uchar",
            PlyType::I16 => "short",
            PlyType::U16 => "ushort",
            PlyType::I32 => "int",
            PlyType::U32 => "uint",
            PlyType::F32 => "float",
            PlyType::F64 => "double",
        }
    }

    fn size(self) -> usize {
        match self {
            PlyType::I8 | PlyType::U8 => 1,
            PlyType::I16 | PlyType::U16 => 2,
            PlyType::I32 | PlyType::U32 | PlyType::F32 => 4,
            PlyType::F64 => 8,
        }
    }

    fn decode(self, b: &[u8], little: bool) -> f64 {
        macro_rules! get {
            ($t:ty, $n:expr) => {{
                let a: [u8; $n] = b[..$n].try_into().unwrap();
                (if little { <$t>::from_le_bytes(a) } else { <$t>::from_be_bytes(a) }) as f64
            }};
        }
        match self {
            PlyType::I8 => b[0] as i8 as f64,
            PlyType::U8 => b[0] as f64,
            PlyType::I16 => get!(i16, 2),
            PlyType::U16 => get!(u16, 2),
            PlyType::I32 => get!(i32, 4),
            PlyType::U32 => get!(u32, 4),
            PlyType::F32 => get!(f32, 4),
            PlyType::F64 => get!(f64, 8),
        }
    }

    fn encode(self, v: f64, out: &mut Vec<u8>) {
        match self {
            PlyType::I8 => out.push(v as i8 as u8),
            PlyType::U8 => out.push(v as u8),
            PlyType::I16 => out.extend_from_slice(&(v as i16).to_le_bytes()),
            PlyType::U16 => out.extend_from_slice(&(v as u16).to_le_bytes()),
            PlyType::I32 => out.extend_from_slice(&(v as i32).to_le_bytes()),
            PlyType::U32 => out.extend_from_slice(&(v as u32).to_le_bytes()),
            PlyType::F32 => out.extend_from_slice(&(v as f32).to_le_bytes()),
            PlyType::F64 => out.extend_from_slice(&v.to_le_bytes()),
        }
    }
}

#[derive(Clone, Copy, PartialEq)]
enum Format {
    Ascii,
    BinaryLittle,
    BinaryBig,
}

/// Where each known attribute lives among the vertex properties.
enum Slot {
    Mean(usize),
    Normal(usize),
    Scale(usize),
    Rot(usize),
    Opacity,
    Dc(usize),
    Rest(usize),
    Extra(usize),
}

/// Reads an INRIA-layout Gaussian PLY. Errors name the file and what is wrong with it.
pub fn read_ply(path: &Path) -> Result<GaussianScene> {
    let file = std::fs::File::open(path).with_context(|| format!("{}: cannot open", path.display()))?;
    let mut reader = BufReader::with_capacity(1 << 20, file);
    read_ply_from(&mut reader, &path.display().to_string())
}

pub fn read_ply_from<R: BufRead>(reader: &mut R, what: &str) -> Result<GaussianScene> {
    read_vertices(reader, what, true)
}

/// Reads a point-cloud PLY (x, y, z; colors such as red, green, blue and any other property land
/// in `extras`), as the `ply_file_path` of a transforms.json capture.
pub fn read_point_cloud(path: &Path) -> Result<GaussianScene> {
    let file = std::fs::File::open(path).with_context(|| format!("{}: cannot open", path.display()))?;
    let mut reader = BufReader::with_capacity(1 << 20, file);
    read_vertices(&mut reader, &path.display().to_string(), false)
}

/// The vertices of a PLY as a scene; `gaussian`: every INRIA Gaussian property is required
/// (otherwise only the position).
fn read_vertices<R: BufRead>(reader: &mut R, what: &str, gaussian: bool) -> Result<GaussianScene> {
    // header
    let mut line = String::new();
    let mut next_line = |reader: &mut R| -> Result<String> {
        line.clear();
        let n = reader.read_line(&mut line).with_context(|| format!("{what}: read error in the PLY header"))?;
        if n == 0 {
            bail!("{what}: the PLY header ends before end_header");
        }
        Ok(line.trim_end_matches(['\n', '\r']).to_string())
    };
    if next_line(reader)? != "ply" {
        bail!("{what}: not a PLY file (first line is not \"ply\")");
    }
    let mut format = None;
    let mut count = None;
    let mut props: Vec<(String, PlyType)> = Vec::new();
    let mut in_vertex = false;
    loop {
        let l = next_line(reader)?;
        let words: Vec<&str> = l.split_whitespace().collect();
        match words.as_slice() {
            ["end_header"] => break,
            ["format", f, _] => {
                format = Some(match *f {
                    "ascii" => Format::Ascii,
                    "binary_little_endian" => Format::BinaryLittle,
                    "binary_big_endian" => Format::BinaryBig,
                    _ => bail!("{what}: unknown PLY format {f:?}"),
                })
            }
            ["comment", ..] | ["obj_info", ..] | [] => {}
            ["element", name, n] => {
                let n: usize = n.parse().map_err(|_| anyhow!("{what}: bad element count in {l:?}"))?;
                if *name == "vertex" {
                    if count.is_some() {
                        bail!("{what}: more than one vertex element");
                    }
                    count = Some(n);
                    in_vertex = true;
                } else {
                    if n != 0 {
                        bail!("{what}: unsupported PLY element {name:?} with {n} entries (a Gaussian PLY has only vertices)");
                    }
                    in_vertex = false;
                }
            }
            ["property", "list", ..] => {
                if in_vertex {
                    bail!("{what}: list properties on vertices are not supported");
                }
            }
            ["property", ty, name] => {
                if in_vertex {
                    let t = PlyType::parse(ty).ok_or_else(|| anyhow!("{what}: unknown property type {ty:?}"))?;
                    if props.iter().any(|(n, _)| n == name) {
                        bail!("{what}: property {name:?} appears twice");
                    }
                    props.push((name.to_string(), t));
                }
            }
            _ => bail!("{what}: unrecognized PLY header line {l:?}"),
        }
    }
    let format = format.ok_or_else(|| anyhow!("{what}: the PLY header has no format line"))?;
    let n = count.ok_or_else(|| anyhow!("{what}: the PLY has no vertex element"))?;

    // map properties to attributes
    let find = |name: &str| props.iter().position(|(p, _)| p == name);
    let required: &[&str] = if gaussian {
        &[
            "x", "y", "z", "opacity", "scale_0", "scale_1", "scale_2", "rot_0", "rot_1", "rot_2", "rot_3", "f_dc_0",
            "f_dc_1", "f_dc_2",
        ]
    } else {
        &["x", "y", "z"]
    };
    for &req in required {
        if find(req).is_none() {
            let kind = if gaussian { " (not an INRIA Gaussian PLY?)" } else { "" };
            bail!("{what}: missing required property {req:?}{kind}");
        }
    }
    let n_rest = (0..).take_while(|i| find(&format!("f_rest_{i}")).is_some()).count();
    let sh_degree = match n_rest {
        0 => 0,
        9 => 1,
        24 => 2,
        45 => 3,
        _ => bail!("{what}: {n_rest} f_rest properties; expected 0, 9, 24 or 45 (SH degree 0..3)"),
    };
    let k = sh_coeffs(sh_degree);
    let mut extras: Vec<ExtraProperty> = Vec::new();
    let slots: Vec<Slot> = props
        .iter()
        .map(|(name, ty)| {
            let idx = |prefix: &str| name.strip_prefix(prefix).and_then(|s| s.parse::<usize>().ok());
            match name.as_str() {
                "x" => Slot::Mean(0),
                "y" => Slot::Mean(1),
                "z" => Slot::Mean(2),
                "nx" => Slot::Normal(0),
                "ny" => Slot::Normal(1),
                "nz" => Slot::Normal(2),
                "opacity" => Slot::Opacity,
                _ => {
                    if let Some(i) = idx("scale_").filter(|&i| i < 3) {
                        Slot::Scale(i)
                    } else if let Some(i) = idx("rot_").filter(|&i| i < 4) {
                        Slot::Rot(i)
                    } else if let Some(i) = idx("f_dc_").filter(|&i| i < 3) {
                        Slot::Dc(i)
                    } else if let Some(i) = idx("f_rest_").filter(|&i| i < n_rest) {
                        Slot::Rest(i)
                    } else {
                        extras.push(ExtraProperty { name: name.clone(), ty: *ty, values: Vec::new() });
                        Slot::Extra(extras.len() - 1)
                    }
                }
            }
        })
        .collect();

    // The header's count is a claim: storage grows with the rows actually read (in blocks of at
    // most ROWS), so a header claiming 2^40 vertices fails at the end of the data, not in malloc.
    const ROWS: usize = 4096;
    let mut scene = GaussianScene {
        means: Vec::new(),
        normals: Vec::new(),
        log_scales: Vec::new(),
        quats: Vec::new(),
        opacity_logits: Vec::new(),
        sh_degree,
        sh: Vec::new(),
        extras,
    };
    let grow = |scene: &mut GaussianScene, rows: usize| {
        let len = scene.means.len() + rows;
        scene.means.resize(len, [0.0; 3]);
        scene.normals.resize(len, [0.0; 3]);
        scene.log_scales.resize(len, [0.0; 3]);
        scene.quats.resize(len, [0.0; 4]);
        scene.opacity_logits.resize(len, 0.0);
        scene.sh.resize(len * k * 3, 0.0);
    };
    let store = |scene: &mut GaussianScene, i: usize, slot: &Slot, v: f64| match *slot {
        Slot::Mean(c) => scene.means[i][c] = v as f32,
        Slot::Normal(c) => scene.normals[i][c] = v as f32,
        Slot::Scale(c) => scene.log_scales[i][c] = v as f32,
        Slot::Rot(c) => scene.quats[i][c] = v as f32,
        Slot::Opacity => scene.opacity_logits[i] = v as f32,
        Slot::Dc(c) => scene.sh[i * k * 3 + c] = v as f32,
        // f_rest is channel-major: f_rest[c*(K-1) + (b-1)] is channel c of basis b
        Slot::Rest(j) => {
            let (c, b) = (j / (k - 1), j % (k - 1) + 1);
            scene.sh[(i * k + b) * 3 + c] = v as f32
        }
        Slot::Extra(e) => scene.extras[e].values.push(v),
    };

    match format {
        Format::Ascii => {
            let mut text = String::new();
            reader
                .read_to_string(&mut text)
                .with_context(|| format!("{what}: read error (an ascii PLY must be UTF-8 text)"))?;
            let mut tokens = text.split_ascii_whitespace();
            for i in 0..n {
                if i % ROWS == 0 {
                    grow(&mut scene, (n - i).min(ROWS));
                }
                for (j, slot) in slots.iter().enumerate() {
                    let tok = tokens
                        .next()
                        .ok_or_else(|| anyhow!("{what}: file ends in vertex {i} of {n} (truncated PLY)"))?;
                    // float properties are parsed as f32 directly: going through f64 could round twice
                    let parsed = match props[j].1 {
                        PlyType::F32 => tok.parse::<f32>().map(|v| v as f64).ok(),
                        _ => tok.parse::<f64>().ok(),
                    };
                    let v = parsed.ok_or_else(|| {
                        anyhow!("{what}: vertex {i}: property {:?} has unparsable value {tok:?}", props[j].0)
                    })?;
                    store(&mut scene, i, slot, v);
                }
            }
        }
        Format::BinaryLittle | Format::BinaryBig => {
            let little = format == Format::BinaryLittle;
            let stride: usize = props.iter().map(|(_, t)| t.size()).sum();
            let offsets: Vec<usize> = props
                .iter()
                .scan(0, |o, (_, t)| {
                    let cur = *o;
                    *o += t.size();
                    Some(cur)
                })
                .collect();
            // rows per read: ROWS, fewer for very wide rows (the read buffer stays near 1 MiB)
            let block = ROWS.min((1 << 20) / stride.max(1)).max(1);
            let mut buf = vec![0u8; stride * n.min(block)];
            let mut i = 0;
            while i < n {
                let rows = (n - i).min(block);
                let chunk = &mut buf[..rows * stride];
                if let Err(e) = reader.read_exact(chunk) {
                    if e.kind() == std::io::ErrorKind::UnexpectedEof {
                        bail!("{what}: file ends within vertices {i}..{} of {n} (truncated PLY)", i + rows);
                    }
                    return Err(e).with_context(|| format!("{what}: read error"));
                }
                grow(&mut scene, rows);
                for r in 0..rows {
                    let row = &chunk[r * stride..(r + 1) * stride];
                    for (j, slot) in slots.iter().enumerate() {
                        let v = props[j].1.decode(&row[offsets[j]..], little);
                        store(&mut scene, i + r, slot, v);
                    }
                }
                i += rows;
            }
        }
    }
    Ok(scene)
}

/// The PLY header and body of a scene in the INRIA layout, extra properties last.
pub fn encode_ply(scene: &GaussianScene) -> Vec<u8> {
    let n = scene.len();
    let k = scene.sh_coeffs();
    let mut header = String::from("ply\nformat binary_little_endian 1.0\n");
    header += &format!("element vertex {n}\n");
    let mut names: Vec<String> =
        ["x", "y", "z", "nx", "ny", "nz", "f_dc_0", "f_dc_1", "f_dc_2"].iter().map(|s| s.to_string()).collect();
    names.extend((0..3 * (k - 1)).map(|i| format!("f_rest_{i}")));
    names.push("opacity".into());
    names.extend((0..3).map(|i| format!("scale_{i}")));
    names.extend((0..4).map(|i| format!("rot_{i}")));
    for name in &names {
        header += &format!("property float {name}\n");
    }
    for e in &scene.extras {
        header += &format!("property {} {}\n", e.ty.name(), e.name);
    }
    header += "end_header\n";
    let stride = names.len() * 4 + scene.extras.iter().map(|e| e.ty.size()).sum::<usize>();
    let mut out = Vec::with_capacity(header.len() + n * stride);
    out.extend_from_slice(header.as_bytes());
    let put = |v: f32, out: &mut Vec<u8>| out.extend_from_slice(&v.to_le_bytes());
    for i in 0..n {
        scene.means[i].iter().for_each(|&v| put(v, &mut out));
        let normal = scene.normals.get(i).copied().unwrap_or([0.0; 3]);
        normal.iter().for_each(|&v| put(v, &mut out));
        (0..3).for_each(|c| put(scene.sh[i * k * 3 + c], &mut out));
        for c in 0..3 {
            for b in 1..k {
                put(scene.sh[(i * k + b) * 3 + c], &mut out);
            }
        }
        put(scene.opacity_logits[i], &mut out);
        scene.log_scales[i].iter().for_each(|&v| put(v, &mut out));
        scene.quats[i].iter().for_each(|&v| put(v, &mut out));
        for e in &scene.extras {
            e.ty.encode(e.values[i], &mut out);
        }
    }
    out
}

/// Writes the scene atomically (temporary file, then rename): never a half-written PLY.
pub fn write_ply(scene: &GaussianScene, path: &Path) -> Result<()> {
    let bytes = encode_ply(scene);
    write_atomic(path, |w| w.write_all(&bytes).map_err(Into::into))
}
