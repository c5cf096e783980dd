//! Undistortion on load: a photo taken through a lens (scene/lens.rs) is resampled once into a
//! pinhole camera, so every later stage (training, tagging, the removal's color transfer between
//! views) sees straight lines straight and one surface point at the same ray in every view.
//!
//! The pinhole is chosen as COLMAP's undistorter does by default: the same focal lengths (so the
//! image center keeps its scale and is only shifted, not resampled to another size), and the
//! largest axis-aligned rectangle of the image plane that the photo saw everywhere (no black
//! borders), which makes the image a little smaller than the photo. The rectangle's edges are the
//! innermost points of the photo's four edges after undistortion, shrunk until every border pixel
//! of the pinhole image reads inside the photo. Photos are read with Lanczos-3 (sharp; the
//! resampling happens once), label maps with the nearest pixel.

use super::camera::Camera;
use super::lens::{ColmapIntrinsics, Lens};
use crate::image_ops::sample_lanczos3_rgb;
use anyhow::{bail, Result};

/// How one photo becomes its pinhole image. Small: the per-pixel source positions are recomputed
/// (closed form, the forward lens model) each time an image is resampled, so a loaded capture
/// does not hold a map per view.
#[derive(Clone, Debug)]
pub struct Undistortion {
    /// The photo's size.
    pub source: (u32, u32),
    /// The photo's intrinsics and lens.
    pub lens: ColmapIntrinsics,
    /// The pinhole camera of the undistorted image (the photo's pose and name).
    pub pinhole: Camera,
}

impl Undistortion {
    /// The undistortion of the photo of `distorted` (its pose, name, size and intrinsics) taken
    /// through `lens`; `what` names it in errors.
    pub fn new(distorted: &Camera, lens: Lens, what: &str) -> Result<Undistortion> {
        let source = (distorted.width, distorted.height);
        Ok(Undistortion { source, lens: intrinsics(distorted, lens), pinhole: pinhole_camera(distorted, lens, what)? })
    }

    /// The alternative to COLMAP's choice for the same photo: a pinhole image holding the whole
    /// photo (the smallest rectangle around every ray it saw, so its corners lie beyond the photo),
    /// to be trained with `valid_mask` as loss weights. `tests/undistort.rs` measures it against
    /// the cropped frame; the loader keeps the crop (no stage after training would need a mask).
    pub fn whole_frame(&self, what: &str) -> Result<Undistortion> {
        let k = self.lens;
        let (width, height) = self.source;
        let (w, h) = (width as f64, height as f64);
        let border = (0..=width)
            .flat_map(|i| [(i as f64, 0.0), (i as f64, h)])
            .chain((0..=height).flat_map(|i| [(0.0, i as f64), (w, i as f64)]));
        let (mut left, mut right, mut top, mut bottom) =
            (f64::INFINITY, f64::NEG_INFINITY, f64::INFINITY, f64::NEG_INFINITY);
        for (x, y) in border {
            let Some((u, v)) = k.unproject(x, y) else {
                bail!("{what}: the lens model cannot be inverted along the image border")
            };
            (left, right, top, bottom) = (left.min(u), right.max(u), top.min(v), bottom.max(v));
        }
        let (fx, fy) = (k.fx, k.fy);
        let (pw, ph) = (((right - left) * fx).ceil() as u32, ((bottom - top) * fy).ceil() as u32);
        let pinhole = Camera { width: pw, height: ph, fx, fy, cx: -left * fx, cy: -top * fy, ..self.pinhole.clone() };
        Ok(Undistortion { source: self.source, lens: k, pinhole })
    }

    /// 1 where a pinhole pixel's ray lands inside the photo, 0 where the photo did not see it.
    pub fn valid_mask(&self) -> Vec<f32> {
        let (w, h) = (self.source.0 as f64, self.source.1 as f64);
        (0..self.pixels())
            .map(|i| {
                let (x, y) = self.source_position(i);
                if (0.0..=w).contains(&x) && (0.0..=h).contains(&y) {
                    1.0
                } else {
                    0.0
                }
            })
            .collect()
    }

    /// Where the ray of pinhole pixel `i` (row-major) lands in the photo (pixel centers at +0.5).
    fn source_position(&self, i: usize) -> (f64, f64) {
        let p = &self.pinhole;
        let w = p.width as usize;
        let (px, py) = ((i % w) as f64 + 0.5, (i / w) as f64 + 0.5);
        self.lens.project((px - p.cx) / p.fx, (py - p.cy) / p.fy)
    }

    fn pixels(&self) -> usize {
        self.pinhole.width as usize * self.pinhole.height as usize
    }

    /// The photo (planar RGB at the source size) resampled into the pinhole image.
    pub fn rgb(&self, photo: &[f32]) -> Vec<f32> {
        let (w, h) = (self.source.0 as usize, self.source.1 as usize);
        let n = self.pixels();
        let mut out = vec![0f32; 3 * n];
        for i in 0..n {
            let (x, y) = self.source_position(i);
            for (c, v) in sample_lanczos3_rgb(photo, w, h, x, y).into_iter().enumerate() {
                out[c * n + i] = v.clamp(0.0, 1.0);
            }
        }
        out
    }

    /// A label map (one byte per pixel at the source size) resampled by the nearest pixel.
    pub fn labels(&self, map: &[u8]) -> Vec<u8> {
        let (w, h) = (self.source.0 as usize, self.source.1 as usize);
        (0..self.pixels())
            .map(|i| {
                let (x, y) = self.source_position(i);
                let (x, y) = ((x.floor().max(0.0) as usize).min(w - 1), (y.floor().max(0.0) as usize).min(h - 1));
                map[y * w + x]
            })
            .collect()
    }
}

/// The photo's intrinsics: `camera`'s focal lengths and principal point with `lens`.
fn intrinsics(camera: &Camera, lens: Lens) -> ColmapIntrinsics {
    ColmapIntrinsics { fx: camera.fx, fy: camera.fy, cx: camera.cx, cy: camera.cy, lens }
}

/// `distorted`, a camera with lens `lens`, as the pinhole camera its photos are undistorted into.
pub fn pinhole_camera(distorted: &Camera, lens: Lens, what: &str) -> Result<Camera> {
    if lens.is_pinhole() {
        return Ok(distorted.clone());
    }
    let k = intrinsics(distorted, lens);
    let (width, height) = (distorted.width, distorted.height);
    let (w, h) = (width as f64, height as f64);
    let edge = |n: u32| (0..=n).map(move |i| i as f64);
    let ray = |x: f64, y: f64| k.unproject(x, y);
    let inner = |pts: Vec<Option<(f64, f64)>>, pick: fn((f64, f64)) -> f64, max: bool| {
        let vals = pts.into_iter().flatten().map(pick);
        if max {
            vals.fold(f64::NEG_INFINITY, f64::max)
        } else {
            vals.fold(f64::INFINITY, f64::min)
        }
    };
    let mut left = inner(edge(height).map(|y| ray(0.0, y)).collect(), |p| p.0, true);
    let mut right = inner(edge(height).map(|y| ray(w, y)).collect(), |p| p.0, false);
    let mut top = inner(edge(width).map(|x| ray(x, 0.0)).collect(), |p| p.1, true);
    let mut bottom = inner(edge(width).map(|x| ray(x, h)).collect(), |p| p.1, false);
    if !(left.is_finite() && right.is_finite() && top.is_finite() && bottom.is_finite())
        || left >= right
        || top >= bottom
    {
        bail!("{what}: the lens model cannot be inverted along the image border");
    }
    // shrink about the rectangle's center until its whole border reads inside the photo
    let inside = |u: f64, v: f64| {
        let (x, y) = k.project(u, v);
        (0.0..=w).contains(&x) && (0.0..=h).contains(&y)
    };
    for attempt in 0.. {
        let border_ok = (0..=200).all(|i| {
            let t = i as f64 / 200.0;
            let (u, v) = (left + t * (right - left), top + t * (bottom - top));
            inside(u, top) && inside(u, bottom) && inside(left, v) && inside(right, v)
        });
        if border_ok {
            break;
        }
        if attempt == 100 {
            bail!("{what}: no pinhole rectangle fits inside the photo");
        }
        let (cu, cv) = ((left + right) / 2.0, (top + bottom) / 2.0);
        (left, right) = (cu + 0.99 * (left - cu), cu + 0.99 * (right - cu));
        (top, bottom) = (cv + 0.99 * (top - cv), cv + 0.99 * (bottom - cv));
    }
    let (fx, fy) = (k.fx, k.fy);
    let pw = ((right - left) * fx).floor() as u32;
    let ph = ((bottom - top) * fy).floor() as u32;
    if pw < 8 || ph < 8 {
        bail!("{what}: the undistorted image would be {pw}x{ph} pixels");
    }
    Ok(Camera { width: pw, height: ph, fx, fy, cx: -left * fx, cy: -top * fy, ..distorted.clone() })
}
