//! `cogeo run`: train, tag and remove in one command, the steps of `cogeo::pipeline`.

use super::args::{CaptureArgs, DeviceArgs};
use super::remove::RemovalFlags;
use super::{dispatch, Cli, Command};
use anyhow::{anyhow, Context, Result};
use clap::{Args, Parser};
use cogeo::pipeline::{self, Capture, Chosen, Layout, Objects};
use cogeo::tag::{distill::DistillConfig, Method};
use cogeo::train::trainer::TrainConfig;
use std::path::PathBuf;

#[derive(Args)]
pub struct RunArgs {
    /// Dataset folder: COLMAP model (or nerfstudio transforms.json) and images.
    #[arg(long)]
    pub data: PathBuf,
    /// Masks for tagging (see `cogeo tag --masks`).
    #[arg(long)]
    pub masks: PathBuf,
    #[command(flatten)]
    pub capture: CaptureArgs,
    /// Output folder: train/, tagged.ply (+ .json), removal/.
    #[arg(long)]
    pub out: PathBuf,
    /// Training iterations.
    #[arg(long, default_value_t = TrainConfig::default().iters)]
    pub iters: u32,
    /// Highest SH degree of training.
    #[arg(long, default_value_t = TrainConfig::default().sh_degree)]
    pub sh_degree: u32,
    /// Training iterations between SH band increases (`cogeo train --sh-band-every`).
    #[arg(long, default_value_t = TrainConfig::default().sh_band_every,
          value_parser = clap::value_parser!(u32).range(1..))]
    pub sh_band_every: u32,
    /// Learn per-view exposure maps in training (`cogeo train --exposure`) and hand them to the
    /// removal (`cogeo remove --exposure`), for photos whose exposure or white balance varies.
    #[arg(long)]
    pub exposure: bool,
    /// Tagging method.
    #[arg(long, value_enum, default_value_t)]
    pub tag_method: Method,
    /// Distillation iterations.
    #[arg(long, default_value_t = DistillConfig::default().iters)]
    pub tag_iters: u32,
    #[command(flatten)]
    pub removal: RemovalFlags,
    #[command(flatten)]
    pub device: DeviceArgs,
}

pub fn run(a: RunArgs) -> Result<()> {
    std::fs::create_dir_all(&a.out).with_context(|| format!("{}: cannot create output folder", a.out.display()))?;
    let layout = Layout { out: &a.out };
    let capture = Capture { data: &a.data, images: Some(&a.capture.images), downscale: Some(a.capture.downscale) };
    let (seed, background) = (a.removal.options.seed.to_string(), a.removal.options.background);
    let background = background.map(|c| c.to_string()).join(",");
    let device = a.device.command_line();
    let mut train = pipeline::train(&capture, &layout.train());
    train.extend(["--iters".into(), a.iters.to_string(), "--sh-degree".into(), a.sh_degree.to_string()]);
    train.extend(["--sh-band-every".into(), a.sh_band_every.to_string()]);
    train.extend(["--checkpoint-every".into(), "0".into(), "--seed".into(), seed.clone()]);
    train.extend(["--background".into(), background]);
    if a.exposure {
        train.push("--exposure".into());
    }
    let masks = a.masks.to_string_lossy().into_owned();
    let method = clap::ValueEnum::to_possible_value(&a.tag_method).expect("every method has a name");
    let objects = Objects::Masks(&masks);
    let mut tag = pipeline::tag(&layout.trained_scene(), &capture, objects, Some(method.get_name()), &layout.tagged());
    tag.extend(["--iters".into(), a.tag_iters.to_string(), "--seed".into(), seed]);
    // the removal's flags are already parsed: the step's own command line names the files, and
    // the user's flags replace its defaults
    let labels = a.removal.labels.iter().map(|l| l.to_string()).collect::<Vec<_>>().join(",");
    let chosen = if a.removal.labels.is_empty() { Chosen::Names(&a.removal.prompt) } else { Chosen::Labels(&labels) };
    let mut remove = pipeline::remove(&layout.tagged(), &capture, chosen, &layout.removal());
    if a.exposure {
        remove.extend(["--exposure".into(), layout.exposure().to_string_lossy().into_owned()]);
    }
    let steps = [("train", train), ("tag", tag), ("remove", remove)];
    for (i, (name, mut args)) in steps.into_iter().enumerate() {
        eprintln!("== {}/3 {name}", i + 1);
        args.extend(device.iter().cloned());
        let cli = Cli::try_parse_from(std::iter::once("cogeo".to_string()).chain(args.iter().cloned()))
            .map_err(|e| anyhow!("internal command line {args:?}: {e}"))?;
        let command = match cli.command {
            Command::Remove(mut r) => {
                r.removal = a.removal.clone();
                Command::Remove(r)
            }
            other => other,
        };
        dispatch(command).with_context(|| format!("step {name}"))?;
    }
    Ok(())
}
