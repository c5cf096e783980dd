//! `cogeo run`: train, tag and remove in one command.

use super::args::{DeviceArgs, ScaleArgs};
use super::remove::{RemovalFlags, RemoveArgs};
use super::tag::TagArgs;
use super::train::TrainArgs;
use super::{remove, tag, train};
use anyhow::{Context, Result};
use clap::Args;
use std::path::PathBuf;

#[derive(Args)]
pub struct RunArgs {
    /// Dataset folder: COLMAP model and images.
    #[arg(long)]
    pub data: PathBuf,
    /// Masks for tagging (see `cogeo tag --masks`).
    #[arg(long)]
    pub masks: PathBuf,
    /// Image folder inside --data.
    #[arg(long, default_value = "images")]
    pub images: String,
    #[command(flatten)]
    pub scale: ScaleArgs,
    /// Output folder: train/, tagged.ply (+ .json), removal/.
    #[arg(long)]
    pub out: PathBuf,
    /// Training iterations.
    #[arg(long, default_value_t = 30_000)]
    pub iters: u32,
    /// Highest SH degree of training.
    #[arg(long, default_value_t = 3)]
    pub sh_degree: u32,
    /// Tagging method.
    #[arg(long, value_enum, default_value = "distill")]
    pub tag_method: cogeo::tag::Method,
    /// Distillation iterations.
    #[arg(long, default_value_t = 1000)]
    pub tag_iters: u32,
    #[command(flatten)]
    pub removal: RemovalFlags,
    #[command(flatten)]
    pub device: DeviceArgs,
}

pub fn run(a: RunArgs) -> Result<()> {
    std::fs::create_dir_all(&a.out).with_context(|| format!("{}: cannot create output folder", a.out.display()))?;
    let train_dir = a.out.join("train");
    eprintln!("== 1/3 train");
    train::run(TrainArgs {
        data: a.data.clone(),
        out: train_dir.clone(),
        images: a.images.clone(),
        scale: a.scale,
        iters: a.iters,
        resume: false,
        checkpoint_every: 0,
        sh_degree: a.sh_degree,
        no_densify: false,
        strategy: cogeo::train::trainer::Strategy::Adc,
        max_gaussians: 3_000_000,
        densify_until: None,
        background: a.removal.background,
        seed: a.removal.seed,
        device: a.device.clone(),
    })?;
    eprintln!("== 2/3 tag");
    let tagged = a.out.join("tagged.ply");
    tag::run(TagArgs {
        scene: train_dir.join("scene.ply"),
        data: a.data.clone(),
        images: a.images.clone(),
        scale: a.scale,
        masks: Some(a.masks.clone()),
        prompt: Vec::new(),
        detector: None,
        segmenter: None,
        prompt_embeddings: None,
        box_threshold: 0.3,
        method: a.tag_method,
        out: tagged.clone(),
        iters: a.tag_iters,
        dim: 16,
        lambda: 0.1,
        knn: 5,
        margin: 0.0,
        seed: a.removal.seed,
        device: a.device.clone(),
    })?;
    eprintln!("== 3/3 remove");
    remove::run(RemoveArgs {
        scene: tagged,
        data: a.data,
        images: a.images,
        scale: a.scale,
        out: a.out.join("removal"),
        removal: a.removal,
        device: a.device,
    })
}
