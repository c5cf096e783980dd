//! Depth completion stage 2 with a learned depth-inpainting denoiser: a deterministic DDIM loop in
//! which, after every step, the sample outside the hole is reset to the anchor depth noised to that
//! step's level, so only the hole is synthesized and the background comes out exactly as anchored
//! (the last step has no noise left).
//!
//! Depth is normalized per view to [-1, 1] (min/max of the anchor) for the loop and mapped back.
//! The schedule is DDPM's linear betas 1e-4 .. 0.02 over 1000 training steps.
//!
//! ONNX denoiser contract (`OnnxDenoiser`): inputs `sample` [1, 1, H, W] (noisy normalized depth),
//! `timestep` [1] (float, 0..999), `alpha_bar` [1] (the cumulative signal level at that step),
//! `image` [1, 3, H, W] (the completed RGB in [0, 1]), `mask` [1, 1, H, W] (1 = hole); output
//! [1, 1, H, W]: the predicted noise epsilon. H and W are the view's.

use crate::onnx::{Model, Tensor};
use crate::rng::Rng;
use anyhow::{bail, Result};
use std::path::Path;

pub const TRAIN_STEPS: usize = 1000;

/// Cumulative product of (1 - beta) up to training step t (0-based).
pub fn alpha_bar(t: usize) -> f64 {
    (0..=t.min(TRAIN_STEPS - 1)).map(|s| 1.0 - (1e-4 + (0.02 - 1e-4) * s as f64 / (TRAIN_STEPS - 1) as f64)).product()
}

/// Predicts the noise in a sample.
pub trait Denoiser {
    #[allow(clippy::too_many_arguments)]
    fn predict_noise(
        &self,
        sample: &[f32],
        timestep: usize,
        alpha_bar: f64,
        image: &[f32],
        mask: &[f32],
        w: usize,
        h: usize,
    ) -> Result<Vec<f32>>;
}

pub struct OnnxDenoiser(Model);

impl OnnxDenoiser {
    pub fn load(path: &Path) -> Result<OnnxDenoiser> {
        let model = Model::load(path)?;
        model.expect("depth denoiser", &["sample", "timestep", "alpha_bar", "image", "mask"], 1)?;
        Ok(OnnxDenoiser(model))
    }

    pub fn path(&self) -> &Path {
        self.0.path()
    }
}

impl Denoiser for OnnxDenoiser {
    fn predict_noise(
        &self,
        sample: &[f32],
        timestep: usize,
        alpha_bar: f64,
        image: &[f32],
        mask: &[f32],
        w: usize,
        h: usize,
    ) -> Result<Vec<f32>> {
        let (wi, hi) = (w as i64, h as i64);
        let out = self.0.run(&[
            ("sample", &Tensor::new(vec![1, 1, hi, wi], sample.to_vec())),
            ("timestep", &Tensor::new(vec![1], vec![timestep as f32])),
            ("alpha_bar", &Tensor::new(vec![1], vec![alpha_bar as f32])),
            ("image", &Tensor::new(vec![1, 3, hi, wi], image.to_vec())),
            ("mask", &Tensor::new(vec![1, 1, hi, wi], mask.to_vec())),
        ])?;
        if out[0].data.len() != w * h {
            bail!("{}: denoiser output has shape {:?}, expected [1, 1, {h}, {w}]", self.path().display(), out[0].shape);
        }
        Ok(out[0].data.clone())
    }
}

/// Runs the masked loop on `anchor` (depth, w x h) over `steps` DDIM steps. Pixels outside `hole`
/// are returned exactly as in `anchor`.
#[allow(clippy::too_many_arguments)]
pub fn masked_ddim(
    anchor: &[f32],
    hole: &[bool],
    image: &[f32],
    w: usize,
    h: usize,
    steps: usize,
    seed: u64,
    denoiser: &dyn Denoiser,
) -> Result<Vec<f32>> {
    if steps == 0 || steps > TRAIN_STEPS {
        bail!("diffusion steps must be 1..{TRAIN_STEPS}");
    }
    let lo = anchor.iter().copied().fold(f32::INFINITY, f32::min) as f64;
    let hi = anchor.iter().copied().fold(f32::NEG_INFINITY, f32::max) as f64;
    let span = (hi - lo).max(1e-9);
    let normalized: Vec<f64> = anchor.iter().map(|&d| 2.0 * (d as f64 - lo) / span - 1.0).collect();
    let mask: Vec<f32> = hole.iter().map(|&m| m as u8 as f32).collect();
    let mut rng = Rng::new(seed);
    let n = w * h;
    // timesteps from the noisiest down to 0
    let ts: Vec<usize> = (0..steps).map(|k| (TRAIN_STEPS - 1) * (steps - 1 - k) / (steps - 1).max(1)).collect();
    let ts: Vec<usize> = if steps == 1 { vec![TRAIN_STEPS - 1] } else { ts };
    let ab0 = alpha_bar(ts[0]);
    let mut x: Vec<f64> = normalized.iter().map(|&a| ab0.sqrt() * a + (1.0 - ab0).sqrt() * rng.normal()).collect();
    for (k, &t) in ts.iter().enumerate() {
        let ab = alpha_bar(t);
        let ab_prev = if k + 1 < ts.len() { alpha_bar(ts[k + 1]) } else { 1.0 };
        let sample: Vec<f32> = x.iter().map(|&v| v as f32).collect();
        let eps = denoiser.predict_noise(&sample, t, ab, image, &mask, w, h)?;
        if eps.len() != n {
            bail!("denoiser returned {} values for {n} pixels", eps.len());
        }
        for i in 0..n {
            let e = eps[i] as f64;
            if hole[i] {
                let x0 = (x[i] - (1.0 - ab).sqrt() * e) / ab.sqrt();
                x[i] = ab_prev.sqrt() * x0.clamp(-1.5, 1.5) + (1.0 - ab_prev).sqrt() * e;
            } else {
                // the known region follows the forward process of the anchor
                let z = if ab_prev < 1.0 { rng.normal() } else { 0.0 };
                x[i] = ab_prev.sqrt() * normalized[i] + (1.0 - ab_prev).sqrt() * z;
            }
        }
    }
    Ok((0..n).map(|i| if hole[i] { ((x[i] + 1.0) * 0.5 * span + lo) as f32 } else { anchor[i] }).collect())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A denoiser that knows the clean signal is `target` (normalized): eps = (x - sqrt(ab) target) / sqrt(1 - ab).
    struct Oracle(Vec<f32>);

    impl Denoiser for Oracle {
        fn predict_noise(
            &self,
            s: &[f32],
            _t: usize,
            ab: f64,
            _i: &[f32],
            _m: &[f32],
            _w: usize,
            _h: usize,
        ) -> Result<Vec<f32>> {
            Ok(s.iter()
                .zip(&self.0)
                .map(|(&x, &t)| ((x as f64 - ab.sqrt() * t as f64) / (1.0 - ab).sqrt()) as f32)
                .collect())
        }
    }

    #[test]
    fn schedule_is_monotone_and_ends_near_zero_signal() {
        assert!((alpha_bar(0) - (1.0 - 1e-4)).abs() < 1e-12);
        assert!(alpha_bar(999) < 1e-4);
        assert!((1..TRAIN_STEPS).all(|t| alpha_bar(t) < alpha_bar(t - 1)));
    }

    #[test]
    fn oracle_denoiser_synthesizes_its_target_in_the_hole_only() {
        let (w, h) = (12, 9);
        let anchor: Vec<f32> = (0..w * h).map(|i| 2.0 + 0.1 * (i % w) as f32).collect();
        let hole: Vec<bool> = (0..w * h).map(|i| (3..8).contains(&(i % w)) && (2..6).contains(&(i / w))).collect();
        // the oracle's target: normalized value 0 (the middle of the anchor's range) everywhere
        let oracle = Oracle(vec![0.0; w * h]);
        let image = vec![0.5; 3 * w * h];
        let out = masked_ddim(&anchor, &hole, &image, w, h, 10, 3, &oracle).unwrap();
        let (lo, hi) = (2.0f32, 2.0 + 0.1 * (w - 1) as f32);
        for i in 0..w * h {
            if hole[i] {
                assert!((out[i] - (lo + hi) / 2.0).abs() < 1e-4, "hole pixel {i}: {}", out[i]);
            } else {
                assert_eq!(out[i], anchor[i], "background pixel {i} changed");
            }
        }
    }
}
