//! Concept-aware tagging (the paper's stage 1): every Gaussian gets an object label 0..Q
//! (0 = background) consistent across views, so any subset of objects can be selected at once.
//!
//! Three methods, one output (a label and its probability per Gaussian):
//! - `distill`: identity features + classifier + cross-entropy + kNN KL (distill.rs);
//! - `vote`: closed form: each Gaussian's blending weight summed per label over all views in one
//!   feature-backward pass per view, then argmax with a background margin (`vote`);
//! - `project`: the naive 2D baseline: a Gaussian takes the label its projected center falls on, in
//!   any view (`project`).

pub mod distill;
pub mod labels;
pub mod prompt;

use crate::gpu::{Buffer, Gpu, Recorder};
use crate::render::backward::{Backward, PixelGradients, SceneGradients};
use crate::render::{Rasterizer, RenderSettings, SceneBuffers, SceneRenderer};
use crate::scene::{Camera, ExtraProperty, GaussianScene, PlyType};
use anyhow::{bail, Result};
use labels::{LabelMaps, IGNORE};

#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, clap::ValueEnum, serde::Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Method {
    /// Feature distillation with a classifier (cross-entropy + kNN KL consistency).
    #[default]
    Distill,
    /// Closed-form voting of blending weights per label.
    Vote,
    /// Naive baseline: the label under each Gaussian's projected center in any view.
    Project,
}

/// Per-Gaussian labels.
#[derive(Clone, Debug)]
pub struct Tags {
    pub labels: Vec<u8>,
    /// Probability (distill), vote share (vote) or share of views (project) of the label.
    pub probability: Vec<f32>,
}

/// The one-hot planes of a label map (IGNORE pixels get all zeros).
fn one_hot(map: &[u8], classes: usize) -> Vec<f32> {
    let hw = map.len();
    let mut out = vec![0f32; classes * hw];
    for (u, &l) in map.iter().enumerate() {
        if (l as usize) < classes {
            out[l as usize * hw + u] = 1.0;
        }
    }
    out
}

/// Sum over views and pixels of each Gaussian's blending weight w_i(u), split by the label O(u):
/// votes[i * classes + q]. One forward + one feature-backward per view: with dL/dF(u) = onehot(O(u))
/// the feature backward's dL/df_i is exactly that sum.
pub fn vote_weights(gpu: &Gpu, scene: &GaussianScene, cameras: &[Camera], labels: &LabelMaps) -> Result<Vec<f32>> {
    let (n, classes) = (scene.len(), labels.classes());
    let zeros = vec![0f32; n * classes];
    let buffers = SceneBuffers::upload(gpu, scene, Some((&zeros, classes)))?;
    let grads = SceneGradients::for_features(gpu, &buffers)?;
    let mut raster = Rasterizer::new(gpu)?;
    let mut backward = Backward::new(gpu, false)?;
    let settings = RenderSettings { features: true, sh_degree: Some(0), ..Default::default() };
    let max_hw = cameras.iter().map(|c| c.width * c.height).max().unwrap_or(1) as usize;
    let upstream = Buffer::zeroed(gpu, "one-hot labels", (classes * max_hw * 4) as u64)?;
    for (cam, map) in cameras.iter().zip(&labels.maps) {
        upstream.upload(gpu, &one_hot(map, classes))?;
        let frame = raster.forward(&buffers, cam, &settings)?;
        let mut rec = Recorder::new(gpu)?;
        let px = PixelGradients {
            rgb: &upstream,
            alpha: None,
            depth: None,
            expected_depth: None,
            features: Some(&upstream),
        };
        backward.record(&mut rec, raster.params_buffer(), &frame.params, &px, &grads, true)?;
        rec.submit_and_wait()?;
    }
    grads.features.as_ref().unwrap().download(gpu, n * classes)
}

/// Labels from votes: the share p_q = votes_q / sum(votes); an object label q needs
/// p_q >= p_0 + margin (ties and near-ties go to the background), the largest such q wins. A Gaussian
/// no view sees gets background with probability 0.
pub fn labels_from_votes(votes: &[f32], classes: usize, margin: f32) -> Tags {
    let mut tags = Tags { labels: Vec::new(), probability: Vec::new() };
    for v in votes.chunks(classes) {
        let total: f64 = v.iter().map(|&x| x.max(0.0) as f64).sum();
        if total <= 0.0 {
            tags.labels.push(0);
            tags.probability.push(0.0);
            continue;
        }
        let p: Vec<f64> = v.iter().map(|&x| x.max(0.0) as f64 / total).collect();
        let (best, pb) = p.iter().enumerate().skip(1).fold((0, -1.0), |a, (q, &x)| if x > a.1 { (q, x) } else { a });
        if best != 0 && pb >= p[0] + margin as f64 {
            tags.labels.push(best as u8);
            tags.probability.push(pb as f32);
        } else {
            tags.labels.push(0);
            tags.probability.push(p[0] as f32);
        }
    }
    tags
}

/// The naive baseline: each Gaussian whose center projects inside an image (in front of the camera)
/// reads the label there; an object label seen in any view wins over background (the most frequent
/// object label if several). Probability = the share of those views that saw the chosen label.
pub fn project_labels(scene: &GaussianScene, cameras: &[Camera], labels: &LabelMaps) -> Tags {
    use rayon::prelude::*;
    let classes = labels.classes();
    let (labels_out, probability) = scene
        .means
        .par_iter()
        .map(|m| {
            let mut hits = vec![0u32; classes];
            let mut seen = 0u32;
            for (cam, map) in cameras.iter().zip(&labels.maps) {
                let p = cam.to_camera(m.map(|v| v as f64));
                if p[2] <= 0.01 {
                    continue;
                }
                let x = cam.fx * p[0] / p[2] + cam.cx;
                let y = cam.fy * p[1] / p[2] + cam.cy;
                if x < 0.0 || y < 0.0 || x >= cam.width as f64 || y >= cam.height as f64 {
                    continue;
                }
                let l = map[y as usize * cam.width as usize + x as usize];
                if (l as usize) < classes && l != IGNORE {
                    hits[l as usize] += 1;
                    seen += 1;
                }
            }
            let (best, count) =
                hits.iter().enumerate().skip(1).fold((0, 0), |a, (q, &c)| if c > a.1 { (q, c) } else { a });
            match (best, seen) {
                (_, 0) => (0u8, 0f32),
                (0, _) => (0, 1.0),
                (q, s) => (q as u8, count as f32 / s as f32),
            }
        })
        .unzip();
    Tags { labels: labels_out, probability }
}

/// Renders label maps: the one-hot of each Gaussian's label is splatted like a feature and every
/// pixel takes the label of largest weight, the uncovered remainder (final transmittance) counting
/// as background.
pub struct LabelRenderer {
    renderer: SceneRenderer,
    classes: usize,
}

impl LabelRenderer {
    pub fn new(gpu: &Gpu, scene: &GaussianScene, labels: &[u8]) -> Result<LabelRenderer> {
        if labels.len() != scene.len() {
            bail!("{} labels for {} Gaussians", labels.len(), scene.len());
        }
        let classes = labels.iter().copied().max().unwrap_or(0) as usize + 1;
        let mut features = vec![0f32; scene.len() * classes];
        for (i, &l) in labels.iter().enumerate() {
            features[i * classes + l as usize] = 1.0;
        }
        Ok(LabelRenderer { renderer: SceneRenderer::new(gpu, scene, Some((&features, classes)))?, classes })
    }

    pub fn render(&mut self, camera: &Camera) -> Result<Vec<u8>> {
        let settings = RenderSettings { features: true, sh_degree: Some(0), ..Default::default() };
        let out = self.renderer.render(camera, &settings)?;
        let hw = (out.width * out.height) as usize;
        Ok((0..hw)
            .map(|u| {
                let mut best = (0u8, out.final_t[u] + out.features[u]);
                for q in 1..self.classes {
                    let w = out.features[q * hw + u];
                    if w > best.1 {
                        best = (q as u8, w);
                    }
                }
                best.0
            })
            .collect())
    }
}

/// Writes `labels` (and optionally identity features) into the scene's extra properties
/// `f_obj_0..`, `label`, `label_prob`, replacing earlier ones.
pub fn attach(scene: &mut GaussianScene, tags: &Tags, features: Option<(&[f32], usize)>) {
    scene.extras.retain(|e| !(e.name.starts_with("f_obj_") || e.name == "label" || e.name == "label_prob"));
    if let Some((f, d)) = features {
        for c in 0..d {
            let values = f.chunks(d).map(|row| row[c] as f64).collect();
            scene.extras.push(ExtraProperty { name: format!("f_obj_{c}"), ty: PlyType::F32, values });
        }
    }
    scene.extras.push(ExtraProperty {
        name: "label".into(),
        ty: PlyType::U8,
        values: tags.labels.iter().map(|&l| l as f64).collect(),
    });
    scene.extras.push(ExtraProperty {
        name: "label_prob".into(),
        ty: PlyType::F32,
        values: tags.probability.iter().map(|&p| p as f64).collect(),
    });
}

/// The `label` property of a tagged scene.
pub fn scene_labels(scene: &GaussianScene) -> Option<Vec<u8>> {
    let p = scene.extras.iter().find(|e| e.name == "label")?;
    Some(p.values.iter().map(|&v| v.clamp(0.0, 255.0) as u8).collect())
}

/// How to tag: the one home of the tagging defaults, also `cogeo tag`'s flags.
#[derive(Clone, Debug, clap::Args)]
pub struct TagOptions {
    /// distill: identity features + classifier (cross-entropy + kNN KL); vote: closed-form blending
    /// weight vote; project: label under each Gaussian's projected center (naive baseline).
    #[arg(long, value_enum, default_value_t)]
    pub method: Method,
    #[command(flatten)]
    pub distill: distill::DistillConfig,
    /// Vote: an object label needs a vote share at least this much above the background's
    /// (see `labels_from_votes`).
    #[arg(long, default_value_t = 0.0)]
    pub margin: f32,
}

crate::default_from_flags!(TagOptions);

pub struct Tagged {
    pub tags: Tags,
    /// n x dim identity features (distill only).
    pub features: Option<(Vec<f32>, usize)>,
    pub classifier: Option<distill::Classifier>,
    /// (L_obj, L_space) at the end (distill only).
    pub losses: Option<(f32, f32)>,
}

/// Tags `scene` from the label maps of `cameras` (same order as `labels.maps`).
pub fn tag_scene(
    gpu: &Gpu,
    scene: &GaussianScene,
    cameras: &[Camera],
    labels: &LabelMaps,
    opts: &TagOptions,
    progress: impl FnMut(u32, Option<(f32, f32)>),
) -> Result<Tagged> {
    if labels.num_objects == 0 {
        bail!("the masks contain no object (every pixel is 0)");
    }
    Ok(match opts.method {
        Method::Distill => {
            let d = distill::distill(gpu, scene, cameras, labels, &opts.distill, progress)?;
            let (l, p) = distill::classify(&d.features, &d.classifier);
            Tagged {
                tags: Tags { labels: l, probability: p },
                features: Some((d.features, opts.distill.dim)),
                classifier: Some(d.classifier),
                losses: Some(d.final_losses),
            }
        }
        Method::Vote => {
            let votes = vote_weights(gpu, scene, cameras, labels)?;
            Tagged {
                tags: labels_from_votes(&votes, labels.classes(), opts.margin),
                features: None,
                classifier: None,
                losses: None,
            }
        }
        Method::Project => {
            Tagged { tags: project_labels(scene, cameras, labels), features: None, classifier: None, losses: None }
        }
    })
}

/// Renders the label maps of `cameras` and compares them with `truth`: IoU per class and the mean.
pub fn evaluate_labels(
    gpu: &Gpu,
    scene: &GaussianScene,
    labels: &[u8],
    cameras: &[Camera],
    truth: &LabelMaps,
) -> Result<(Vec<Option<f64>>, f64)> {
    let mut renderer = LabelRenderer::new(gpu, scene, labels)?;
    let pred: Vec<Vec<u8>> = cameras.iter().map(|c| renderer.render(c)).collect::<Result<_>>()?;
    Ok(labels::iou(&pred, &truth.maps, truth.classes()))
}
