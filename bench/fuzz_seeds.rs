//! Valid seed inputs for the fuzzer (bench/fuzz_targets.rs), written field by field so that the
//! mutator knows where the counts, sizes, floats and section ends are; and the PNG chunk mutator,
//! which keeps chunk CRCs valid so that mutations reach the decoder instead of its checksum test.
#![allow(dead_code)]

use super::fuzz_targets::{plain, Field, Seed};
use cogeo::rng::Rng;

/// PLY property types as named in headers, with their sizes.
const PLY_TYPES: [(&str, usize); 8] =
    [("char", 1), ("uchar", 1), ("short", 2), ("ushort", 2), ("int", 4), ("uint", 4), ("float", 4), ("double", 8)];

/// A Gaussian PLY with the given format, SH degree, Gaussian count and extra properties; required
/// floats are sometimes stored as double, and the property order is shuffled when `shuffle`.
fn ply_seed(format: &str, sh_degree: usize, n: usize, extras: &[(&str, &str)], shuffle: bool, salt: u64) -> Seed {
    let mut rng = Rng::new(salt);
    let mut props: Vec<(String, &str)> = ["x", "y", "z", "nx", "ny", "nz", "f_dc_0", "f_dc_1", "f_dc_2"]
        .iter()
        .map(|p| (p.to_string(), if salt.is_multiple_of(3) { "double" } else { "float" }))
        .collect();
    let rest = [0, 9, 24, 45][sh_degree];
    props.extend((0..rest).map(|i| (format!("f_rest_{i}"), "float")));
    props.extend(
        ["opacity", "scale_0", "scale_1", "scale_2", "rot_0", "rot_1", "rot_2", "rot_3"]
            .map(|p| (p.to_string(), "float")),
    );
    props.extend(extras.iter().map(|(n, t)| (n.to_string(), *t)));
    if shuffle {
        for i in (1..props.len()).rev() {
            props.swap(i, (rng.next_u64() % (i as u64 + 1)) as usize);
        }
    }
    let mut header = format!("ply\nformat {format} 1.0\ncomment fuzz seed\nelement vertex {n}\n");
    for (name, ty) in &props {
        header += &format!("property {ty} {name}\n");
    }
    header += "end_header\n";
    let mut bytes = header.clone().into_bytes();
    let mut cuts: Vec<usize> = header.match_indices('\n').map(|(i, _)| i + 1).collect();
    let mut fields = Vec::new();
    let little = format == "binary_little_endian";
    for _ in 0..n {
        for (name, ty) in &props {
            let v = match name.as_str() {
                "rot_0" => 1.0,
                "opacity" => rng.range(-2.0, 2.0),
                s if s.starts_with("scale") => rng.range(-4.0, -1.0),
                s if s.starts_with("label") => (rng.next_u64() % 4) as f64,
                _ => rng.range(-1.0, 1.0),
            };
            if format == "ascii" {
                let text =
                    if ty.contains("float") || *ty == "double" { format!("{v}") } else { format!("{}", v as i64) };
                bytes.extend_from_slice(text.as_bytes());
                bytes.push(b' ');
                continue;
            }
            let size = PLY_TYPES.iter().find(|(t, _)| t == ty).unwrap().1;
            let at = bytes.len();
            let raw: Vec<u8> = match *ty {
                "float" => {
                    if little {
                        fields.push((at, Field::F32));
                    }
                    if little { (v as f32).to_le_bytes() } else { (v as f32).to_be_bytes() }.to_vec()
                }
                "double" => {
                    if little {
                        fields.push((at, Field::F64));
                    }
                    if little { v.to_le_bytes() } else { v.to_be_bytes() }.to_vec()
                }
                _ => {
                    let i = v as i64 as u64;
                    let b = if little { i.to_le_bytes() } else { i.to_be_bytes() };
                    if little {
                        b[..size].to_vec()
                    } else {
                        b[8 - size..].to_vec()
                    }
                }
            };
            bytes.extend_from_slice(&raw);
        }
        if format == "ascii" {
            bytes.push(b'\n');
        }
        cuts.push(bytes.len());
    }
    Seed { bytes, cuts, fields, part: 0 }
}

pub fn ply_seeds() -> Vec<Seed> {
    vec![
        ply_seed("binary_little_endian", 0, 6, &[], false, 1),
        ply_seed("binary_little_endian", 1, 4, &[("label", "uchar"), ("f_feat_0", "float")], true, 2),
        ply_seed("binary_little_endian", 3, 2, &[("label", "uchar")], false, 3),
        ply_seed("binary_big_endian", 2, 3, &[("label", "int")], true, 4),
        ply_seed("ascii", 0, 5, &[], false, 5),
        ply_seed("ascii", 1, 3, &[("label", "uchar"), ("confidence", "double")], true, 6),
    ]
}

/// A seed camera: id, model name, model id, width, height, parameters.
type SeedCamera = (i32, &'static str, i32, u64, u64, &'static [f64]);
/// A seed image: id, quaternion, translation, camera id, file name.
type SeedImage = (i32, [f64; 4], [f64; 3], i32, &'static str);

/// COLMAP seeds: two cameras (PINHOLE, OPENCV), three images, four points; text and binary.
const CAMERAS: [SeedCamera; 2] = [
    (1, "PINHOLE", 1, 64, 48, &[60.0, 61.0, 32.0, 24.0]),
    (2, "OPENCV", 4, 32, 24, &[30.0, 30.0, 16.0, 12.0, 0.01, -0.02, 0.0, 0.0]),
];
const IMAGES: [SeedImage; 3] = [
    (1, [1.0, 0.0, 0.0, 0.0], [0.0, 0.0, 4.0], 1, "a.png"),
    (2, [0.9, 0.1, 0.3, 0.0], [0.5, 0.0, 4.0], 1, "b.png"),
    (3, [0.7, 0.0, 0.7, 0.1], [0.0, 0.2, 3.5], 2, "c d.jpg"),
];
const POINTS: [[f64; 3]; 4] = [[0.0, 0.0, 0.0], [0.5, -0.2, 0.1], [-0.3, 0.4, 0.2], [0.1, 0.1, -0.5]];

pub fn colmap_text_seeds() -> Vec<Seed> {
    let mut cameras = "# Camera list\n".to_string();
    for (id, model, _, w, h, p) in CAMERAS {
        let params: Vec<String> = p.iter().map(|v| v.to_string()).collect();
        cameras += &format!("{id} {model} {w} {h} {}\n", params.join(" "));
    }
    let mut images = "# Image list\n".to_string();
    for (id, q, t, cam, name) in IMAGES {
        images += &format!(
            "{id} {} {} {} {} {} {} {} {cam} {name}\n10.5 20.25 1 11.0 3.0 -1\n",
            q[0], q[1], q[2], q[3], t[0], t[1], t[2]
        );
    }
    let mut points = "# 3D point list\n".to_string();
    for (i, p) in POINTS.iter().enumerate() {
        points += &format!("{} {} {} {} 200 {} 30 0.5 1 0 2 1\n", i + 1, p[0], p[1], p[2], 50 * i);
    }
    [cameras, images, points]
        .into_iter()
        .enumerate()
        .map(|(part, text)| Seed { part, ..plain(text.into_bytes()) })
        .collect()
}

struct BinWriter {
    bytes: Vec<u8>,
    cuts: Vec<usize>,
    fields: Vec<(usize, Field)>,
}

impl BinWriter {
    fn new() -> BinWriter {
        BinWriter { bytes: Vec::new(), cuts: Vec::new(), fields: Vec::new() }
    }
    fn u64(&mut self, v: u64) {
        self.fields.push((self.bytes.len(), Field::U64));
        self.bytes.extend_from_slice(&v.to_le_bytes());
    }
    fn i32(&mut self, v: i32) {
        self.fields.push((self.bytes.len(), Field::I32));
        self.bytes.extend_from_slice(&v.to_le_bytes());
    }
    fn f64(&mut self, v: f64) {
        self.fields.push((self.bytes.len(), Field::F64));
        self.bytes.extend_from_slice(&v.to_le_bytes());
    }
    fn cut(&mut self) {
        self.cuts.push(self.bytes.len());
    }
    fn seed(self, part: usize) -> Seed {
        Seed { bytes: self.bytes, cuts: self.cuts, fields: self.fields, part }
    }
}

pub fn colmap_bin_seeds() -> Vec<Seed> {
    let mut cameras = BinWriter::new();
    cameras.u64(CAMERAS.len() as u64);
    for (id, _, model, w, h, p) in CAMERAS {
        cameras.cut();
        cameras.i32(id);
        cameras.i32(model);
        cameras.u64(w);
        cameras.u64(h);
        p.iter().for_each(|&v| cameras.f64(v));
    }
    let mut images = BinWriter::new();
    images.u64(IMAGES.len() as u64);
    for (id, q, t, cam, name) in IMAGES {
        images.cut();
        images.i32(id);
        q.iter().chain(&t).for_each(|&v| images.f64(v));
        images.i32(cam);
        images.bytes.extend_from_slice(name.as_bytes());
        images.bytes.push(0);
        images.cut();
        images.u64(2);
        for k in 0..2 {
            images.f64(10.0 * k as f64);
            images.f64(5.0);
            images.bytes.extend_from_slice(&(k as u64).to_le_bytes());
        }
    }
    let mut points = BinWriter::new();
    points.u64(POINTS.len() as u64);
    for (i, p) in POINTS.iter().enumerate() {
        points.cut();
        points.u64(i as u64 + 1);
        p.iter().for_each(|&v| points.f64(v));
        points.bytes.extend_from_slice(&[200, 50, 30]);
        points.f64(0.5);
        points.u64(2);
        points.bytes.extend_from_slice(&[1, 0, 0, 0, 0, 0, 0, 0, 2, 0, 0, 0, 1, 0, 0, 0]);
    }
    vec![cameras.seed(0), images.seed(1), points.seed(2)]
}

pub fn cameras_json_seed() -> Vec<u8> {
    let cameras = vec![
        cogeo::scene::Camera::look_at("view_000", 64, 48, 60.0, [0.0, -1.0, 4.0], [0.0; 3], [0.0, -1.0, 0.0]),
        cogeo::scene::Camera::look_at("view_001", 32, 24, 30.0, [3.0, -1.0, 2.0], [0.0; 3], [0.0, -1.0, 0.0]),
    ];
    cogeo::scene::camera::encode_cameras_json(&cameras).unwrap().into_bytes()
}

/// Label maps and masks as PNG (8- and 16-bit gray, RGB, RGBA, gray+alpha) and JPEG, with the PNG
/// chunk boundaries as cuts and the IHDR width and height as fields.
pub fn image_seeds() -> Vec<Seed> {
    use image::{ColorType, ImageFormat};
    let (w, h) = (24u32, 16u32);
    let label = |x: u32, y: u32| ((x / 6 + y / 4) % 4) as u8;
    let encode = |color: ColorType, bytes_per_pixel: usize, format: ImageFormat| {
        let mut px = Vec::new();
        for y in 0..h {
            for x in 0..w {
                let v = label(x, y) * 60;
                px.extend(std::iter::repeat_n(v, bytes_per_pixel));
            }
        }
        let mut out = std::io::Cursor::new(Vec::new());
        image::write_buffer_with_format(&mut out, &px, w, h, color, format).unwrap();
        out.into_inner()
    };
    let mut seeds: Vec<Seed> =
        [(ColorType::L8, 1), (ColorType::L16, 2), (ColorType::Rgb8, 3), (ColorType::Rgba8, 4), (ColorType::La8, 2)]
            .into_iter()
            .map(|(c, b)| png_seed(encode(c, b, ImageFormat::Png)))
            .collect();
    seeds.push(plain(encode(ColorType::Rgb8, 3, ImageFormat::Jpeg)));
    seeds
}

fn png_chunks(data: &[u8]) -> Vec<(usize, usize)> {
    // (offset of the length field, data length) of each chunk whose header is complete
    let mut out = Vec::new();
    let mut at = 8;
    while at + 8 <= data.len() {
        let len = u32::from_be_bytes(data[at..at + 4].try_into().unwrap()) as usize;
        out.push((at, len));
        at = match at.checked_add(12 + len) {
            Some(next) => next,
            None => break,
        };
    }
    out
}

fn png_seed(bytes: Vec<u8>) -> Seed {
    let chunks = png_chunks(&bytes);
    let cuts = chunks.iter().map(|&(at, _)| at).chain(std::iter::once(bytes.len())).collect();
    // IHDR: width and height right after the chunk type
    let fields = vec![(16, Field::U32Be), (20, Field::U32Be)];
    Seed { bytes, cuts, fields, part: 0 }
}

fn crc32(data: &[u8]) -> u32 {
    let mut crc = !0u32;
    for &b in data {
        crc ^= b as u32;
        for _ in 0..8 {
            crc = if crc & 1 != 0 { (crc >> 1) ^ 0xedb8_8320 } else { crc >> 1 };
        }
    }
    !crc
}

/// Edits one chunk of a PNG (IHDR fields, bytes of any chunk, a chunk dropped or repeated) and
/// recomputes its CRC, so the decoder sees the edit.
pub fn mutate_png(data: &mut Vec<u8>, rng: &mut Rng) {
    let chunks: Vec<(usize, usize)> =
        png_chunks(data).into_iter().filter(|&(at, len)| at + 12 + len <= data.len()).collect();
    if chunks.is_empty() {
        return;
    }
    let (at, len) = chunks[(rng.next_u64() % chunks.len() as u64) as usize];
    let body = at + 8;
    match rng.next_u64() % 4 {
        0 if &data[at + 4..at + 8] == b"IHDR" && len >= 13 => {
            let k = (rng.next_u64() % 7) as usize;
            if k < 2 {
                // width or height: sizes at and beyond the limits
                let sizes = [0u32, 1, 2, 32768, 32769, 65535, 1 << 20, 1 << 31, u32::MAX];
                let v = sizes[(rng.next_u64() % sizes.len() as u64) as usize];
                data[body + 4 * k..body + 4 * k + 4].copy_from_slice(&v.to_be_bytes());
            } else {
                // bit depth, color type, compression, filter, interlace
                data[body + 6 + k] = [0u8, 1, 2, 3, 4, 6, 7, 8, 16, 255][(rng.next_u64() % 10) as usize];
            }
        }
        1 if len > 0 => {
            let i = body + (rng.next_u64() % len as u64) as usize;
            data[i] = rng.next_u64() as u8;
        }
        2 => {
            data.drain(at..at + 12 + len);
            return;
        }
        _ => {
            let chunk = data[at..at + 12 + len].to_vec();
            data.splice(at..at, chunk);
            return;
        }
    }
    let crc = crc32(&data[at + 4..body + len]);
    data[body + len..body + len + 4].copy_from_slice(&crc.to_be_bytes());
}
