//! Training data: a COLMAP model (or a transforms.json, scene/transforms.rs) plus an image folder
//! (`images`, or a Mip-NeRF 360 style `images_2`, `images_4`, ... holding downscaled copies:
//! intrinsics are scaled to the actual image size), with the Mip-NeRF 360 split (every 8th view,
//! 0, 8, 16, ..., held out for testing). Photos taken through a lens are undistorted into pinhole
//! cameras first (scene/undistort.rs). A `downscale` factor N then box-filters every image by N x N
//! pixels (as `-r N` in the INRIA code), so a capture can be trained, tagged and edited at a lower
//! resolution without writing a copy of it.

use crate::image_ops::resize_nearest_u8;
use crate::scene::colmap::{find_model_dir, read_colmap, ColmapModel, Point3D};
use crate::scene::pose_check::{check_rotations, with_transposed_rotation, RotationCheck};
use crate::scene::transforms;
use crate::scene::undistort::Undistortion;
use crate::scene::Camera;
use anyhow::{bail, Context, Result};
use std::path::{Path, PathBuf};
use std::sync::Arc;

pub struct View {
    /// A pinhole camera: with a lens, the undistorted one.
    pub camera: Camera,
    /// Planar RGB in [0, 1], width * height per plane.
    pub image: Vec<f32>,
    pub path: PathBuf,
    /// How the photo (and so every mask drawn on it) was resampled into `camera`'s frame, for a
    /// camera with a lens (then `camera.width` x `height` may also be smaller, by --downscale).
    pub undistortion: Option<Arc<Undistortion>>,
}

impl View {
    /// A label map drawn on this view's stored photo (any size: nearest-resized), in the view's
    /// own frame: undistorted and at the camera's size.
    pub fn label_map(&self, stored: &[u8], w: u32, h: u32) -> Vec<u8> {
        let (cw, ch) = (self.camera.width, self.camera.height);
        match &self.undistortion {
            None => resize_nearest_u8(stored, w, h, cw, ch),
            Some(u) => {
                let (sw, sh) = u.source;
                let undistorted = u.labels(&resize_nearest_u8(stored, w, h, sw, sh));
                resize_nearest_u8(&undistorted, u.pinhole.width, u.pinhole.height, cw, ch)
            }
        }
    }
}

pub struct Dataset {
    pub train: Vec<View>,
    pub test: Vec<View>,
    pub points: Vec<Point3D>,
    /// Radius of the camera centers around their mean, times 1.1 (INRIA's scene extent).
    pub extent: f64,
    pub warnings: Vec<String>,
    /// The poses measured against the images (scene/pose_check.rs), when points carry colors.
    pub pose_check: Option<RotationCheck>,
}

const IMAGE_EXTENSIONS: [&str; 5] = ["png", "jpg", "jpeg", "PNG", "JPG"];

/// The image folder inside a capture that every command reads unless told another.
pub const DEFAULT_IMAGE_FOLDER: &str = "images";

/// The cameras and points of a capture folder: a COLMAP model (`dir`, `dir/sparse/0`), else a
/// nerfstudio / instant-ngp `transforms.json` (scene/transforms.rs).
pub fn read_capture(dir: &Path) -> Result<ColmapModel> {
    if find_model_dir(dir).is_ok() {
        return read_colmap(dir);
    }
    if dir.join(transforms::FILE_NAME).is_file() {
        return transforms::read_transforms(dir);
    }
    bail!("{}: no COLMAP model (cameras.bin/.txt here or in sparse/0) and no {}", dir.display(), transforms::FILE_NAME)
}

/// Finds `stem.<ext>` in `dir`.
pub fn find_image(dir: &Path, stem: &str) -> Option<PathBuf> {
    IMAGE_EXTENSIONS.iter().map(|e| dir.join(format!("{stem}.{e}"))).find(|p| p.exists())
}

/// Loads an image as planar RGB floats in [0, 1].
pub fn load_rgb(path: &Path) -> Result<(u32, u32, Vec<f32>)> {
    let img = crate::io::read_image(path)?.to_rgb8();
    let (w, h) = img.dimensions();
    let hw = (w * h) as usize;
    let mut out = vec![0f32; 3 * hw];
    for (i, p) in img.pixels().enumerate() {
        for c in 0..3 {
            out[c * hw + i] = p[c] as f32 / 255.0;
        }
    }
    Ok((w, h, out))
}

/// Is view `index` (in name order) a held-out test view?
pub fn is_test_view(index: usize) -> bool {
    index.is_multiple_of(8)
}

/// Checks the model's poses against up to 8 of its images in `image_dir` (scene/pose_check.rs).
/// Rotations stored transposed (camera-to-world quaternions beside world-to-camera translations)
/// are transposed back, with a warning; poses that agree with the images under neither reading
/// get a warning. Returns the measurement (None: no images or no colored points to compare).
pub fn repair_rotations(model: &mut ColmapModel, dir: &Path, image_dir: &Path) -> Result<Option<RotationCheck>> {
    let n = model.cameras.len();
    let picks: Vec<usize> = (0..n.min(8)).map(|k| k * n / n.min(8)).collect();
    let (mut cams, mut images) = (Vec::new(), Vec::new());
    for &i in &picks {
        let cam = &model.cameras[i];
        let Some(path) = find_image(image_dir, &cam.name) else { continue };
        let (w, h, rgb) = load_rgb(&path)?;
        cams.push(cam.resized(w, h));
        images.push(rgb);
    }
    let Some(check) = check_rotations(&cams, &images, &model.points, 4000) else { return Ok(None) };
    if check.transposed_rotations() {
        for c in &mut model.cameras {
            *c = with_transposed_rotation(c);
        }
        model.warnings.push(format!(
            "{}: the COLMAP rotations disagree with the images (sparse point colors off by {:.3} on average, \
             {:.3} against unrelated pixels) while their transposes agree ({:.3}): the quaternions look like \
             camera-to-world rotations written beside world-to-camera translations; using the transposed rotations",
            dir.display(),
            check.stored,
            check.chance,
            check.transposed
        ));
    } else if check.disagrees() {
        model.warnings.push(format!(
            "{}: the sparse points' colors do not match the images under these poses (off by {:.3} on average, \
             {:.3} against unrelated pixels); training will blur if the poses are wrong",
            dir.display(),
            check.stored,
            check.chance
        ));
    }
    Ok(Some(check))
}

/// Averages each `n` x `n` block of a planar RGB image (`w` x `h`); a partial block at the right or
/// bottom edge is dropped, so output pixel (x, y) covers input pixels [n x, n x + n) x [n y, n y + n).
pub fn box_downscale(w: u32, h: u32, rgb: &[f32], n: u32) -> (u32, u32, Vec<f32>) {
    let (ow, oh) = (w / n, h / n);
    let (w, h, n, ow, oh) = (w as usize, h as usize, n as usize, ow as usize, oh as usize);
    let mut out = vec![0f32; 3 * ow * oh];
    let norm = 1.0 / (n * n) as f64;
    for c in 0..3 {
        let plane = &rgb[c * w * h..(c + 1) * w * h];
        for y in 0..oh {
            for x in 0..ow {
                let mut sum = 0.0f64;
                for sy in 0..n {
                    let row = &plane[(y * n + sy) * w + x * n..][..n];
                    sum += row.iter().map(|&v| v as f64).sum::<f64>();
                }
                out[c * ow * oh + y * ow + x] = (sum * norm) as f32;
            }
        }
    }
    (ow as u32, oh as u32, out)
}

/// Loads `dir` (COLMAP model in `dir` or `dir/sparse/0`) with images from `dir/<images>`, each
/// box-filtered by `downscale` (1 = as stored); intrinsics follow the images.
pub fn load(dir: &Path, images: &str, downscale: u32) -> Result<Dataset> {
    if downscale == 0 {
        bail!("the downscale factor must be at least 1");
    }
    let mut model = read_capture(dir)?;
    let image_dir = dir.join(images);
    if !image_dir.is_dir() {
        bail!("{}: image folder not found", image_dir.display());
    }
    let pose_check = repair_rotations(&mut model, dir, &image_dir)?;
    let mut train = Vec::new();
    let mut test = Vec::new();
    for (i, (cam, lens)) in model.cameras.iter().zip(&model.lenses).enumerate() {
        let path = find_image(&image_dir, &cam.name).with_context(|| {
            format!("{}: no image named {}.png/.jpg for a COLMAP view", image_dir.display(), cam.name)
        })?;
        let (w, h, rgb) = load_rgb(&path)?;
        // downscaled folders: scale the intrinsics to the image actually loaded
        let camera = if (w, h) != (cam.width, cam.height) {
            let (sx, sy) = (w as f64 / cam.width as f64, h as f64 / cam.height as f64);
            if (sx / sy - 1.0).abs() > 0.02 {
                bail!(
                    "{}: {w}x{h} does not match the aspect of the COLMAP camera {}x{}",
                    path.display(),
                    cam.width,
                    cam.height
                );
            }
            cam.resized(w, h)
        } else {
            cam.clone()
        };
        // a lens: the photo resampled once into a pinhole camera of its size (scene/undistort.rs)
        let (camera, rgb, undistortion) = if lens.is_pinhole() {
            (camera, rgb, None)
        } else {
            let u = Undistortion::new(&camera, *lens, &path.display().to_string())?;
            (u.pinhole.clone(), u.rgb(&rgb), Some(Arc::new(u)))
        };
        let (camera, rgb) = if downscale > 1 {
            let (w, h) = (camera.width, camera.height);
            let (dw, dh, small) = box_downscale(w, h, &rgb, downscale);
            if dw < 8 || dh < 8 {
                bail!("{}: {w}x{h} downscaled by {downscale} leaves {dw}x{dh} pixels", path.display());
            }
            // pixel x of the small image spans x * n .. x * n + n of the loaded one: intrinsics / n
            let n = downscale as f64;
            let c = Camera {
                width: dw,
                height: dh,
                fx: camera.fx / n,
                fy: camera.fy / n,
                cx: camera.cx / n,
                cy: camera.cy / n,
                ..camera
            };
            (c, small)
        } else {
            (camera, rgb)
        };
        let view = View { camera, image: rgb, path, undistortion };
        if is_test_view(i) {
            test.push(view);
        } else {
            train.push(view);
        }
    }
    if train.is_empty() {
        bail!("{}: no training views", dir.display());
    }
    let centers: Vec<[f64; 3]> = train.iter().chain(&test).map(|v| v.camera.center()).collect();
    let mean = (0..3).map(|a| centers.iter().map(|c| c[a]).sum::<f64>() / centers.len() as f64).collect::<Vec<_>>();
    let radius = centers
        .iter()
        .map(|c| ((c[0] - mean[0]).powi(2) + (c[1] - mean[1]).powi(2) + (c[2] - mean[2]).powi(2)).sqrt())
        .fold(0.0, f64::max);
    Ok(Dataset {
        train,
        test,
        points: model.points,
        extent: (radius * 1.1).max(1e-3),
        warnings: model.warnings,
        pose_check,
    })
}
