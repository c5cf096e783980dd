//! Learned metrics through user-supplied ONNX networks. cogeo ships no weights; without a model
//! the metric is reported as not computed.
//!
//! - LPIPS contract: inputs `in0` and `in1`, each [1, 3, H, W] RGB scaled to [-1, 1] (H, W >= 16,
//!   the image's own size); output: the distance, any shape holding one value (the reference
//!   export gives [1, 1, 1, 1]). Lower is better.
//! - FID feature contract: input `images` [N, 3, 299, 299] RGB in [0, 1] (bilinearly resized);
//!   output: features [N, D] (Inception-v3 pool3 gives D = 2048). cogeo fits a Gaussian to each
//!   set's features and reports their Fréchet distance (`frechet_distance`). With a handful of
//!   views FID is noisy: the report gives the sample count next to it.

use crate::image_ops::resize_bilinear;
use crate::onnx::{Model, Tensor};
use anyhow::{bail, Result};
use std::path::Path;

pub struct Lpips(Model);

impl Lpips {
    pub fn load(path: &Path) -> Result<Lpips> {
        let m = Model::load(path)?;
        m.expect("LPIPS", &["in0", "in1"], 1)?;
        Ok(Lpips(m))
    }

    /// Distance between two planar RGB images in [0, 1] of size w x h.
    pub fn distance(&mut self, a: &[f32], b: &[f32], w: usize, h: usize) -> Result<f64> {
        let scale = |x: &[f32]| Tensor::new(vec![1, 3, h as i64, w as i64], x.iter().map(|v| 2.0 * v - 1.0).collect());
        let (ta, tb) = (scale(a), scale(b));
        let out = self.0.run(&[("in0", &ta), ("in1", &tb)])?;
        if out[0].data.len() != 1 {
            bail!("{}: LPIPS output has {} values, the contract is one", self.0.path().display(), out[0].data.len());
        }
        Ok(out[0].data[0] as f64)
    }
}

pub const FID_SIDE: usize = 299;

pub struct FidFeatures(Model);

impl FidFeatures {
    pub fn load(path: &Path) -> Result<FidFeatures> {
        let m = Model::load(path)?;
        m.expect("FID feature", &["images"], 1)?;
        Ok(FidFeatures(m))
    }

    /// Feature vector of one planar RGB image in [0, 1].
    pub fn features(&mut self, img: &[f32], w: usize, h: usize) -> Result<Vec<f64>> {
        let x = resize_bilinear(img, w, h, 3, FID_SIDE, FID_SIDE);
        let t = Tensor::new(vec![1, 3, FID_SIDE as i64, FID_SIDE as i64], x);
        let out = self.0.run(&[("images", &t)])?;
        let f = &out[0];
        if f.shape.len() != 2 || f.shape[0] != 1 {
            bail!("{}: FID features have shape {:?}, the contract is [N, D]", self.0.path().display(), f.shape);
        }
        Ok(f.data.iter().map(|&v| v as f64).collect())
    }
}
