//! Identity-feature distillation (the paper's stage 1): a learnable f_i in R^D per Gaussian is
//! splatted with the forward feature pass, a linear classifier Phi(f) = W f + b shared by pixels and
//! Gaussians maps it to Q+1 logits, and
//!
//!   L = L_obj + lambda * L_space
//!   L_obj   = mean over supervised pixels of cross-entropy(softmax(Phi(F(u))), O(u))
//!   L_space = mean over sampled Gaussians i of (1/k) sum over the k nearest neighbours j of
//!             KL(p_i || p_j), p = softmax(Phi(f))
//!
//! is minimized over the features and Phi with Adam, geometry and color frozen (so the feature
//! backward alone runs, and the neighbours are found once with kiddo). One optimization covers all
//! objects. Each Gaussian's label is then argmax_q p_q(f_i).

use super::labels::{LabelMaps, IGNORE};
use crate::gpu::{dispatch_1d, Buffer, ComputePipeline, Gpu, Recorder};
use crate::render::backward::{Backward, PixelGradients, SceneGradients};
use crate::render::{Rasterizer, RenderSettings, SceneBuffers};
use crate::rng::Rng;
use crate::scene::{Camera, GaussianScene};
use crate::shaders;
use crate::train::adam::{Adam, Moments};
use anyhow::{bail, Result};
use bytemuck::{Pod, Zeroable};
use rayon::prelude::*;

/// Limits of the classifier shaders (shaders/glsl/tag/classifier.glsl).
pub const MAX_DIM: usize = 32;
pub const MAX_CLASSES: usize = 32;

/// Phi(f) = W f + b.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Classifier {
    pub dim: usize,
    pub classes: usize,
    /// classes x dim, row-major.
    pub weights: Vec<f32>,
    pub bias: Vec<f32>,
}

impl Classifier {
    /// The GPU layout: W then b.
    pub fn packed(&self) -> Vec<f32> {
        [self.weights.as_slice(), self.bias.as_slice()].concat()
    }

    pub fn from_packed(dim: usize, classes: usize, v: &[f32]) -> Classifier {
        Classifier { dim, classes, weights: v[..classes * dim].to_vec(), bias: v[classes * dim..].to_vec() }
    }

    /// softmax(W f + b) in f64.
    pub fn probabilities(&self, f: &[f32]) -> Vec<f64> {
        let z: Vec<f64> = (0..self.classes)
            .map(|c| {
                self.bias[c] as f64
                    + (0..self.dim).map(|d| self.weights[c * self.dim + d] as f64 * f[d] as f64).sum::<f64>()
            })
            .collect();
        let m = z.iter().cloned().fold(f64::MIN, f64::max);
        let e: Vec<f64> = z.iter().map(|v| (v - m).exp()).collect();
        let s: f64 = e.iter().sum();
        e.iter().map(|v| v / s).collect()
    }
}

#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct CrossEntropyPush {
    features: u64,
    labels: u64,
    classifier: u64,
    dl_dfeatures: u64,
    grad_classifier: u64,
    loss: u64,
    hw: u32,
    label_offset: u32,
    dim: u32,
    classes: u32,
    weight: f32,
    _pad: u32,
}

#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct KnnKlPush {
    features: u64,
    neighbors: u64,
    classifier: u64,
    grad_features: u64,
    grad_classifier: u64,
    loss: u64,
    n: u32,
    samples: u32,
    k: u32,
    dim: u32,
    classes: u32,
    seed: u32,
    weight: f32,
    _pad: u32,
}

/// Inputs of the cross-entropy pass for one view.
pub struct CrossEntropyArgs<'a> {
    /// The feature render: `dim` planes of `hw`.
    pub features: &'a Buffer,
    /// u32 labels, all views back to back; this view starts at `label_offset`.
    pub labels: &'a Buffer,
    pub label_offset: u32,
    pub hw: u32,
    /// Packed classifier (W then b).
    pub classifier: &'a Buffer,
    /// Out: dL/dF, `dim` planes of `hw`.
    pub dl_dfeatures: &'a Buffer,
    /// Accumulated: dL/dW, dL/db (packed like the classifier).
    pub grad_classifier: &'a Buffer,
    /// Accumulated: the loss, one float.
    pub loss: &'a Buffer,
    /// Scale of every pixel's term (1 / supervised pixel count for a mean).
    pub weight: f32,
}

/// Inputs of the kNN KL pass.
pub struct KnnKlArgs<'a> {
    /// n x dim, row-major.
    pub features: &'a Buffer,
    /// n x k u32 neighbour indices.
    pub neighbors: &'a Buffer,
    pub n: u32,
    pub k: u32,
    /// Gaussians drawn per evaluation (all of them, in order, when >= n).
    pub samples: u32,
    pub seed: u32,
    pub classifier: &'a Buffer,
    pub grad_features: &'a Buffer,
    pub grad_classifier: &'a Buffer,
    pub loss: &'a Buffer,
    /// lambda / (samples k) for lambda times the mean.
    pub weight: f32,
}

/// The two tagging losses with their gradients (tag_cross_entropy.comp, tag_knn_kl.comp).
pub struct TagLosses {
    cross_entropy: ComputePipeline,
    knn_kl: ComputePipeline,
    pub dim: u32,
    pub classes: u32,
}

impl TagLosses {
    /// `force_cas` picks the compare-and-swap variants even where float atomics exist (tests).
    pub fn new(gpu: &Gpu, dim: usize, classes: usize, force_cas: bool) -> Result<TagLosses> {
        if dim == 0 || dim > MAX_DIM {
            bail!("feature dimension {dim} outside 1..={MAX_DIM}");
        }
        if !(2..=MAX_CLASSES).contains(&classes) {
            bail!("{} object labels: 1..={} are supported", classes as i64 - 1, MAX_CLASSES - 1);
        }
        let cas = force_cas || !gpu.info().float_atomic_add;
        let (ce, kl) = if cas {
            (shaders::TAG_CROSS_ENTROPY_CAS, shaders::TAG_KNN_KL_CAS)
        } else {
            (shaders::TAG_CROSS_ENTROPY, shaders::TAG_KNN_KL)
        };
        Ok(TagLosses {
            cross_entropy: ComputePipeline::new(gpu, "tag_cross_entropy", ce)?,
            knn_kl: ComputePipeline::new(gpu, "tag_knn_kl", kl)?,
            dim: dim as u32,
            classes: classes as u32,
        })
    }

    pub fn record_cross_entropy(&self, rec: &mut Recorder, a: &CrossEntropyArgs) {
        let push = CrossEntropyPush {
            features: a.features.address(),
            labels: a.labels.address(),
            classifier: a.classifier.address(),
            dl_dfeatures: a.dl_dfeatures.address(),
            grad_classifier: a.grad_classifier.address(),
            loss: a.loss.address(),
            hw: a.hw,
            label_offset: a.label_offset,
            dim: self.dim,
            classes: self.classes,
            weight: a.weight,
            _pad: 0,
        };
        rec.dispatch(&self.cross_entropy, &push, dispatch_1d(a.hw.div_ceil(256)));
    }

    pub fn record_knn_kl(&self, rec: &mut Recorder, a: &KnnKlArgs) {
        let push = KnnKlPush {
            features: a.features.address(),
            neighbors: a.neighbors.address(),
            classifier: a.classifier.address(),
            grad_features: a.grad_features.address(),
            grad_classifier: a.grad_classifier.address(),
            loss: a.loss.address(),
            n: a.n,
            samples: a.samples,
            k: a.k,
            dim: self.dim,
            classes: self.classes,
            seed: a.seed,
            weight: a.weight,
            _pad: 0,
        };
        rec.dispatch(&self.knn_kl, &push, dispatch_1d(a.samples.div_ceil(64)));
    }
}

/// The `k` nearest other Gaussians of every Gaussian (by mean), n x k row-major, nearest first.
pub fn nearest_neighbors(means: &[[f32; 3]], k: usize) -> Result<Vec<u32>> {
    use kiddo::{KdTree, SquaredEuclidean};
    if means.len() <= k {
        bail!("{} Gaussians: need more than k = {k} for neighbour queries", means.len());
    }
    let mut tree: KdTree<f64, 3> = KdTree::with_capacity(means.len());
    for (i, m) in means.iter().enumerate() {
        tree.add(&m.map(|v| v as f64), i as u64);
    }
    let rows: Vec<Vec<u32>> = means
        .par_iter()
        .enumerate()
        .map(|(i, m)| {
            let found = tree.nearest_n::<SquaredEuclidean>(&m.map(|v| v as f64), k + 1);
            // drop the query itself (or one exact duplicate, which is as good a neighbour)
            let mut row: Vec<u32> = found.iter().map(|n| n.item as u32).filter(|&j| j != i as u32).collect();
            row.truncate(k);
            row
        })
        .collect();
    Ok(rows.concat())
}

/// Distillation settings: the one home of their defaults, also `cogeo tag`'s flags.
#[derive(Clone, Debug, clap::Args)]
pub struct DistillConfig {
    /// Identity feature dimension D (1..32).
    #[arg(long, default_value_t = 16)]
    pub dim: usize,
    /// Distillation iterations (one training view each).
    #[arg(long, default_value_t = 1000)]
    pub iters: u32,
    /// Weight lambda of the kNN KL spatial loss (0 disables it).
    #[arg(long, default_value_t = 0.1)]
    pub lambda: f32,
    /// Neighbours k of the spatial loss.
    #[arg(long, default_value_t = 5)]
    pub knn: usize,
    /// Gaussians sampled per iteration for L_space.
    #[arg(skip = 4096u32)]
    pub samples: u32,
    #[arg(skip = 0.01)]
    pub lr_features: f32,
    #[arg(skip = 0.005)]
    pub lr_classifier: f32,
    /// Random seed (feature and classifier initialization, view order, KL samples).
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
}

crate::default_from_flags!(DistillConfig);

pub struct Distilled {
    /// n x dim, row-major.
    pub features: Vec<f32>,
    pub classifier: Classifier,
    /// (L_obj, L_space) of the last iteration.
    pub final_losses: (f32, f32),
}

/// Runs the distillation over the views `cameras` with label maps `labels.maps` (same order).
/// `progress(iteration, losses)` is called after every iteration (losses every 25).
pub fn distill(
    gpu: &Gpu,
    scene: &GaussianScene,
    cameras: &[Camera],
    labels: &LabelMaps,
    cfg: &DistillConfig,
    mut progress: impl FnMut(u32, Option<(f32, f32)>),
) -> Result<Distilled> {
    let n = scene.len();
    let (dim, classes) = (cfg.dim, labels.classes());
    let losses = TagLosses::new(gpu, dim, classes, false)?;
    if cameras.is_empty() || cameras.len() != labels.maps.len() {
        bail!("distillation needs one label map per view ({} views, {} maps)", cameras.len(), labels.maps.len());
    }
    let mut rng = Rng::new(cfg.seed);
    let init: Vec<f32> = (0..n * dim).map(|_| (0.1 * rng.normal()) as f32).collect();
    let buffers = SceneBuffers::upload(gpu, scene, Some((&init, dim)))?;
    let features = buffers.features.as_ref().unwrap();
    let grads = SceneGradients::for_features(gpu, &buffers)?;
    let grad_features = grads.features.as_ref().unwrap();
    let neighbors = Buffer::from_slice(gpu, "knn neighbours", &nearest_neighbors(&scene.means, cfg.knn)?)?;

    let w0: Vec<f32> = (0..classes * dim).map(|_| (rng.normal() / (dim as f64).sqrt()) as f32).collect();
    let classifier = Classifier { dim, classes, weights: w0, bias: vec![0.0; classes] };
    let phi = Buffer::from_slice(gpu, "classifier", &classifier.packed())?;
    let grad_phi = Buffer::zeroed(gpu, "classifier gradient", phi.size())?;
    let phi_moments = Moments::new(gpu, "classifier", (classes * (dim + 1)) as u32)?;
    let feature_moments = Moments::new(gpu, "features", (n * dim) as u32)?;
    let loss_obj = Buffer::zeroed(gpu, "L_obj", 4)?;
    let loss_space = Buffer::zeroed(gpu, "L_space", 4)?;

    let mut all_labels: Vec<u32> = Vec::new();
    let mut offsets = Vec::new();
    let mut weights = Vec::new();
    for map in &labels.maps {
        offsets.push(all_labels.len() as u32);
        let supervised = map.iter().filter(|&&v| v != IGNORE && (v as usize) < classes).count();
        weights.push(if supervised > 0 { 1.0 / supervised as f32 } else { 0.0 });
        all_labels.extend(map.iter().map(|&v| if (v as usize) < classes { v as u32 } else { IGNORE as u32 }));
    }
    let label_buf = Buffer::from_slice(gpu, "label maps", &all_labels)?;
    let max_hw = cameras.iter().map(|c| c.width * c.height).max().unwrap();
    let dl_dfeatures = Buffer::zeroed(gpu, "dL/dF", (max_hw as usize * dim * 4) as u64)?;

    let mut raster = Rasterizer::new(gpu)?;
    let mut backward = Backward::new(gpu, false)?;
    let adam = Adam::new(gpu)?;
    let settings = RenderSettings { features: true, sh_degree: Some(0), ..Default::default() };
    let mut order: Vec<usize> = Vec::new();
    let mut last = (f32::NAN, f32::NAN);
    for it in 1..=cfg.iters {
        if order.is_empty() {
            order = (0..cameras.len()).collect();
            for i in (1..order.len()).rev() {
                order.swap(i, (rng.next_u64() % (i as u64 + 1)) as usize);
            }
        }
        let v = order.pop().unwrap();
        let cam = &cameras[v];
        let hw = cam.width * cam.height;
        let frame = raster.forward(&buffers, cam, &settings)?;
        let out = raster.outputs().unwrap();
        let mut rec = Recorder::new(gpu)?;
        rec.fill(grad_features, 0, grad_features.size(), 0);
        rec.fill(&grad_phi, 0, grad_phi.size(), 0);
        rec.fill(&loss_obj, 0, 4, 0);
        rec.fill(&loss_space, 0, 4, 0);
        losses.record_cross_entropy(
            &mut rec,
            &CrossEntropyArgs {
                features: out.features,
                labels: &label_buf,
                label_offset: offsets[v],
                hw,
                classifier: &phi,
                dl_dfeatures: &dl_dfeatures,
                grad_classifier: &grad_phi,
                loss: &loss_obj,
                weight: weights[v],
            },
        );
        let upstream = PixelGradients {
            rgb: &dl_dfeatures, // not read: the features-only backward uses `features` alone
            alpha: None,
            depth: None,
            expected_depth: None,
            features: Some(&dl_dfeatures),
        };
        backward.record(&mut rec, raster.params_buffer(), &frame.params, &upstream, &grads, true)?;
        if cfg.lambda > 0.0 {
            let samples = cfg.samples.min(n as u32);
            losses.record_knn_kl(
                &mut rec,
                &KnnKlArgs {
                    features,
                    neighbors: &neighbors,
                    n: n as u32,
                    k: cfg.knn as u32,
                    samples,
                    seed: (cfg.seed as u32) ^ it.wrapping_mul(0x9e37_79b9),
                    classifier: &phi,
                    grad_features,
                    grad_classifier: &grad_phi,
                    loss: &loss_space,
                    weight: cfg.lambda / (samples as f32 * cfg.knn as f32),
                },
            );
        }
        adam.record(&mut rec, features, grad_features, &feature_moments, cfg.lr_features, it);
        adam.record(&mut rec, &phi, &grad_phi, &phi_moments, cfg.lr_classifier, it);
        rec.submit_and_wait()?;
        let read = it % 25 == 0 || it == cfg.iters;
        if read {
            let o: Vec<f32> = loss_obj.download(gpu, 1)?;
            let s: Vec<f32> = loss_space.download(gpu, 1)?;
            last = (o[0], s[0]);
        }
        progress(it, read.then_some(last));
    }
    let features_host = features.download(gpu, n * dim)?;
    let classifier = Classifier::from_packed(dim, classes, &phi.download(gpu, classes * (dim + 1))?);
    Ok(Distilled { features: features_host, classifier, final_losses: last })
}

/// Each Gaussian's label and its probability under the classifier.
pub fn classify(features: &[f32], classifier: &Classifier) -> (Vec<u8>, Vec<f32>) {
    features
        .par_chunks(classifier.dim)
        .map(|f| {
            let p = classifier.probabilities(f);
            let (q, best) = p.iter().enumerate().fold((0, -1.0), |a, (q, &v)| if v > a.1 { (q, v) } else { a });
            (q as u8, best as f32)
        })
        .unzip()
}
