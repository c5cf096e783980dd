//! RGB completion of one view: fill the pixels of a hole mask.
//!
//! - `Inpainter::Exemplar` (the default) needs no weights either: texture copied patch by patch
//!   from around the hole, each background surface from itself (`exemplar.rs`).
//! - `Inpainter::Harmonic` needs no weights: the harmonic (membrane) interpolant of the pixels around
//!   the hole, solved coarse to fine (`harmonic::harmonic_fill`). Deterministic; smooth rather than
//!   textured, which is what a masked PSNR rewards when nothing is known about the hole.
//! - `Inpainter::Onnx` runs a user-supplied model with the LaMa contract: inputs `image`
//!   [1, 3, 512, 512] RGB in [0, 1] and `mask` [1, 1, 512, 512] (1 = hole), one output [1, 3, 512, 512]
//!   RGB in [0, 1]. The hole's bounding box, grown by half its size (and at least 16 pixels) for
//!   context, is cropped, resized to 512 x 512, inpainted, resized back, and only the hole pixels are
//!   pasted into the view.
//! - `Inpainter::Provided` takes the user's own inpainted views (`cogeo remove --inpainted DIR`:
//!   LaMa, Stable Diffusion, an image editor, ...), one per edited view in view order, already at
//!   the view's size: their pixels are used exactly inside the hole, the render everywhere else.

use super::harmonic::harmonic_fill;
use super::surfaces::{fill_by_surface, Boundary};
use crate::image_ops::{bounding_box, crop, resize_bilinear, Rect};
use crate::onnx::{Model, Tensor};
use anyhow::{bail, Result};
use std::path::Path;

/// The built-in inpainters.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize, clap::ValueEnum)]
#[serde(rename_all = "lowercase")]
pub enum BuiltInInpainter {
    #[default]
    Exemplar,
    Harmonic,
}

/// Side of the LaMa contract's square input.
pub const LAMA_SIZE: usize = 512;

pub enum Inpainter {
    /// The harmonic fill (the smooth ablation).
    Harmonic,
    /// Exemplar texture synthesis on the GPU (exemplar.rs); the default.
    Exemplar(Box<super::exemplar::ExemplarFill>),
    Onnx(Box<Model>),
    /// Planar RGB per edited view, from `dir`.
    Provided {
        dir: std::path::PathBuf,
        views: Vec<Vec<f32>>,
    },
}

impl Inpainter {
    /// The ONNX inpainter of `path`, checked against the LaMa contract.
    pub fn onnx(path: &Path) -> Result<Inpainter> {
        let model = Model::load(path)?;
        model.expect("LaMa inpainting", &["image", "mask"], 1)?;
        Ok(Inpainter::Onnx(Box::new(model)))
    }

    pub fn name(&self) -> String {
        match self {
            Inpainter::Harmonic => "built-in harmonic".into(),
            Inpainter::Exemplar(_) => "built-in exemplar (PatchMatch)".into(),
            Inpainter::Onnx(m) => format!("onnx {}", m.path().display()),
            Inpainter::Provided { dir, .. } => format!("inpainted views from {}", dir.display()),
        }
    }

    /// The user's inpainted views of `dir` for the views named `names` (sizes `sizes`), found by
    /// name like the images (PNG or JPEG); a view of another size is resized bilinearly. Errors
    /// name the folder and the missing view.
    pub fn provided(dir: &Path, names: &[String], sizes: &[(u32, u32)]) -> Result<Inpainter> {
        use crate::scene::dataset::{find_image, load_rgb};
        if !dir.is_dir() {
            bail!("{}: --inpainted is not a folder", dir.display());
        }
        let mut views = Vec::with_capacity(names.len());
        for (name, &(w, h)) in names.iter().zip(sizes) {
            let path = find_image(dir, name).ok_or_else(|| {
                anyhow::anyhow!("{}: no inpainted view for image {name} (PNG or JPEG)", dir.display())
            })?;
            let (iw, ih, rgb) = load_rgb(&path)?;
            views.push(if (iw, ih) == (w, h) {
                rgb
            } else {
                eprintln!("{}: {iw}x{ih}, resized to the view's {w}x{h}", path.display());
                resize_bilinear(&rgb, iw as usize, ih as usize, 3, w as usize, h as usize)
            });
        }
        Ok(Inpainter::Provided { dir: dir.to_path_buf(), views })
    }

    /// Takes each provided view `i` through `map(i, rgb)`: `cogeo remove --exposure` brings them
    /// into the scene's colors, as it does the photos they complete. Other inpainters are unchanged.
    pub fn map_provided(&mut self, map: impl Fn(usize, &[f32]) -> Vec<f32>) {
        if let Inpainter::Provided { views, .. } = self {
            for (i, v) in views.iter_mut().enumerate() {
                *v = map(i, v);
            }
        }
    }

    /// As `inpaint`, for edited view `index` (the provided views are per view).
    pub fn inpaint_view(&self, index: usize, image: &[f32], hole: &[bool], w: usize, h: usize) -> Result<Vec<f32>> {
        if let Inpainter::Provided { views, dir } = self {
            let Some(view) = views.get(index).filter(|v| v.len() == 3 * w * h) else {
                bail!("{}: no inpainted view {index} of size {w}x{h}", dir.display());
            };
            let n = w * h;
            return Ok((0..3 * n).map(|i| if hole[i % n] { view[i] } else { image[i] }).collect());
        }
        self.inpaint(image, hole, w, h)
    }

    /// Fills the `hole` pixels of the planar RGB `image` (w x h); pixels outside the hole are
    /// returned unchanged.
    pub fn inpaint(&self, image: &[f32], hole: &[bool], w: usize, h: usize) -> Result<Vec<f32>> {
        if image.len() != 3 * w * h || hole.len() != w * h {
            bail!("inpaint: image and mask sizes disagree with {w}x{h}");
        }
        let Some(bbox) = bounding_box(hole, w) else {
            return Ok(image.to_vec());
        };
        match self {
            Inpainter::Harmonic => {
                let known: Vec<bool> = hole.iter().map(|&m| !m).collect();
                Ok(harmonic_fill(image, &known, w, h, 3))
            }
            Inpainter::Onnx(model) => lama(model, image, hole, w, h, bbox),
            Inpainter::Exemplar(e) => e.fill(image, hole, &vec![0; w * h], w, h),
            Inpainter::Provided { dir, .. } => {
                bail!("{}: provided inpaintings are per view (inpaint_view)", dir.display())
            }
        }
    }

    /// Inpaints `fill` of edited view `index`'s `image` (e.g. after color transfer made more
    /// pixels known), keeping each surface's colors on that surface where the built-in inpainter
    /// is used (`guide`: the surface labels, the completed disparity, the planes and the view's
    /// intrinsics); `avoid` pixels stay but lend the exemplar fill no texture. With the exemplar,
    /// also which surfaces' texture repeats (`exemplar::RectifiedFill::repeats`).
    #[allow(clippy::too_many_arguments)]
    pub fn inpaint_again(
        &self,
        index: usize,
        image: &[f32],
        fill: &[bool],
        avoid: &[bool],
        (labels, disparity, planes, k): (&[u8], &[f32], &[crate::planes::Plane], &super::rectify::Intrinsics),
        w: usize,
        h: usize,
    ) -> Result<(Vec<f32>, Option<[bool; 256]>)> {
        match self {
            // a membrane takes its values from the nearest boundary: stray colors are left out
            Inpainter::Harmonic => Ok((fill_by_surface(image, fill, labels, w, h, 3, Boundary::TypicalColors), None)),
            Inpainter::Exemplar(e) => {
                let filled = e.fill_rectified(image, fill, avoid, labels, Some(disparity), planes, k, w, h)?;
                Ok((filled.rgb, Some(filled.repeats)))
            }
            Inpainter::Onnx(_) | Inpainter::Provided { .. } => Ok((self.inpaint_view(index, image, fill, w, h)?, None)),
        }
    }
}

/// The context window around a hole: the box grown by half its size (at least `min_margin`),
/// clamped to the image.
pub fn context_window(b: Rect, w: usize, h: usize, min_margin: usize) -> Rect {
    b.grown((b.width() / 2).max(min_margin), (b.height() / 2).max(min_margin), w, h)
}

fn lama(model: &Model, image: &[f32], hole: &[bool], w: usize, h: usize, bbox: Rect) -> Result<Vec<f32>> {
    let win = context_window(bbox, w, h, 16);
    let (cw, ch) = (win.width(), win.height());
    let patch = crop(image, w, h, 3, win);
    let hole_f: Vec<f32> = hole.iter().map(|&m| m as u8 as f32).collect();
    let mask_patch = crop(&hole_f, w, h, 1, win);
    let s = LAMA_SIZE;
    let mut input = resize_bilinear(&patch, cw, ch, 3, s, s);
    // zero the hole as LaMa's training did; any mask pixel touched by the hole counts as hole
    let mask_big: Vec<f32> =
        resize_bilinear(&mask_patch, cw, ch, 1, s, s).iter().map(|&v| (v > 0.0) as u8 as f32).collect();
    for c in 0..3 {
        for i in 0..s * s {
            input[c * s * s + i] *= 1.0 - mask_big[i];
        }
    }
    let out = model.run(&[
        ("image", &Tensor::new(vec![1, 3, s as i64, s as i64], input)),
        ("mask", &Tensor::new(vec![1, 1, s as i64, s as i64], mask_big)),
    ])?;
    let result = &out[0];
    if result.data.len() != 3 * s * s {
        bail!("{}: LaMa output has shape {:?}, expected [1, 3, {s}, {s}]", model.path().display(), result.shape);
    }
    let back = resize_bilinear(&result.data, s, s, 3, cw, ch);
    let mut filled = image.to_vec();
    for y in win.y0..win.y1 {
        for x in win.x0..win.x1 {
            if hole[y * w + x] {
                let pi = (y - win.y0) * cw + (x - win.x0);
                for c in 0..3 {
                    filled[c * w * h + y * w + x] = back[c * cw * ch + pi].clamp(0.0, 1.0);
                }
            }
        }
    }
    Ok(filled)
}
