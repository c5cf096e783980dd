//! Argument groups and helpers shared by several subcommands: the device, the capture's
//! resolution, colors, progress bars, scene loading.

use anyhow::Result;
use clap::Args;
use cogeo::gpu::{DeviceChoice, Gpu};
use cogeo::scene::{ply, GaussianScene};
use indicatif::{ProgressBar, ProgressStyle};
use std::path::Path;

#[derive(Args, Clone)]
pub struct DeviceArgs {
    /// Vulkan device to use: index or case-insensitive name substring (see `cogeo devices`).
    /// Default: COGEO_DEVICE, else the first discrete GPU, then integrated, then CPU (lavapipe).
    #[arg(long, global = true)]
    pub device: Option<String>,
}

/// Resolution at which a capture is used (train, tag, remove and run share it).
#[derive(Args, Clone, Copy)]
pub struct ScaleArgs {
    /// Box-filter every image by N x N pixels on load (intrinsics follow; masks are resized to the
    /// result): train, tag and edit a capture at 1/N resolution without writing a copy. Use the same
    /// value for train, tag and remove.
    #[arg(long, default_value_t = 1, value_parser = clap::value_parser!(u32).range(1..=16))]
    pub downscale: u32,
}

pub use cogeo::flag_values::parse_rgb;

pub fn progress(len: usize, what: &str) -> ProgressBar {
    let bar = ProgressBar::new(len as u64);
    bar.set_style(
        ProgressStyle::with_template("{msg:>10} [{bar:40}] {pos}/{len} {elapsed_precise} eta {eta}")
            .unwrap()
            .progress_chars("=> "),
    );
    bar.set_message(what.to_string());
    bar
}

pub fn open_gpu(device: &DeviceArgs) -> Result<Gpu> {
    Gpu::new(&DeviceChoice::from_env(device.device.clone()))
}

pub fn load_scene(path: &Path) -> Result<GaussianScene> {
    let scene = ply::read_ply(path)?;
    scene.validate(&path.display().to_string())?;
    Ok(scene)
}
