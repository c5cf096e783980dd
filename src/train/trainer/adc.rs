//! INRIA adaptive density control for `Trainer` (`Strategy::Adc`): clone / split / prune from the
//! accumulated view-space gradients, and the periodic opacity reset.

use super::Trainer;
use crate::gpu::Recorder;
use crate::scene::camera::rotation_from_qvec;
use crate::scene::{logit, GaussianScene};
use anyhow::{bail, Result};

impl Trainer {
    /// INRIA adaptive density control: clone small / split large Gaussians whose mean view-space
    /// gradient exceeds the threshold, prune transparent and oversized ones.
    pub(super) fn densify(&mut self) -> Result<()> {
        let n = self.scene.num_gaussians as usize;
        let sums: Vec<f32> = self.grads.xy_norm_sum.download(&self.gpu, n)?;
        let views: Vec<u32> = self.grads.xy_views.download(&self.gpu, n)?;
        let scene = self.download_scene()?;
        let k = scene.sh_coeffs();
        let extent = self.extent as f32;
        let mut out = GaussianScene { sh_degree: scene.sh_degree, ..Default::default() };
        let mut keep: Vec<Option<usize>> = Vec::new();
        let budget = self.cfg.max_gaussians;
        let push = |out: &mut GaussianScene,
                    keep: &mut Vec<Option<usize>>,
                    i: usize,
                    mean: [f32; 3],
                    log_scale: [f32; 3],
                    carried: bool| {
            out.push(mean, log_scale, scene.quats[i], scene.opacity_logits[i], &scene.sh[i * k * 3..(i + 1) * k * 3]);
            keep.push(if carried { Some(i) } else { None });
        };
        let mut grown = n;
        for i in 0..n {
            let opacity = 1.0 / (1.0 + (-scene.opacity_logits[i]).exp());
            let max_scale = scene.log_scales[i].iter().fold(f32::MIN, |a, &b| a.max(b)).exp();
            // prune: nearly transparent, or huge in the world once opacity has been reset once
            if opacity < 0.005 || (self.step > self.cfg.opacity_reset_interval && max_scale > 0.1 * extent) {
                continue;
            }
            let grad = if views[i] > 0 { sums[i] / views[i] as f32 } else { 0.0 };
            let dense = grad >= self.cfg.grad_threshold && grown < budget;
            if dense && max_scale <= 0.01 * extent {
                // clone: same Gaussian twice
                push(&mut out, &mut keep, i, scene.means[i], scene.log_scales[i], true);
                push(&mut out, &mut keep, i, scene.means[i], scene.log_scales[i], false);
                grown += 1;
            } else if dense {
                // split into two samples of the Gaussian, scales divided by 1.6
                let r = rotation_from_qvec(scene.quats[i].map(|v| v as f64));
                let s = scene.log_scales[i].map(|v| (v as f64).exp());
                for _ in 0..2 {
                    let z = [self.rng.normal() * s[0], self.rng.normal() * s[1], self.rng.normal() * s[2]];
                    let off: Vec<f64> = (0..3).map(|a| r[a][0] * z[0] + r[a][1] * z[1] + r[a][2] * z[2]).collect();
                    let mean = [0, 1, 2].map(|a| scene.means[i][a] + off[a] as f32);
                    let ls = scene.log_scales[i].map(|v| v - 1.6f32.ln());
                    push(&mut out, &mut keep, i, mean, ls, false);
                }
                grown += 1;
            } else {
                push(&mut out, &mut keep, i, scene.means[i], scene.log_scales[i], true);
            }
        }
        if out.is_empty() {
            bail!("densification pruned every Gaussian (step {})", self.step);
        }
        self.replace_scene(&out, &keep)
    }

    /// Sets every opacity to at most 0.01 and clears its Adam state (INRIA's opacity reset).
    pub(super) fn reset_opacity(&mut self) -> Result<()> {
        let n = self.scene.num_gaussians as usize;
        let cap = logit(0.01);
        let ops: Vec<f32> =
            self.scene.opacity_logits.download::<f32>(&self.gpu, n)?.iter().map(|&v| v.min(cap)).collect();
        self.scene.opacity_logits.upload(&self.gpu, &ops)?;
        let m = &self.moments.opacity_logits;
        let mut rec = Recorder::new(&self.gpu)?;
        rec.fill(&m.m, 0, m.m.size(), 0);
        rec.fill(&m.v, 0, m.v.size(), 0);
        rec.submit_and_wait()?;
        Ok(())
    }
}
