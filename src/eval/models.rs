//! Learned metrics through ONNX networks as they are published (cogeo ships no weights; without a
//! model the metric is reported as not computed). Nothing about a network is assumed beyond its
//! shape: input names come from the model (or the caller), the value range from the caller.
//!
//! - LPIPS: two image inputs [1, 3, H, W] (taken in the model's order unless named), RGB mapped from
//!   [0, 1] by `scale * x + offset` (the LPIPS convention, [-1, 1], is 2x - 1); the first output holds
//!   the distance (one value). Lower is better. Networks with strided backbones need a minimum side
//!   (AlexNet LPIPS: 32): smaller images are upsampled to it, crops are grown to it.
//! - FID features: one input [N, 3, 299, 299] (bilinearly resized), mapped by `scale * x + offset`
//!   (TF-style FID feeds x_uint8 / 128 - 1, i.e. scale 255/128 and offset -1); first output [N, D]
//!   (Inception-v3 pool3 gives D = 2048). cogeo fits a Gaussian to each set's features and reports
//!   their Fréchet distance (`frechet_distance`), with the sample count beside it.

use crate::image_ops::{bounding_box, crop, resize_bilinear, Rect};
use crate::onnx::{Model, Tensor};
use anyhow::{bail, Result};
use std::path::{Path, PathBuf};

/// How images are fed to a network: input names (None: the model's own, in its order) and the
/// affine map from [0, 1].
#[derive(Clone, Debug, PartialEq)]
pub struct NetworkInput {
    pub names: Option<Vec<String>>,
    pub scale: f32,
    pub offset: f32,
}

impl NetworkInput {
    /// LPIPS's own convention, [-1, 1] (`MetricModels`' defaults).
    pub fn lpips_default() -> NetworkInput {
        MetricModels::default().lpips_input()
    }

    /// TF-style FID (pytorch-fid, clean-fid), x_uint8 / 128 - 1 (`MetricModels`' defaults).
    pub fn fid_default() -> NetworkInput {
        MetricModels::default().fid_input()
    }

    /// The input names to feed: the given ones, which the model must have, else all of the model's.
    fn resolve(&self, model: &Model, what: &str, count: usize) -> Result<Vec<String>> {
        let names = self.names.clone().unwrap_or_else(|| model.input_names().to_vec());
        if names.len() != count {
            bail!(
                "{}: {what} needs {count} image input(s); the model has {:?}{}",
                model.path().display(),
                model.input_names(),
                if self.names.is_some() { format!(", {:?} were named", names) } else { String::new() }
            );
        }
        if let Some(n) = names.iter().find(|n| !model.input_names().contains(n)) {
            bail!("{}: the model has no input {n:?} (it has {:?})", model.path().display(), model.input_names());
        }
        if model.output_names().is_empty() {
            bail!("{}: the model has no output", model.path().display());
        }
        Ok(names)
    }

    fn map(&self, x: &[f32]) -> Vec<f32> {
        x.iter().map(|v| self.scale * v + self.offset).collect()
    }
}

pub struct Lpips {
    model: Model,
    inputs: [String; 2],
    input: NetworkInput,
    min_side: usize,
}

impl Lpips {
    /// Loads an LPIPS network; `min_side` is the smallest image side it accepts.
    pub fn load(path: &Path, input: NetworkInput, min_side: usize) -> Result<Lpips> {
        let model = Model::load(path)?;
        let names = input.resolve(&model, "LPIPS", 2)?;
        Ok(Lpips { model, inputs: [names[0].clone(), names[1].clone()], input, min_side: min_side.max(1) })
    }

    /// Distance between two planar RGB images in [0, 1] of size w x h (upsampled so that the
    /// smaller side is at least the minimum).
    pub fn distance(&mut self, a: &[f32], b: &[f32], w: usize, h: usize) -> Result<f64> {
        let (a, b, w, h) = if w.min(h) < self.min_side {
            let f = self.min_side as f64 / w.min(h) as f64;
            let (nw, nh) = (
                ((w as f64 * f).ceil() as usize).max(self.min_side),
                ((h as f64 * f).ceil() as usize).max(self.min_side),
            );
            (resize_bilinear(a, w, h, 3, nw, nh), resize_bilinear(b, w, h, 3, nw, nh), nw, nh)
        } else {
            (a.to_vec(), b.to_vec(), w, h)
        };
        let tensor = |x: &[f32]| Tensor::new(vec![1, 3, h as i64, w as i64], self.input.map(x));
        let (ta, tb) = (tensor(&a), tensor(&b));
        let out = self.model.run(&[(self.inputs[0].as_str(), &ta), (self.inputs[1].as_str(), &tb)])?;
        if out[0].data.len() != 1 {
            bail!("{}: LPIPS output has {} values, expected one", self.model.path().display(), out[0].data.len());
        }
        Ok(out[0].data[0] as f64)
    }

    /// The region's bounding box, grown around its centre to the minimum side where the image allows.
    pub fn region_box(&self, region: &[bool], w: usize, h: usize) -> Option<Rect> {
        bounding_box(region, w).map(|r| grow_to(r, self.min_side, w, h))
    }

    /// Bbox LPIPS: the region's bounding-box crop of `render` against the same crop of `gt`.
    pub fn bbox(&mut self, render: &[f32], gt: &[f32], region: &[bool], w: usize, h: usize) -> Result<Option<f64>> {
        let Some(r) = self.region_box(region, w, h) else { return Ok(None) };
        self.distance(&crop(render, w, h, 3, r), &crop(gt, w, h, 3, r), r.width(), r.height()).map(Some)
    }

    /// Masked LPIPS: as `bbox`, with the render pasted into the ground truth inside the region only,
    /// so that every difference the network sees comes from the region's pixels.
    pub fn masked(&mut self, render: &[f32], gt: &[f32], region: &[bool], w: usize, h: usize) -> Result<Option<f64>> {
        let n = w * h;
        let pasted: Vec<f32> = (0..3 * n).map(|i| if region[i % n] { render[i] } else { gt[i] }).collect();
        self.bbox(&pasted, gt, region, w, h)
    }
}

/// `r` grown symmetrically (then shifted to fit) to at least `side` x `side`, clamped to w x h.
fn grow_to(r: Rect, side: usize, w: usize, h: usize) -> Rect {
    let grow = |lo: usize, hi: usize, limit: usize| {
        let want = side.min(limit);
        if hi - lo >= want {
            return (lo, hi);
        }
        let lo = lo.saturating_sub((want - (hi - lo)) / 2).min(limit - want);
        (lo, lo + want)
    };
    let (x0, x1) = grow(r.x0, r.x1, w);
    let (y0, y1) = grow(r.y0, r.y1, h);
    Rect { x0, y0, x1, y1 }
}

pub const FID_SIDE: usize = 299;

pub struct FidFeatures {
    model: Model,
    input_name: String,
    input: NetworkInput,
}

impl FidFeatures {
    pub fn load(path: &Path, input: NetworkInput) -> Result<FidFeatures> {
        let model = Model::load(path)?;
        let input_name = input.resolve(&model, "the FID feature network", 1)?.remove(0);
        Ok(FidFeatures { model, input_name, input })
    }

    /// Feature vector of one planar RGB image in [0, 1].
    pub fn features(&mut self, img: &[f32], w: usize, h: usize) -> Result<Vec<f64>> {
        let x = resize_bilinear(img, w, h, 3, FID_SIDE, FID_SIDE);
        let t = Tensor::new(vec![1, 3, FID_SIDE as i64, FID_SIDE as i64], self.input.map(&x));
        let out = self.model.run(&[(self.input_name.as_str(), &t)])?;
        let f = &out[0];
        if f.shape.len() != 2 || f.shape[0] != 1 {
            bail!("{}: FID features have shape {:?}, expected [N, D]", self.model.path().display(), f.shape);
        }
        Ok(f.data.iter().map(|&v| v as f64).collect())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn grown_boxes_keep_the_region_and_fit_the_image() {
        // grown around the region, shifted back inside the image at the bottom edge
        let r = grow_to(Rect { x0: 3, y0: 8, x1: 5, y1: 10 }, 8, 20, 11);
        assert_eq!((r.x0, r.x1, r.y0, r.y1), (0, 8, 3, 11));
        let big = Rect { x0: 0, y0: 0, x1: 20, y1: 11 };
        let same = grow_to(big, 8, 20, 11);
        assert_eq!((same.x0, same.x1, same.y0, same.y1), (0, 20, 0, 11));
        let small = grow_to(Rect { x0: 1, y0: 1, x1: 2, y1: 2 }, 64, 20, 11);
        assert_eq!((small.width(), small.height()), (20, 11));
    }
}

/// The learned-metric networks and how to feed them; defaults fit the published LPIPS (v0.1) and
/// TF-FID Inception-v3 exports, whose input names are read from the model.
#[derive(clap::Args, Clone, Debug)]
pub struct MetricModels {
    /// LPIPS network (ONNX): two image inputs [1,3,H,W], one output value. Reports full-image,
    /// bounding-box and masked LPIPS (masked: the render pasted into the ground truth inside the
    /// mask only, cropped to the mask's box); with --data also never-seen and seen-elsewhere.
    #[arg(long)]
    pub lpips_model: Option<PathBuf>,
    /// The LPIPS inputs' names, e.g. `img0,img1` (default: the model's two inputs, in its order).
    #[arg(long, value_delimiter = ',', num_args = 2)]
    pub lpips_inputs: Option<Vec<String>>,
    /// LPIPS input = scale * rgb + offset, rgb in [0,1] (default 2, -1: the [-1,1] of LPIPS).
    #[arg(long, default_value_t = 2.0, allow_negative_numbers = true)]
    pub lpips_scale: f32,
    #[arg(long, default_value_t = -1.0, allow_negative_numbers = true)]
    pub lpips_offset: f32,
    /// Smallest side the LPIPS network accepts (AlexNet: 32): smaller images are upsampled and
    /// crops grown to it.
    #[arg(long, default_value_t = 32)]
    pub lpips_min_side: usize,
    /// FID feature network (ONNX): one image input [N,3,299,299] (resized bilinearly), output [N,D].
    #[arg(long)]
    pub fid_model: Option<PathBuf>,
    /// The FID input's name (default: the model's only input).
    #[arg(long)]
    pub fid_input: Option<String>,
    /// FID input = scale * rgb + offset, rgb in [0,1] (default 255/128, -1: TF-FID's x/128 - 1).
    #[arg(long, default_value_t = 255.0 / 128.0, allow_negative_numbers = true)]
    pub fid_scale: f32,
    #[arg(long, default_value_t = -1.0, allow_negative_numbers = true)]
    pub fid_offset: f32,
}

crate::default_from_flags!(MetricModels);

impl MetricModels {
    pub fn lpips_input(&self) -> NetworkInput {
        NetworkInput { names: self.lpips_inputs.clone(), scale: self.lpips_scale, offset: self.lpips_offset }
    }

    pub fn fid_input(&self) -> NetworkInput {
        NetworkInput { names: self.fid_input.clone().map(|n| vec![n]), scale: self.fid_scale, offset: self.fid_offset }
    }
}
