//! COLMAP sparse models (`cameras`, `images`, `points3D`; `.bin` or `.txt`).

use super::camera::{rotation_from_qvec, Camera};
use anyhow::{anyhow, bail, Context, Result};
use std::collections::HashMap;
use std::io::Read;
use std::path::{Path, PathBuf};

/// Intrinsics of one COLMAP camera, reduced to a pinhole.
#[derive(Clone, Debug)]
struct Intrinsics {
    width: u32,
    height: u32,
    fx: f64,
    fy: f64,
    cx: f64,
    cy: f64,
}

/// A sparse point (for initializing training).
#[derive(Clone, Debug)]
pub struct Point3D {
    pub xyz: [f64; 3],
    pub rgb: [u8; 3],
}

/// A loaded COLMAP model: cameras sorted by image name, and the sparse points.
pub struct ColmapModel {
    pub cameras: Vec<Camera>,
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

/// Number of parameters of a COLMAP camera model id, and its name.
fn model_info(id: i32) -> Option<(&'static str, usize)> {
    Some(match id {
        0 => ("SIMPLE_PINHOLE", 3),
        1 => ("PINHOLE", 4),
        2 => ("SIMPLE_RADIAL", 4),
        3 => ("RADIAL", 5),
        4 => ("OPENCV", 8),
        5 => ("OPENCV_FISHEYE", 8),
        6 => ("FULL_OPENCV", 12),
        7 => ("FOV", 5),
        8 => ("SIMPLE_RADIAL_FISHEYE", 4),
        9 => ("RADIAL_FISHEYE", 5),
        10 => ("THIN_PRISM_FISHEYE", 12),
        _ => return None,
    })
}

fn to_pinhole(
    what: &str,
    model: &str,
    width: u32,
    height: u32,
    p: &[f64],
    warnings: &mut Vec<String>,
) -> Result<Intrinsics> {
    let (fx, fy, cx, cy) = match model {
        "SIMPLE_PINHOLE" | "SIMPLE_RADIAL" | "RADIAL" if p.len() >= 3 => (p[0], p[0], p[1], p[2]),
        "PINHOLE" | "OPENCV" | "FULL_OPENCV" if p.len() >= 4 => (p[0], p[1], p[2], p[3]),
        "SIMPLE_PINHOLE" | "SIMPLE_RADIAL" | "RADIAL" | "PINHOLE" | "OPENCV" | "FULL_OPENCV" => {
            bail!("{what}: camera model {model} with too few parameters ({})", p.len())
        }
        _ => bail!(
            "{what}: unknown or unsupported camera model {model:?} (supported: PINHOLE, SIMPLE_PINHOLE; \
             SIMPLE_RADIAL, RADIAL, OPENCV, FULL_OPENCV with distortion ignored)"
        ),
    };
    if !matches!(model, "PINHOLE" | "SIMPLE_PINHOLE") {
        let w = format!("{what}: camera model {model}: distortion is ignored; undistort the images for best results");
        if !warnings.contains(&w) {
            warnings.push(w);
        }
    }
    if width == 0 || height == 0 || !(fx > 0.0 && fy > 0.0) {
        bail!("{what}: camera with invalid size {width}x{height} or focal length");
    }
    Ok(Intrinsics { width, height, fx, fy, cx, cy })
}

struct Bin<'a> {
    data: &'a [u8],
    pos: usize,
    what: &'a str,
}

impl Bin<'_> {
    fn take(&mut self, n: usize) -> Result<&[u8]> {
        if self.pos + n > self.data.len() {
            bail!("{}: truncated binary COLMAP file", self.what);
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

fn read_cameras(dir: &Path, warnings: &mut Vec<String>) -> Result<HashMap<i64, Intrinsics>> {
    let mut out = HashMap::new();
    let txt = dir.join("cameras.txt");
    if txt.exists() {
        let what = txt.display().to_string();
        let text = std::fs::read_to_string(&txt).with_context(|| format!("{what}: cannot read"))?;
        for (ln, line) in text.lines().enumerate() {
            let line = line.trim();
            if line.is_empty() || line.starts_with('#') {
                continue;
            }
            let w: Vec<&str> = line.split_whitespace().collect();
            if w.len() < 4 {
                bail!("{what}:{}: expected CAMERA_ID MODEL WIDTH HEIGHT PARAMS[]", ln + 1);
            }
            let parse_err = || anyhow!("{what}:{}: unparsable camera line", ln + 1);
            let id: i64 = w[0].parse().map_err(|_| parse_err())?;
            let width: u32 = w[2].parse().map_err(|_| parse_err())?;
            let height: u32 = w[3].parse().map_err(|_| parse_err())?;
            let params: Vec<f64> =
                w[4..].iter().map(|s| s.parse()).collect::<Result<_, _>>().map_err(|_| parse_err())?;
            out.insert(id, to_pinhole(&format!("{what}:{}", ln + 1), w[1], width, height, &params, warnings)?);
        }
    } else {
        let path = dir.join("cameras.bin");
        let what = path.display().to_string();
        let data = read_bytes(&path)?;
        let mut b = Bin { data: &data, pos: 0, what: &what };
        let n = b.u64()?;
        for _ in 0..n {
            let id = b.i32()? as i64;
            let model_id = b.i32()?;
            let (model, np) =
                model_info(model_id).ok_or_else(|| anyhow!("{what}: unknown camera model id {model_id}"))?;
            let width = b.u64()? as u32;
            let height = b.u64()? as u32;
            let params: Vec<f64> = (0..np).map(|_| b.f64()).collect::<Result<_>>()?;
            out.insert(id, to_pinhole(&what, model, width, height, &params, warnings)?);
        }
    }
    if out.is_empty() {
        bail!("{}: the COLMAP model has no cameras", dir.display());
    }
    Ok(out)
}

struct ImageEntry {
    name: String,
    qvec: [f64; 4],
    tvec: [f64; 3],
    camera_id: i64,
}

fn read_images(dir: &Path) -> Result<Vec<ImageEntry>> {
    let mut out = Vec::new();
    let txt = dir.join("images.txt");
    if txt.exists() {
        let what = txt.display().to_string();
        let text = std::fs::read_to_string(&txt).with_context(|| format!("{what}: cannot read"))?;
        // Two lines per image; the second (points) may be empty, so count non-comment lines strictly.
        let lines: Vec<(usize, &str)> = text.lines().enumerate().filter(|(_, l)| !l.starts_with('#')).collect();
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
        let path = dir.join("images.bin");
        let what = path.display().to_string();
        let data = read_bytes(&path)?;
        let mut b = Bin { data: &data, pos: 0, what: &what };
        let n = b.u64()?;
        for _ in 0..n {
            let _id = b.i32()?;
            let qvec = [b.f64()?, b.f64()?, b.f64()?, b.f64()?];
            let tvec = [b.f64()?, b.f64()?, b.f64()?];
            let camera_id = b.i32()? as i64;
            let name = b.string()?;
            let np = b.u64()? as usize;
            b.take(np * 24)?;
            out.push(ImageEntry { name, qvec, tvec, camera_id });
        }
    }
    Ok(out)
}

fn read_points(dir: &Path) -> Result<Vec<Point3D>> {
    let txt = dir.join("points3D.txt");
    let bin = dir.join("points3D.bin");
    let mut out = Vec::new();
    if txt.exists() {
        let what = txt.display().to_string();
        let text = std::fs::read_to_string(&txt).with_context(|| format!("{what}: cannot read"))?;
        for (ln, line) in text.lines().enumerate() {
            let line = line.trim();
            if line.is_empty() || line.starts_with('#') {
                continue;
            }
            let w: Vec<&str> = line.split_whitespace().collect();
            if w.len() < 7 {
                bail!("{what}:{}: expected POINT3D_ID X Y Z R G B ...", ln + 1);
            }
            let err = || anyhow!("{what}:{}: unparsable point", ln + 1);
            let f = |s: &str| s.parse::<f64>().map_err(|_| err());
            let u = |s: &str| s.parse::<u8>().map_err(|_| err());
            out.push(Point3D { xyz: [f(w[1])?, f(w[2])?, f(w[3])?], rgb: [u(w[4])?, u(w[5])?, u(w[6])?] });
        }
    } else if bin.exists() {
        let what = bin.display().to_string();
        let data = read_bytes(&bin)?;
        let mut b = Bin { data: &data, pos: 0, what: &what };
        let n = b.u64()?;
        for _ in 0..n {
            b.u64()?;
            let xyz = [b.f64()?, b.f64()?, b.f64()?];
            let c = b.take(3)?;
            let rgb = [c[0], c[1], c[2]];
            b.f64()?;
            let track = b.u64()? as usize;
            b.take(track * 8)?;
            out.push(Point3D { xyz, rgb });
        }
    }
    Ok(out)
}

/// Loads a COLMAP model from `dir` (or `dir/sparse/0`). Cameras come sorted by image name; their
/// names drop the file extension.
pub fn read_colmap(dir: &Path) -> Result<ColmapModel> {
    let model_dir = find_model_dir(dir)?;
    let mut warnings = Vec::new();
    let intrinsics = read_cameras(&model_dir, &mut warnings)?;
    let mut images = read_images(&model_dir)?;
    if images.is_empty() {
        bail!("{}: the COLMAP model has no images", model_dir.display());
    }
    images.sort_by(|a, b| a.name.cmp(&b.name));
    let cameras = images
        .iter()
        .map(|im| {
            let k = intrinsics.get(&im.camera_id).ok_or_else(|| {
                anyhow!("{}: image {:?} refers to missing camera {}", model_dir.display(), im.name, im.camera_id)
            })?;
            let stem = Path::new(&im.name).file_stem().map(|s| s.to_string_lossy().into_owned()).unwrap_or_default();
            Ok(Camera {
                name: stem,
                width: k.width,
                height: k.height,
                fx: k.fx,
                fy: k.fy,
                cx: k.cx,
                cy: k.cy,
                rotation: rotation_from_qvec(im.qvec),
                translation: im.tvec,
            })
        })
        .collect::<Result<Vec<_>>>()?;
    let points = read_points(&model_dir)?;
    Ok(ColmapModel { cameras, points, warnings })
}
