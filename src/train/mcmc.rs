//! The 3DGS-MCMC densification strategy (Kheradmand et al., "3D Gaussian Splatting as Markov Chain
//! Monte Carlo", 2024), an alternative to INRIA's clone/split/prune with a hard Gaussian budget:
//!
//! - every iteration: opacity and scale L1 regularizers (`mcmc_regularize.comp`, before Adam) and
//!   covariance-shaped position noise gated to near-transparent Gaussians (`mcmc_noise.comp`, after);
//! - every densification interval, on the host: "dead" Gaussians (opacity <= 0.005) are relocated
//!   onto live ones sampled in proportion to opacity, and the scene grows by 5 % up to the budget
//!   (`--max-gaussians`) the same way. A source Gaussian copied into N Gaussians at its own position
//!   gets opacity 1 - (1 - o)^(1/N) and a scale chosen so that the N stacked copies keep the same
//!   opacity at the center and the same integral along a line through it (`relocated`).

use crate::gpu::{dispatch_1d, ComputePipeline, Gpu, Recorder};
use crate::render::backward::SceneGradients;
use crate::render::SceneBuffers;
use crate::rng::Rng;
use crate::scene::{logit, GaussianScene};
use crate::shaders;
use anyhow::{bail, Result};
use bytemuck::{Pod, Zeroable};

/// Gaussians at or below this opacity are dead and get relocated.
pub const MIN_OPACITY: f64 = 0.005;
/// Noise learning rate: the noise is this times the current position learning rate times Sigma z.
pub const NOISE_LR: f32 = 5e5;
pub const OPACITY_REG: f32 = 0.01;
pub const SCALE_REG: f32 = 0.01;
/// The scene grows by this factor per densification step until it reaches the budget.
pub const GROWTH: f64 = 1.05;
/// Copies per source are capped here (the binomial sum loses precision beyond).
const MAX_COPIES: usize = 51;

#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct RegularizePush {
    opacity_logits: u64,
    log_scales: u64,
    grad_opacity: u64,
    grad_log_scales: u64,
    n: u32,
    opacity_weight: f32,
    scale_weight: f32,
    _pad: u32,
}

#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct NoisePush {
    means: u64,
    log_scales: u64,
    quats: u64,
    opacity_logits: u64,
    n: u32,
    scale: f32,
    seed: u32,
    _pad: u32,
}

/// The two per-iteration GPU passes of the strategy.
pub struct McmcPasses {
    regularize: ComputePipeline,
    noise: ComputePipeline,
}

impl McmcPasses {
    pub fn new(gpu: &Gpu) -> Result<McmcPasses> {
        Ok(McmcPasses {
            regularize: ComputePipeline::new(gpu, "mcmc_regularize", shaders::MCMC_REGULARIZE)?,
            noise: ComputePipeline::new(gpu, "mcmc_noise", shaders::MCMC_NOISE)?,
        })
    }

    /// Adds the gradients of `w_o mean sigmoid(o) + w_s mean exp(s)` to the opacity and scale gradients.
    pub fn record_regularize(
        &self,
        rec: &mut Recorder,
        scene: &SceneBuffers,
        grads: &SceneGradients,
        weights: (f32, f32),
    ) {
        let push = RegularizePush {
            opacity_logits: scene.opacity_logits.address(),
            log_scales: scene.log_scales.address(),
            grad_opacity: grads.opacity_logits.address(),
            grad_log_scales: grads.log_scales.address(),
            n: scene.num_gaussians,
            opacity_weight: weights.0,
            scale_weight: weights.1,
            _pad: 0,
        };
        rec.dispatch(&self.regularize, &push, dispatch_1d(scene.num_gaussians.div_ceil(256)));
    }

    /// Moves every mean by `scale * Sigma z * gate(opacity)`; `seed` should differ per iteration.
    pub fn record_noise(&self, rec: &mut Recorder, scene: &SceneBuffers, scale: f32, seed: u32) {
        let push = NoisePush {
            means: scene.means.address(),
            log_scales: scene.log_scales.address(),
            quats: scene.quats.address(),
            opacity_logits: scene.opacity_logits.address(),
            n: scene.num_gaussians,
            scale,
            seed,
            _pad: 0,
        };
        rec.dispatch(&self.noise, &push, dispatch_1d(scene.num_gaussians.div_ceil(256)));
    }
}

/// Opacity and scale factor for one of `copies` Gaussians that replace a Gaussian of opacity
/// `opacity` at the same position: o' = 1 - (1 - o)^(1/N), and s'/s = o / sum_{i=1..N} sum_{k<i}
/// C(i-1, k) (-1)^k o'^(k+1) / sqrt(k+1), which makes the 1D integral of 1 - (1 - o' g(x/s'))^N
/// equal that of o g(x/s).
pub fn relocated(opacity: f64, copies: usize) -> (f64, f64) {
    let n = copies.clamp(1, MAX_COPIES);
    let o = opacity.clamp(MIN_OPACITY, 1.0 - 1e-6);
    let o_new = 1.0 - (1.0 - o).powf(1.0 / n as f64);
    let mut denom = 0.0;
    for i in 1..=n {
        let mut binom = 1.0; // C(i-1, k)
        for k in 0..i {
            let sign = if k % 2 == 0 { 1.0 } else { -1.0 };
            denom += binom * sign * o_new.powi(k as i32 + 1) / ((k + 1) as f64).sqrt();
            binom = binom * (i - 1 - k) as f64 / (k + 1) as f64;
        }
    }
    (o_new, o / denom)
}

/// What one relocation step did.
#[derive(Clone, Copy, Debug, Default)]
pub struct RelocationStats {
    pub relocated: usize,
    pub added: usize,
}

fn sigmoid(x: f32) -> f64 {
    1.0 / (1.0 + (-(x as f64)).exp())
}

/// Draws `count` indices with probability proportional to `weights` (with replacement).
fn sample_weighted(weights: &[f64], count: usize, rng: &mut Rng) -> Vec<usize> {
    let mut cdf = Vec::with_capacity(weights.len());
    let mut total = 0.0;
    for &w in weights {
        total += w;
        cdf.push(total);
    }
    (0..count)
        .map(|_| {
            let u = rng.uniform() * total;
            cdf.partition_point(|&c| c <= u).min(weights.len() - 1)
        })
        .collect()
}

/// Gives each sampled source its relocated opacity and scale for (its sample count + 1) copies;
/// returns the sources in first-sampled order.
fn apply_relocation(scene: &mut GaussianScene, samples: &[usize]) -> Vec<usize> {
    let mut counts = std::collections::HashMap::<usize, usize>::new();
    let mut order = Vec::new();
    for &s in samples {
        let c = counts.entry(s).or_insert(0);
        if *c == 0 {
            order.push(s);
        }
        *c += 1;
    }
    for &s in &order {
        let (o, ratio) = relocated(sigmoid(scene.opacity_logits[s]), counts[&s] + 1);
        scene.opacity_logits[s] = logit(o);
        let d = (ratio.max(1e-30)).ln() as f32;
        scene.log_scales[s] = scene.log_scales[s].map(|v| v + d);
    }
    order
}

/// Copies Gaussian `src` (all attributes) over slot `dst`, or appends it when `dst` is None.
fn copy_gaussian(scene: &mut GaussianScene, src: usize, dst: Option<usize>) {
    let k3 = scene.sh_coeffs() * 3;
    let sh: Vec<f32> = scene.sh[src * k3..(src + 1) * k3].to_vec();
    let (m, n, s, q, o) =
        (scene.means[src], scene.normals[src], scene.log_scales[src], scene.quats[src], scene.opacity_logits[src]);
    match dst {
        Some(d) => {
            scene.means[d] = m;
            scene.normals[d] = n;
            scene.log_scales[d] = s;
            scene.quats[d] = q;
            scene.opacity_logits[d] = o;
            scene.sh[d * k3..(d + 1) * k3].copy_from_slice(&sh);
        }
        None => {
            scene.means.push(m);
            scene.normals.push(n);
            scene.log_scales.push(s);
            scene.quats.push(q);
            scene.opacity_logits.push(o);
            scene.sh.extend_from_slice(&sh);
        }
    }
}

/// One MCMC densification step on a host copy of the scene: relocate dead Gaussians, then grow by
/// 5 % up to `budget`. Returns the new scene and, per new Gaussian, the old index whose Adam moments
/// it keeps (None = fresh moments: relocated Gaussians, their sources, and added Gaussians).
pub fn relocate_and_grow(
    scene: &GaussianScene,
    budget: usize,
    rng: &mut Rng,
) -> Result<(GaussianScene, Vec<Option<usize>>, RelocationStats)> {
    let mut out = scene.clone();
    let n = scene.len();
    let mut keep: Vec<Option<usize>> = (0..n).map(Some).collect();
    let opacity: Vec<f64> = scene.opacity_logits.iter().map(|&l| sigmoid(l)).collect();
    let dead: Vec<usize> = (0..n).filter(|&i| opacity[i].is_nan() || opacity[i] <= MIN_OPACITY).collect();
    let alive_weight: Vec<f64> = opacity.iter().map(|&o| if o > MIN_OPACITY { o } else { 0.0 }).collect();
    if dead.len() == n {
        bail!("every Gaussian is transparent (opacity <= {MIN_OPACITY}); nothing to relocate onto");
    }
    let mut stats = RelocationStats::default();
    if !dead.is_empty() {
        let samples = sample_weighted(&alive_weight, dead.len(), rng);
        let sources = apply_relocation(&mut out, &samples);
        for (&d, &s) in dead.iter().zip(&samples) {
            copy_gaussian(&mut out, s, Some(d));
            keep[d] = None;
        }
        for s in sources {
            keep[s] = None;
        }
        stats.relocated = dead.len();
    }
    let target = budget.min((n as f64 * GROWTH) as usize);
    if target > n {
        let weight: Vec<f64> = out.opacity_logits.iter().map(|&l| sigmoid(l)).collect();
        let samples = sample_weighted(&weight, target - n, rng);
        apply_relocation(&mut out, &samples);
        for &s in &samples {
            copy_gaussian(&mut out, s, None);
            keep.push(None);
        }
        stats.added = target - n;
    }
    Ok((out, keep, stats))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Numerical 1D integral of 1 - (1 - o g(x/s))^N over the real line (g the unit Gaussian bump).
    fn line_integral(o: f64, s: f64, n: usize) -> f64 {
        let h = s * 1e-3;
        (-20_000..=20_000)
            .map(|i| {
                let x = i as f64 * h;
                1.0 - (1.0 - o * (-0.5 * x * x / (s * s)).exp()).powi(n as i32)
            })
            .sum::<f64>()
            * h
    }

    #[test]
    fn relocated_copies_keep_center_opacity_and_line_integral() {
        for &o in &[0.01, 0.3, 0.8, 0.99] {
            for &copies in &[1usize, 2, 3, 7, 20] {
                let (o_new, ratio) = relocated(o, copies);
                let center = 1.0 - (1.0 - o_new).powi(copies as i32);
                assert!((center - o).abs() < 1e-12, "o {o} N {copies}: center {center}");
                let want = line_integral(o, 1.0, 1);
                let got = line_integral(o_new, ratio, copies);
                assert!((got - want).abs() < 1e-9 * want.max(1.0), "o {o} N {copies}: {got} vs {want}");
            }
        }
    }

    #[test]
    fn relocation_moves_dead_onto_live_and_grows_to_budget() {
        let mut scene = GaussianScene { sh_degree: 0, ..Default::default() };
        for i in 0..100 {
            // every 4th is dead
            let opacity = if i % 4 == 0 { logit(0.001) } else { logit(0.6) };
            scene.push([i as f32, 0.0, 0.0], [-2.0; 3], [1.0, 0.0, 0.0, 0.0], opacity, &[i as f32, 0.0, 0.0]);
        }
        let mut rng = Rng::new(3);
        let (out, keep, stats) = relocate_and_grow(&scene, 103, &mut rng).unwrap();
        assert_eq!(stats.relocated, 25);
        assert_eq!(stats.added, 3, "grows by 5 % but stops at the budget");
        assert_eq!(out.len(), 103);
        assert_eq!(keep.len(), 103);
        out.validate("relocated").unwrap();
        for i in 0..out.len() {
            let o = sigmoid(out.opacity_logits[i]);
            assert!(o > MIN_OPACITY, "Gaussian {i} still dead ({o})");
            // every Gaussian sits on a live source: its mean and color are those of a live original
            let src = out.sh[3 * i] as usize;
            assert!(!src.is_multiple_of(4), "Gaussian {i} copies dead source {src}");
            assert_eq!(out.means[i], [src as f32, 0.0, 0.0]);
            if i < 100 && i % 4 != 0 {
                assert_eq!(src, i, "a live Gaussian was overwritten");
            }
        }
        // moments: relocated slots and added Gaussians start fresh
        assert!(keep.iter().enumerate().filter(|(i, _)| i % 4 == 0 && *i < 100).all(|(_, k)| k.is_none()));
        assert!(keep[100..].iter().all(|k| k.is_none()));
        // stacked copies of a source keep its center opacity: 1 - prod(1 - o') = 0.6
        let mut by_source = std::collections::HashMap::<usize, Vec<usize>>::new();
        for i in 0..out.len() {
            by_source.entry(out.sh[3 * i] as usize).or_default().push(i);
        }
        for (src, members) in by_source {
            if members.len() == 1 {
                assert_eq!(out.opacity_logits[src], scene.opacity_logits[src], "unsampled Gaussian {src} changed");
                assert_eq!(out.log_scales[src], scene.log_scales[src]);
            }
            let t: f64 = members.iter().map(|&i| 1.0 - sigmoid(out.opacity_logits[i])).product();
            assert!((1.0 - t - 0.6).abs() < 1e-5, "source {src}: {} copies give {}", members.len(), 1.0 - t);
        }
    }
}
