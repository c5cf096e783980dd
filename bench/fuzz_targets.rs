//! The fuzzed parsers, their seed inputs and the structure-aware mutator, shared by the fuzz bench
//! (bench/fuzz.rs, which drives millions of inputs) and the regression test (tests/fuzz_cases.rs,
//! which replays the minimized inputs the bench found).
#![allow(dead_code)]

use cogeo::rng::Rng;
use std::alloc::{GlobalAlloc, Layout, System};
use std::cell::Cell;

thread_local! {
    /// Largest single allocation request of this thread since its last reset. Per thread, because
    /// the fuzz bench's workers and the test harness's threads parse at once: a global maximum
    /// charged one input with another thread's allocation (seen on a 16-core machine, where
    /// `the_allocation_check_can_fail`'s 64 MiB landed in `every_seed_is_accepted`).
    static LARGEST: Cell<usize> = const { Cell::new(0) };
}
pub const HARD_CAP: usize = 1 << 30;

/// Starts a new measurement of this thread's largest allocation.
pub fn reset_largest() {
    LARGEST.with(|l| l.set(0));
}

/// This thread's largest single allocation request since `reset_largest`.
pub fn largest() -> usize {
    LARGEST.with(Cell::get)
}

fn note(size: usize) {
    // try_with: an allocation during thread teardown must not panic inside the allocator
    let _ = LARGEST.try_with(|l| l.set(l.get().max(size)));
}

struct Tracking;

unsafe impl GlobalAlloc for Tracking {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        note(layout.size());
        if layout.size() > HARD_CAP {
            return std::ptr::null_mut();
        }
        System.alloc(layout)
    }
    unsafe fn alloc_zeroed(&self, layout: Layout) -> *mut u8 {
        note(layout.size());
        if layout.size() > HARD_CAP {
            return std::ptr::null_mut();
        }
        System.alloc_zeroed(layout)
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        System.dealloc(ptr, layout)
    }
    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        note(new_size);
        if new_size > HARD_CAP {
            return std::ptr::null_mut();
        }
        System.realloc(ptr, layout, new_size)
    }
}

#[global_allocator]
static GLOBAL: Tracking = Tracking;

/// The most one allocation may take while parsing `len` bytes: proportional to the data, never to
/// a count the data claims.
pub fn allocation_bound(len: usize) -> usize {
    (16 << 20) + 4096 * len
}

/// What one input did.
pub enum Outcome {
    Accepted,
    Rejected(String),
    Panic(String),
}

pub fn run_one(family: Family, input: &[u8], seeds: &Seeds) -> (Outcome, usize) {
    reset_largest();
    let result = std::panic::catch_unwind(|| run(family, input, seeds));
    let peak = largest();
    let outcome = match result {
        Ok(Ok(())) => Outcome::Accepted,
        Ok(Err(message)) => Outcome::Rejected(message),
        Err(payload) => Outcome::Panic(
            payload
                .downcast_ref::<String>()
                .cloned()
                .or_else(|| payload.downcast_ref::<&str>().map(|s| s.to_string()))
                .unwrap_or_default(),
        ),
    };
    (outcome, peak)
}

/// A parser family: one user-facing input format and the library call that reads it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Family {
    /// Gaussian PLY, ascii and binary (both endiannesses): `read_ply_from` then `validate`, as
    /// `load_scene` does.
    Ply,
    /// COLMAP cameras.txt / images.txt / points3D.txt (one of the three mutated per input).
    ColmapText,
    /// COLMAP cameras.bin / images.bin / points3D.bin.
    ColmapBin,
    /// INRIA cameras.json.
    CamerasJson,
    /// Label and mask images (PNG of every color type, JPEG), decoded to a 24x16 label map.
    MaskImage,
    /// The prompt-embeddings JSON of `tag --prompt`.
    PromptJson,
    /// `--labels` and `--background` strings.
    FlagValues,
}

pub const FAMILIES: [Family; 7] = [
    Family::Ply,
    Family::ColmapText,
    Family::ColmapBin,
    Family::CamerasJson,
    Family::MaskImage,
    Family::PromptJson,
    Family::FlagValues,
];

impl Family {
    pub fn name(self) -> &'static str {
        match self {
            Family::Ply => "ply",
            Family::ColmapText => "colmap-text",
            Family::ColmapBin => "colmap-bin",
            Family::CamerasJson => "cameras-json",
            Family::MaskImage => "mask-image",
            Family::PromptJson => "prompt-json",
            Family::FlagValues => "flag-values",
        }
    }

    pub fn from_name(name: &str) -> Option<Family> {
        FAMILIES.iter().copied().find(|f| f.name() == name)
    }

    /// Whether mutations that treat the input as lines and words apply.
    fn textual(self) -> bool {
        !matches!(self, Family::ColmapBin | Family::MaskImage)
    }
}

/// How a field of a seed is stored, for mutations that overwrite it with a boundary value.
#[derive(Clone, Copy)]
pub enum Field {
    U64,
    I32,
    F64,
    F32,
    U32Be,
}

/// A valid input with the places a mutation should aim at.
#[derive(Clone)]
pub struct Seed {
    pub bytes: Vec<u8>,
    /// Offsets where the file changes section (end of a header, of a record, of a chunk).
    pub cuts: Vec<usize>,
    /// Binary fields (offset, kind): counts, sizes, floats.
    pub fields: Vec<(usize, Field)>,
    /// For COLMAP: which of the three files this is (0 cameras, 1 images, 2 points3D).
    pub part: usize,
}

/// Runs the family's parser on `input`: Ok(true) accepted, Ok(false)/Err rejected with a message.
/// The caller catches panics and measures allocations.
pub fn run(family: Family, input: &[u8], valid: &Seeds) -> Result<(), String> {
    let e = |e: anyhow::Error| format!("{e:#}");
    match family {
        Family::Ply => {
            let scene = cogeo::scene::ply::read_ply_from(&mut &input[..], "fuzz.ply").map_err(e)?;
            scene.validate("fuzz.ply").map_err(e)
        }
        Family::ColmapText | Family::ColmapBin => {
            let text = family == Family::ColmapText;
            let part = input.first().map_or(0, |b| (*b as usize) % 3);
            let body = input.get(1..).unwrap_or(&[]);
            let names = ["cameras", "images", "points3D"];
            let files: Vec<(&[u8], String)> = (0..3)
                .map(|p| {
                    let data: &[u8] = if p == part { body } else { &valid.colmap(text)[p].bytes };
                    (data, format!("{}.{}", names[p], if text { "txt" } else { "bin" }))
                })
                .collect();
            use cogeo::scene::colmap::{parse_colmap, ModelFile};
            let f = |p: usize| ModelFile { data: files[p].0, text, what: &files[p].1 };
            parse_colmap(&f(0), &f(1), Some(&f(2)), "fuzz").map(|_| ()).map_err(e)
        }
        Family::CamerasJson => cogeo::scene::camera::parse_cameras_json(input, "cameras.json").map(|_| ()).map_err(e),
        Family::MaskImage => cogeo::tag::labels::decode_mask(input, "mask.png", 24, 16).map(|_| ()).map_err(e),
        Family::PromptJson => {
            let prompts = ["statue".to_string(), "bench".to_string()];
            cogeo::tag::prompt::parse_prompt_embeddings(input, "prompts.json", &prompts).map(|_| ()).map_err(e)
        }
        Family::FlagValues => {
            // byte 0 picks the flag; clap hands over UTF-8 only and splits --labels at commas
            let text = String::from_utf8_lossy(input.get(1..).unwrap_or(&[])).into_owned();
            match input.first().map_or(0, |b| b % 3) {
                0 => cogeo::flag_values::parse_rgb(&text).map(|_| ()),
                1 => text.split(',').try_for_each(|s| cogeo::flag_values::parse_object_label(s).map(|_| ())),
                _ => cogeo::flag_values::parse_weight(&text).map(|_| ()),
            }
        }
    }
}

/// Every family's seeds, built once.
pub struct Seeds {
    pub ply: Vec<Seed>,
    pub colmap_text: Vec<Seed>,
    pub colmap_bin: Vec<Seed>,
    pub cameras_json: Vec<Seed>,
    pub images: Vec<Seed>,
    pub prompt: Vec<Seed>,
    pub flags: Vec<Seed>,
}

impl Seeds {
    pub fn new() -> Seeds {
        Seeds {
            ply: super::fuzz_seeds::ply_seeds(),
            colmap_text: super::fuzz_seeds::colmap_text_seeds(),
            colmap_bin: super::fuzz_seeds::colmap_bin_seeds(),
            cameras_json: vec![plain(super::fuzz_seeds::cameras_json_seed())],
            images: super::fuzz_seeds::image_seeds(),
            prompt: vec![plain(br#"{"statue": [0.5, -1.25, 3e-3, 0], "bench": [1, 2, 3, 4], "tree": []}"#.to_vec())],
            flags: vec![flag(0, "0.5,0.25,1"), flag(1, "1,2"), flag(1, "3"), flag(0, "0,0,0"), flag(2, "4")],
        }
    }

    fn colmap(&self, text: bool) -> &[Seed] {
        if text {
            &self.colmap_text
        } else {
            &self.colmap_bin
        }
    }

    pub fn of(&self, family: Family) -> Vec<Seed> {
        match family {
            Family::Ply => self.ply.clone(),
            // the input's first byte says which file it replaces
            Family::ColmapText | Family::ColmapBin => self
                .colmap(family == Family::ColmapText)
                .iter()
                .map(|s| {
                    let mut t = s.clone();
                    t.bytes.insert(0, s.part as u8);
                    t.cuts = std::iter::once(1).chain(s.cuts.iter().map(|c| c + 1)).collect();
                    t.fields = s.fields.iter().map(|&(o, k)| (o + 1, k)).collect();
                    t
                })
                .collect(),
            Family::CamerasJson => self.cameras_json.clone(),
            Family::MaskImage => self.images.clone(),
            Family::PromptJson => self.prompt.clone(),
            Family::FlagValues => self.flags.clone(),
        }
    }
}

pub fn plain(bytes: Vec<u8>) -> Seed {
    let cuts = bytes.iter().enumerate().filter(|(_, &b)| b == b'\n' || b == b',').map(|(i, _)| i + 1).collect();
    Seed { bytes, cuts, fields: Vec::new(), part: 0 }
}

fn flag(which: u8, s: &str) -> Seed {
    let mut bytes = vec![which];
    bytes.extend_from_slice(s.as_bytes());
    plain(bytes)
}

const TOKENS: &[&str] = &[
    "nan",
    "NaN",
    "inf",
    "-inf",
    "Infinity",
    "1e309",
    "-1e309",
    "1e-45",
    "4.9e-324",
    "1e-310",
    "-0",
    "0",
    "-1",
    "1",
    "255",
    "256",
    "65535",
    "65536",
    "32769",
    "2147483648",
    "4294967295",
    "4294967296",
    "1099511627776",
    "18446744073709551615",
    "18446744073709551616",
    "-9223372036854775808",
    "0x10",
    "1.5",
    "+3",
    "",
    "\u{0}",
    "99999999999999999999999999999999999999999999",
    "1e38",
    "3.5e38",
    "double",
    "uchar",
    "list",
    "float",
    "int",
    "element",
    "property",
    "vertex",
    "end_header",
    "null",
    "true",
    "[]",
    "{}",
    "\"\"",
    "[[[[[[[[[[",
    ",",
    ",,",
    "PINHOLE",
    "OPENCV",
    "SIMPLE_RADIAL",
    "FISHEYE",
    "#",
    "\u{fffd}",
    "ä",
    "\\u0000",
];

const F64S: &[f64] = &[f64::NAN, f64::INFINITY, f64::NEG_INFINITY, 0.0, -0.0, 1e308, -1e308, 5e-324, 1e-310, 1.0, -1.0];
const INTS: &[u64] = &[0, 1, 2, 3, 7, 255, 256, 65535, 1 << 31, (1 << 32) - 1, 1 << 32, 1 << 40, 1 << 62, u64::MAX];

/// The `index`-th input of a family: a seed (chosen by the index) with 1-6 stacked mutations, a
/// pure function of (family, seed set, index, salt), so a crash found by a child process can be
/// regenerated by its parent.
pub fn input(family: Family, seeds: &[Seed], index: u64, salt: u64) -> Vec<u8> {
    let mut rng = Rng::new(index.wrapping_mul(0x9e37_79b9_7f4a_7c15) ^ salt ^ (family as u64) << 56);
    let seed = &seeds[(rng.next_u64() % seeds.len() as u64) as usize];
    let mut data = seed.bytes.clone();
    let rounds = 1 + rng.next_u64() % 6;
    for _ in 0..rounds {
        mutate(family, seed, seeds, &mut data, &mut rng);
    }
    data
}

fn pick<T: Copy>(rng: &mut Rng, list: &[T]) -> T {
    list[(rng.next_u64() % list.len() as u64) as usize]
}

fn below(rng: &mut Rng, n: usize) -> usize {
    if n == 0 {
        0
    } else {
        (rng.next_u64() % n as u64) as usize
    }
}

fn mutate(family: Family, seed: &Seed, seeds: &[Seed], data: &mut Vec<u8>, rng: &mut Rng) {
    let len = data.len();
    let keep = usize::from(matches!(family, Family::ColmapText | Family::ColmapBin | Family::FlagValues));
    match rng.next_u64() % 16 {
        0 if len > 0 => data[below(rng, len)] ^= 1 << (rng.next_u64() % 8),
        1 if len > 0 => {
            data[below(rng, len)] = pick(rng, &[0u8, 0xff, 0x7f, 0x80, b'0', b'9', b' ', b'\n', b'-', b'.', b'e', b','])
        }
        2 if len > keep => {
            let at = keep + below(rng, len - keep);
            let n = 1 + below(rng, (len - at).min(64));
            data.drain(at..at + n);
        }
        3 if len > 0 => {
            let at = below(rng, len);
            let n = 1 + below(rng, (len - at).min(256));
            let chunk = data[at..at + n].to_vec();
            let to = below(rng, len + 1);
            data.splice(to..to, chunk);
        }
        4 => data.truncate(keep + below(rng, len.saturating_sub(keep) + 1)),
        5 if !seed.cuts.is_empty() => {
            // truncate at a section boundary, or just before or after it
            let cut = pick(rng, &seed.cuts) as i64 + pick(rng, &[-1i64, 0, 0, 1]);
            data.truncate((cut.max(keep as i64) as usize).min(len));
        }
        6 | 7 if !seed.fields.is_empty() => overwrite_field(data, seed, rng),
        8 => {
            let at = below(rng, len + 1).max(keep.min(len));
            let bad: &[u8] = pick(rng, &[&[0xff, 0xfe][..], &[0xc3], &[0xed, 0xa0, 0x80], &[0], b"\r"]);
            data.splice(at..at, bad.iter().copied());
        }
        9 => {
            // splice: the head of this input with the tail of another seed
            let other = &seeds[below(rng, seeds.len())].bytes;
            let (a, b) = (below(rng, len + 1), below(rng, other.len() + 1));
            data.truncate(a.max(keep.min(len)));
            data.extend_from_slice(&other[b..]);
        }
        10 | 11 if matches!(family, Family::CamerasJson | Family::PromptJson) && mutate_json(data, rng) => {}
        _ if family.textual() => mutate_text(data, keep, rng),
        _ if family == Family::MaskImage => super::fuzz_seeds::mutate_png(data, rng),
        _ if len >= 8 => {
            let at = below(rng, len - 7);
            data[at..at + 8].copy_from_slice(&pick(rng, INTS).to_le_bytes());
        }
        _ => {}
    }
}

fn overwrite_field(data: &mut [u8], seed: &Seed, rng: &mut Rng) {
    let (at, kind) = pick(rng, &seed.fields);
    let bytes: Vec<u8> = match kind {
        Field::U64 => pick(rng, INTS).to_le_bytes().to_vec(),
        Field::I32 => (pick(rng, INTS) as i32).to_le_bytes().to_vec(),
        Field::U32Be => (pick(rng, INTS) as u32).to_be_bytes().to_vec(),
        Field::F64 => pick(rng, F64S).to_le_bytes().to_vec(),
        Field::F32 => (pick(rng, F64S) as f32).to_le_bytes().to_vec(),
    };
    if at + bytes.len() <= data.len() {
        data[at..at + bytes.len()].copy_from_slice(&bytes);
    }
}

/// Word- and line-level edits: a token replaced by a boundary value or keyword, a line duplicated,
/// dropped or moved, a number made enormous.
fn mutate_text(data: &mut Vec<u8>, keep: usize, rng: &mut Rng) {
    let head = data[..keep.min(data.len())].to_vec();
    let body = data[head.len()..].to_vec();
    let mut lines: Vec<Vec<u8>> = body.split(|&b| b == b'\n').map(|l| l.to_vec()).collect();
    let n = lines.len();
    match rng.next_u64() % 6 {
        0..=2 => {
            // replace one whitespace-, comma- or bracket-delimited token
            let li = below(rng, n);
            let line = &lines[li];
            let bounds: Vec<usize> = std::iter::once(0)
                .chain(line.iter().enumerate().filter(|(_, b)| b" ,:[]{}\t".contains(b)).map(|(i, _)| i))
                .chain(std::iter::once(line.len()))
                .collect();
            let k = below(rng, bounds.len() - 1);
            let (mut a, b) = (bounds[k], bounds[k + 1]);
            if a < b && b" ,:[]{}\t".contains(&line[a]) {
                a += 1;
            }
            let token = if rng.next_u64().is_multiple_of(8) {
                "9".repeat(1 + below(rng, 400))
            } else {
                pick(rng, TOKENS).to_string()
            };
            lines[li].splice(a..b, token.bytes());
        }
        3 => {
            let li = below(rng, n);
            let copy = lines[li].clone();
            lines.insert(below(rng, n + 1), copy);
        }
        4 if n > 1 => {
            lines.remove(below(rng, n));
        }
        _ => {
            let (a, b) = (below(rng, n), below(rng, n));
            lines.swap(a, b);
        }
    }
    *data = head;
    data.extend_from_slice(&lines.join(&b'\n'));
}

/// Replaces, drops or repeats one node of a JSON document (when it still parses), so that the
/// edit reaches the reader's field checks instead of the JSON syntax errors.
fn mutate_json(data: &mut Vec<u8>, rng: &mut Rng) -> bool {
    use serde_json::{json, Value};
    let Ok(mut doc) = serde_json::from_slice::<Value>(data) else { return false };
    fn count(v: &Value) -> usize {
        1 + match v {
            Value::Array(a) => a.iter().map(count).sum(),
            Value::Object(o) => o.values().map(count).sum(),
            _ => 0,
        }
    }
    /// Applies `f` to the k-th node in pre-order.
    fn at_node(v: &mut Value, k: &mut usize, f: &mut dyn FnMut(&mut Value)) -> bool {
        if *k == 0 {
            f(v);
            return true;
        }
        *k -= 1;
        match v {
            Value::Array(a) => a.iter_mut().any(|c| at_node(c, k, f)),
            Value::Object(o) => o.values_mut().any(|c| at_node(c, k, f)),
            _ => false,
        }
    }
    let mut k = below(rng, count(&doc));
    let numbers = [
        json!(0),
        json!(-1),
        json!(1.5),
        json!(-0.0),
        json!(1e308),
        json!(-1e308),
        json!(5e-324),
        json!(4294967296u64),
        json!(u64::MAX),
        json!(i64::MIN),
        json!(65536),
        json!(32769),
    ];
    let (choice, r1, r2) = (rng.next_u64() % 8, rng.next_u64() as usize, rng.next_u64() as usize);
    at_node(&mut doc, &mut k, &mut |node| edit_json(node, choice, r1, r2, &numbers));
    *data = if rng.next_u64().is_multiple_of(2) { serde_json::to_vec(&doc) } else { serde_json::to_vec_pretty(&doc) }
        .unwrap();
    true
}

fn edit_json(node: &mut serde_json::Value, choice: u64, r1: usize, r2: usize, numbers: &[serde_json::Value]) {
    use serde_json::{json, Value};
    match choice {
        0 => *node = numbers[r1 % numbers.len()].clone(),
        1 => *node = [Value::Null, json!(true), json!("x"), json!([]), json!({})][r1 % 5].clone(),
        2 => *node = Value::Array(vec![node.clone(); r1 % 4]),
        3 => {
            let mut deep = node.clone();
            for _ in 0..r1 % 300 {
                deep = Value::Array(vec![deep]);
            }
            *node = deep;
        }
        4 | 5 => match node {
            Value::Object(o) if !o.is_empty() => {
                let key = o.keys().nth(r1 % o.len()).unwrap().clone();
                o.remove(&key);
            }
            Value::Array(a) if !a.is_empty() => {
                let i = r1 % a.len();
                if r2.is_multiple_of(2) {
                    a.remove(i);
                } else {
                    let c = a[i].clone();
                    a.insert(i, c);
                }
            }
            _ => *node = Value::Null,
        },
        6 => {
            if let Value::Object(o) = node {
                o.insert("unexpected".into(), json!(1));
            }
        }
        _ => {
            if let Value::Number(n) = node {
                *node = json!(n.as_f64().unwrap_or(0.0) * [1e30, -1.0, 1e-30, 0.0][r1 % 4]);
            }
        }
    }
}
