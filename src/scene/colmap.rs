//! COLMAP sparse models (`cameras`, `images`, `points3D`; `.bin` or `.txt`).

use super::camera::{rotation_from_qvec, Camera};
use super::lens::{parameter_count, ColmapIntrinsics, Lens};
use anyhow::{anyhow, bail, Context, Result};
use std::collections::HashMap;
use std::io::Read;
use std::path::{Path, PathBuf};

/// One COLMAP camera: its image size, focal lengths, principal point and lens.
#[derive(Clone, Debug)]
struct Intrinsics {
    width: u32,
    height: u32,
    k: ColmapIntrinsics,
}

/// A sparse point (for initializing training).
#[derive(Clone, Debug)]
pub struct Point3D {
    pub xyz: [f64; 3],
    pub rgb: [u8; 3],
}

/// A loaded capture model (a COLMAP model, or a transforms.json read into the same shape):
/// cameras sorted by image name, and the sparse points.
#[derive(Debug)]
pub struct ColmapModel {
    /// Each image's camera as COLMAP stores it: with a lens other than the pinhole, its focal
    /// lengths and principal point apply to the distorted photo (`lenses`).
    pub cameras: Vec<Camera>,
    /// Each camera's lens distortion (same order); scene/undistort.rs resamples the photos.
    pub lenses: Vec<Lens>,
    pub points: Vec<Point3D>,
    pub warnings: Vec<String>,
}

/// Finds the folder holding cameras/images files: `dir`, `dir/sparse/0` or `dir/sparse`.
pub fn find_model_dir(dir: &Path) -> Result<PathBuf> {
    for cand in [dir.to_path_buf(), dir.join("sparse/0"), dir.join("sparse")] {
        if cand.join("cameras.bin").exists() || cand.join("cameras.txt").exists() {
            return Ok(cand);
        }
    }
    bail!("{}: no COLMAP model (cameras.bin/.txt) here or in sparse/0", dir.display())
}

/// The name of a COLMAP camera model id (the binary format's), with its parameter count.
fn model_info(id: i32) -> Option<(&'static str, usize)> {
    let name = match id {
        0 => "SIMPLE_PINHOLE",
        1 => "PINHOLE",
        2 => "SIMPLE_RADIAL",
        3 => "RADIAL",
        4 => "OPENCV",
        5 => "OPENCV_FISHEYE",
        6 => "FULL_OPENCV",
        7 => return Some(("FOV", 5)),
        8 => "SIMPLE_RADIAL_FISHEYE",
        9 => "RADIAL_FISHEYE",
        10 => "THIN_PRISM_FISHEYE",
        _ => return None,
    };
    Some((name, parameter_count(name)?))
}

fn intrinsics(what: &str, model: &str, width: u32, height: u32, p: &[f64]) -> Result<Intrinsics> {
    Ok(Intrinsics { width, height, k: ColmapIntrinsics::from_colmap(model, p, what)? })
}

struct Bin<'a> {
    data: &'a [u8],
    pos: usize,
    what: &'a str,
}

impl Bin<'_> {
    fn take(&mut self, n: usize) -> Result<&[u8]> {
        if n > self.data.len() - self.pos {
            bail!("{}: truncated binary COLMAP file (needs {n} more bytes at offset {})", self.what, self.pos);
        }
        let s = &self.data[self.pos..self.pos + n];
        self.pos += n;
        Ok(s)
    }
    fn u64(&mut self) -> Result<u64> {
        Ok(u64::from_le_bytes(self.take(8)?.try_into().unwrap()))
    }
    fn i32(&mut self) -> Result<i32> {
        Ok(i32::from_le_bytes(self.take(4)?.try_into().unwrap()))
    }
    fn f64(&mut self) -> Result<f64> {
        Ok(f64::from_le_bytes(self.take(8)?.try_into().unwrap()))
    }
    /// A count read from the file: a claim, checked against the bytes left (each item takes at
    /// least `min_item_bytes`) before anything is sized by it.
    fn count(&mut self, min_item_bytes: usize) -> Result<usize> {
        let n = self.u64()?;
        let left = (self.data.len() - self.pos) as u64;
        if n > left / min_item_bytes as u64 {
            bail!(
                "{}: claims {n} entries at offset {} but only {left} bytes follow (truncated or corrupt)",
                self.what,
                self.pos - 8
            );
        }
        Ok(n as usize)
    }
    fn string(&mut self) -> Result<String> {
        let start = self.pos;
        while self.take(1)?[0] != 0 {}
        Ok(String::from_utf8_lossy(&self.data[start..self.pos - 1]).into_owned())
    }
}

fn read_bytes(path: &Path) -> Result<Vec<u8>> {
    let mut v = Vec::new();
    std::fs::File::open(path)
        .and_then(|mut f| f.read_to_end(&mut v))
        .with_context(|| format!("{}: cannot read", path.display()))?;
    Ok(v)
}

fn text<'a>(data: &'a [u8], what: &str) -> Result<&'a str> {
    std::str::from_utf8(data).map_err(|e| anyhow!("{what}: not UTF-8 text ({e})"))
}

/// The width or height of a camera as stored (u64 in binary models), checked against the largest
/// image cogeo handles.
fn image_side(v: u64, what: &str) -> Result<u32> {
    if v == 0 || v > super::camera::MAX_IMAGE_SIDE as u64 {
        bail!("{what}: camera width/height {v} outside 1..={}", super::camera::MAX_IMAGE_SIDE);
    }
    Ok(v as u32)
}

/// One COLMAP model file's bytes, whether it is the text (`.txt`) or binary (`.bin`) variant, and
/// its name for errors.
pub struct ModelFile<'a> {
    pub data: &'a [u8],
    pub text: bool,
    pub what: &'a str,
}

fn parse_cameras(f: &ModelFile) -> Result<HashMap<i64, Intrinsics>> {
    let what = f.what;
    let mut out = HashMap::new();
    if f.text {
        for (ln, line) in text(f.data, what)?.lines().enumerate() {
            let line = line.trim();
            if line.is_empty() || line.starts_with('#') {
                continue;
            }
            let w: Vec<&str> = line.split_whitespace().collect();
            if w.len() < 4 {
                bail!("{what}:{}: expected CAMERA_ID MODEL WIDTH HEIGHT PARAMS[]", ln + 1);
            }
            let at = format!("{what}:{}", ln + 1);
            let parse_err = || anyhow!("{at}: unparsable camera line");
            let id: i64 = w[0].parse().map_err(|_| parse_err())?;
            let width = image_side(w[2].parse().map_err(|_| parse_err())?, &at)?;
            let height = image_side(w[3].parse().map_err(|_| parse_err())?, &at)?;
            let params: Vec<f64> =
                w[4..].iter().map(|s| s.parse()).collect::<Result<_, _>>().map_err(|_| parse_err())?;
            if out.insert(id, intrinsics(&at, w[1], width, height, &params)?).is_some() {
                bail!("{at}: camera id {id} appears twice");
            }
        }
    } else {
        let mut b = Bin { data: f.data, pos: 0, what };
        let n = b.count(24)?;
        for _ in 0..n {
            let id = b.i32()? as i64;
            let model_id = b.i32()?;
            let (model, np) =
                model_info(model_id).ok_or_else(|| anyhow!("{what}: unknown camera model id {model_id}"))?;
            let width = image_side(b.u64()?, what)?;
            let height = image_side(b.u64()?, what)?;
            let params: Vec<f64> = (0..np).map(|_| b.f64()).collect::<Result<_>>()?;
            if out.insert(id, intrinsics(what, model, width, height, &params)?).is_some() {
                bail!("{what}: camera id {id} appears twice");
            }
        }
    }
    if out.is_empty() {
        bail!("{what}: the COLMAP model has no cameras");
    }
    Ok(out)
}

struct ImageEntry {
    name: String,
    qvec: [f64; 4],
    tvec: [f64; 3],
    camera_id: i64,
}

fn parse_images(f: &ModelFile) -> Result<Vec<ImageEntry>> {
    let what = f.what;
    let mut out = Vec::new();
    if f.text {
        // Two lines per image; the second (points) may be empty, so count non-comment lines strictly.
        let lines: Vec<(usize, &str)> =
            text(f.data, what)?.lines().enumerate().filter(|(_, l)| !l.starts_with('#')).collect();
        let mut i = 0;
        while i < lines.len() {
            let (ln, line) = lines[i];
            if line.trim().is_empty() {
                i += 1;
                continue;
            }
            let w: Vec<&str> = line.split_whitespace().collect();
            if w.len() < 10 {
                bail!("{what}:{}: expected IMAGE_ID QW QX QY QZ TX TY TZ CAMERA_ID NAME", ln + 1);
            }
            let f = |s: &str| s.parse::<f64>().map_err(|_| anyhow!("{what}:{}: unparsable number {s:?}", ln + 1));
            out.push(ImageEntry {
                qvec: [f(w[1])?, f(w[2])?, f(w[3])?, f(w[4])?],
                tvec: [f(w[5])?, f(w[6])?, f(w[7])?],
                camera_id: w[8].parse().map_err(|_| anyhow!("{what}:{}: bad camera id", ln + 1))?,
                name: w[9..].join(" "),
            });
            i += 2; // skip the points line
        }
    } else {
        let mut b = Bin { data: f.data, pos: 0, what };
        let n = b.count(64)?;
        for _ in 0..n {
            let _id = b.i32()?;
            let qvec = [b.f64()?, b.f64()?, b.f64()?, b.f64()?];
            let tvec = [b.f64()?, b.f64()?, b.f64()?];
            let camera_id = b.i32()? as i64;
            let name = b.string()?;
            let np = b.count(24)?;
            b.take(np * 24)?;
            out.push(ImageEntry { name, qvec, tvec, camera_id });
        }
    }
    Ok(out)
}

fn parse_points(f: &ModelFile) -> Result<Vec<Point3D>> {
    let what = f.what;
    let mut out = Vec::new();
    if f.text {
        for (ln, line) in text(f.data, what)?.lines().enumerate() {
            let line = line.trim();
            if line.is_empty() || line.starts_with('#') {
                continue;
            }
            let w: Vec<&str> = line.split_whitespace().collect();
            if w.len() < 7 {
                bail!("{what}:{}: expected POINT3D_ID X Y Z R G B ...", ln + 1);
            }
            let err = || anyhow!("{what}:{}: unparsable point", ln + 1);
            let f = |s: &str| s.parse::<f64>().ok().filter(|v| v.is_finite()).ok_or_else(err);
            let u = |s: &str| s.parse::<u8>().map_err(|_| err());
            out.push(Point3D { xyz: [f(w[1])?, f(w[2])?, f(w[3])?], rgb: [u(w[4])?, u(w[5])?, u(w[6])?] });
        }
    } else {
        let mut b = Bin { data: f.data, pos: 0, what };
        let n = b.count(43)?;
        for i in 0..n {
            b.u64()?;
            let xyz = [b.f64()?, b.f64()?, b.f64()?];
            if !xyz.iter().all(|v| v.is_finite()) {
                bail!("{what}: point {i} has a NaN or infinite coordinate");
            }
            let c = b.take(3)?;
            let rgb = [c[0], c[1], c[2]];
            b.f64()?;
            let track = b.count(8)?;
            b.take(track * 8)?;
            out.push(Point3D { xyz, rgb });
        }
    }
    Ok(out)
}

/// Reads `<stem>.txt` (preferred) or `<stem>.bin` from `dir`; None when neither exists.
fn read_model_file(dir: &Path, stem: &str) -> Result<Option<(Vec<u8>, bool, String)>> {
    for (ext, text) in [("txt", true), ("bin", false)] {
        let path = dir.join(format!("{stem}.{ext}"));
        if path.exists() {
            return Ok(Some((read_bytes(&path)?, text, path.display().to_string())));
        }
    }
    Ok(None)
}

/// Loads a COLMAP model from `dir` (or `dir/sparse/0`). Cameras come sorted by image name; their
/// names drop the file extension.
pub fn read_colmap(dir: &Path) -> Result<ColmapModel> {
    let model_dir = find_model_dir(dir)?;
    let missing = |stem: &str| anyhow!("{}: no {stem}.txt or {stem}.bin", model_dir.display());
    let cameras = read_model_file(&model_dir, "cameras")?.ok_or_else(|| missing("cameras"))?;
    let images = read_model_file(&model_dir, "images")?.ok_or_else(|| missing("images"))?;
    let points = read_model_file(&model_dir, "points3D")?;
    fn file(f: &(Vec<u8>, bool, String)) -> ModelFile<'_> {
        ModelFile { data: &f.0, text: f.1, what: &f.2 }
    }
    parse_colmap(&file(&cameras), &file(&images), points.as_ref().map(file).as_ref(), &model_dir.display().to_string())
}

/// Builds a model from the bytes of its files (`what` names the model in errors): the reader of
/// `read_colmap`, on memory so that it can be fuzzed.
pub fn parse_colmap(
    cameras: &ModelFile,
    images: &ModelFile,
    points: Option<&ModelFile>,
    what: &str,
) -> Result<ColmapModel> {
    let intrinsics = parse_cameras(cameras)?;
    let mut images = parse_images(images)?;
    if images.is_empty() {
        bail!("{what}: the COLMAP model has no images");
    }
    images.sort_by(|a, b| a.name.cmp(&b.name));
    if let Some(w) = images.windows(2).find(|w| w[0].name == w[1].name) {
        bail!("{what}: image {:?} appears twice", w[0].name);
    }
    let (cameras, lenses): (Vec<Camera>, Vec<Lens>) = images
        .iter()
        .map(|im| {
            let k = intrinsics
                .get(&im.camera_id)
                .ok_or_else(|| anyhow!("{what}: image {:?} refers to missing camera {}", im.name, im.camera_id))?;
            let stem = Path::new(&im.name).file_stem().map(|s| s.to_string_lossy().into_owned()).unwrap_or_default();
            let camera = Camera {
                name: stem,
                width: k.width,
                height: k.height,
                fx: k.k.fx,
                fy: k.k.fy,
                cx: k.k.cx,
                cy: k.k.cy,
                rotation: rotation_from_qvec(im.qvec),
                translation: im.tvec,
                whole_view: None,
            };
            camera.check(&format!("{what}: image {:?}", im.name))?;
            Ok((camera, k.k.lens))
        })
        .collect::<Result<Vec<_>>>()?
        .into_iter()
        .unzip();
    let points = points.map(parse_points).transpose()?.unwrap_or_default();
    Ok(ColmapModel { cameras, lenses, points, warnings: Vec::new() })
}
