//! Label maps from text prompts, through two user-supplied ONNX models: an open-vocabulary
//! detector gives each prompt's best box, a SAM-style box-prompted segmenter turns the box into a
//! mask. cogeo ships no weights and no tokenizer: the prompts' text embeddings come from a JSON
//! file made with the detector's own text encoder.
//!
//! Contracts (all float32):
//! - Detector: inputs `image` [1,3,H,W] RGB in [0,1] (the view's own size) and `text_embeds`
//!   [Q,E] (one row per prompt, in the order given); outputs `boxes` [Q,K,4] (x0, y0, x1, y1
//!   normalized to [0,1]) and `scores` [Q,K] in [0,1].
//! - Segmenter: inputs `image` [1,3,H,W] RGB in [0,1] and `box` [1,4] (x0, y0, x1, y1 in pixels);
//!   output `mask_logits` [1,1,H,W], > 0 = object.
//! - Embeddings: a JSON object `{"prompt": [e_1, ..., e_E], ...}`.
//!
//! Per view, prompt q's best box counts when its score reaches the threshold; its mask pixels get
//! label q, and where masks overlap the prompt with the higher detection score wins.

use super::labels::LabelMaps;
use crate::onnx::{Model, Tensor};
use anyhow::{anyhow, bail, Context, Result};
use std::path::Path;

/// The models that turn text prompts into label maps: the one home of their settings' defaults,
/// also `cogeo tag`'s flags.
#[derive(Clone, Debug, clap::Args)]
pub struct PromptModels {
    /// Open-vocabulary detector (ONNX): inputs image [1,3,H,W] in [0,1] and text_embeds [Q,E];
    /// outputs boxes [Q,K,4] (normalized x0,y0,x1,y1) and scores [Q,K].
    #[arg(long)]
    pub detector: Option<std::path::PathBuf>,
    /// Box-prompted segmenter (ONNX, SAM-style): inputs image [1,3,H,W] in [0,1] and box [1,4]
    /// (pixels x0,y0,x1,y1); output mask_logits [1,1,H,W] (> 0 = object).
    #[arg(long)]
    pub segmenter: Option<std::path::PathBuf>,
    /// JSON object mapping each prompt to its text embedding (from the detector's text encoder).
    #[arg(long)]
    pub prompt_embeddings: Option<std::path::PathBuf>,
    /// A prompt's best box is used when its detection score reaches this.
    #[arg(long, default_value_t = 0.3)]
    pub box_threshold: f32,
}

crate::default_from_flags!(PromptModels);

pub struct PromptSegmenter {
    detector: Model,
    segmenter: Model,
    prompts: Vec<String>,
    embeddings: Tensor,
    pub box_threshold: f32,
}

/// What the detector found for one prompt in one view.
#[derive(Clone, Debug, serde::Serialize)]
pub struct Detection {
    pub score: f32,
    /// Pixels, x0, y0, x1, y1.
    pub bbox: [f32; 4],
    pub pixels: usize,
}

fn output_index(m: &Model, name: &str) -> Result<usize> {
    m.output_names()
        .iter()
        .position(|n| n == name)
        .ok_or_else(|| anyhow!("{}: no output named {name:?} (outputs: {:?})", m.path().display(), m.output_names()))
}

/// The embeddings of `prompts`, in order, from a prompt-embeddings JSON's bytes (an object of
/// prompt -> list of numbers, all of one length): the rows and their length. `what` names the file.
pub fn parse_prompt_embeddings(data: &[u8], what: &str, prompts: &[String]) -> Result<(Vec<f32>, usize)> {
    let table: std::collections::BTreeMap<String, Vec<f32>> = serde_json::from_slice(data)
        .with_context(|| format!("{what}: expected a JSON object of prompt -> list of numbers"))?;
    let mut rows = Vec::new();
    let mut dim = None;
    for p in prompts {
        let e = table.get(p).ok_or_else(|| {
            anyhow!("{what}: no embedding for prompt {p:?} (has: {:?})", table.keys().collect::<Vec<_>>())
        })?;
        if *dim.get_or_insert(e.len()) != e.len() || e.is_empty() {
            bail!("{what}: embeddings of different or zero length");
        }
        if let Some(v) = e.iter().find(|v| !v.is_finite()) {
            bail!("{what}: the embedding of {p:?} holds {v}, not a finite number");
        }
        rows.extend_from_slice(e);
    }
    Ok((rows, dim.unwrap_or(0)))
}

impl PromptSegmenter {
    pub fn load(
        detector: &Path,
        segmenter: &Path,
        embeddings: &Path,
        prompts: &[String],
        box_threshold: f32,
    ) -> Result<Self> {
        if prompts.is_empty() {
            bail!("no prompts");
        }
        let data = std::fs::read(embeddings)
            .with_context(|| format!("{}: cannot read the prompt embeddings", embeddings.display()))?;
        let (data, dim) = parse_prompt_embeddings(&data, &embeddings.display().to_string(), prompts)?;
        let detector = Model::load(detector)?;
        detector.expect("detector", &["image", "text_embeds"], 2)?;
        output_index(&detector, "boxes")?;
        output_index(&detector, "scores")?;
        let segmenter = Model::load(segmenter)?;
        segmenter.expect("segmenter", &["image", "box"], 1)?;
        output_index(&segmenter, "mask_logits")?;
        Ok(PromptSegmenter {
            detector,
            segmenter,
            prompts: prompts.to_vec(),
            embeddings: Tensor::new(vec![prompts.len() as i64, dim as i64], data),
            box_threshold,
        })
    }

    /// The segmenter's file, for reports.
    pub fn segmenter_path(&self) -> String {
        self.segmenter.path().display().to_string()
    }

    /// The label map of one view (planar RGB in [0,1]) and, per prompt, what was detected.
    pub fn label_map(&mut self, rgb: &[f32], w: usize, h: usize) -> Result<(Vec<u8>, Vec<Option<Detection>>)> {
        let q = self.prompts.len();
        let image = Tensor::new(vec![1, 3, h as i64, w as i64], rgb.to_vec());
        let out = self.detector.run(&[("image", &image), ("text_embeds", &self.embeddings)])?;
        let (boxes, scores) =
            (&out[output_index(&self.detector, "boxes")?], &out[output_index(&self.detector, "scores")?]);
        let path = self.detector.path().display().to_string();
        if boxes.shape.len() != 3 || boxes.shape[0] as usize != q || boxes.shape[2] != 4 {
            bail!("{path}: boxes have shape {:?}, the contract is [{q}, K, 4]", boxes.shape);
        }
        let k = boxes.shape[1] as usize;
        if scores.shape != [q as i64, k as i64] {
            bail!("{path}: scores have shape {:?}, the contract is [{q}, {k}]", scores.shape);
        }
        let mut labels = vec![0u8; w * h];
        let mut best = vec![f32::NEG_INFINITY; w * h];
        let mut found = Vec::new();
        for p in 0..q {
            let Some(j) = (0..k)
                .filter(|&j| scores.data[p * k + j] >= self.box_threshold)
                .max_by(|&a, &b| scores.data[p * k + a].total_cmp(&scores.data[p * k + b]))
            else {
                found.push(None);
                continue;
            };
            let score = scores.data[p * k + j];
            let b = &boxes.data[(p * k + j) * 4..(p * k + j) * 4 + 4];
            let bbox = [b[0] * w as f32, b[1] * h as f32, b[2] * w as f32, b[3] * h as f32];
            let bt = Tensor::new(vec![1, 4], bbox.to_vec());
            let seg = self.segmenter.run(&[("image", &image), ("box", &bt)])?;
            let logits = &seg[output_index(&self.segmenter, "mask_logits")?];
            if logits.data.len() != w * h {
                bail!(
                    "{}: mask_logits have shape {:?}, the contract is [1, 1, {h}, {w}]",
                    self.segmenter.path().display(),
                    logits.shape
                );
            }
            let mut pixels = 0;
            for i in (0..w * h).filter(|&i| logits.data[i] > 0.0) {
                pixels += 1;
                if score > best[i] {
                    best[i] = score;
                    labels[i] = p as u8 + 1;
                }
            }
            found.push(Some(Detection { score, bbox, pixels }));
        }
        Ok((labels, found))
    }

    /// Label maps of every view, named by the prompts.
    pub fn label_maps(&mut self, views: &[(&[f32], usize, usize)]) -> Result<(LabelMaps, Vec<Vec<Option<Detection>>>)> {
        let mut maps = Vec::new();
        let mut detections = Vec::new();
        for (rgb, w, h) in views {
            let (m, d) = self.label_map(rgb, *w, *h)?;
            maps.push(m);
            detections.push(d);
        }
        Ok((LabelMaps { num_objects: self.prompts.len(), names: self.prompts.clone(), maps }, detections))
    }
}
