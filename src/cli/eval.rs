//! `cogeo eval`: renders scored against ground truth inside masks.

use anyhow::{bail, Result};
use clap::Args;
use std::path::PathBuf;

#[derive(Args)]
pub struct EvalArgs {
    /// Rendered images (PNG/JPEG); every image here is scored.
    #[arg(long)]
    pub renders: PathBuf,
    /// Ground-truth images with the same names (for synth data: `gt_background/`).
    #[arg(long)]
    pub gt: PathBuf,
    /// 8-bit masks with the same names; a pixel counts when its value is nonzero (or in --labels).
    #[arg(long)]
    pub masks: PathBuf,
    /// Mask values that count, e.g. `1,2` (default: every nonzero value).
    #[arg(long, value_delimiter = ',')]
    pub labels: Vec<u8>,
    /// Region of the headline numbers: mask (mean over mask pixels), bbox (the mask's bounding-box
    /// crop, SPIn-NeRF) or full (whole image). All three are always in the JSON.
    #[arg(long, value_enum, default_value = "mask")]
    pub protocol: cogeo::eval::folder::Protocol,
    /// The `cogeo synth` dataset the renders come from: adds never-seen / seen-elsewhere subsets
    /// (`unseen_mask/`), the leftover-object score (`images/`), and enables --depth and --scene.
    /// When its cameras have a lens, the ground truth, masks and photos stored in the photos' frame
    /// are undistorted like the photos were, to meet renders in the pinhole frame (--depth and
    /// --scene are then not scored: the true depth is not resampled).
    #[arg(long)]
    pub data: Option<PathBuf>,
    /// Rendered depth (camera z) as `<name>.exr`: AbsRel and RMSE inside the mask against the true
    /// depth without the removed objects (`without_<labels>/depth/` where the synth wrote it, else
    /// `depth_background/`; needs --data).
    #[arg(long)]
    pub depth: Option<PathBuf>,
    /// The edited scene (PLY): floater score = opacity-weighted count of Gaussians farther than
    /// --tau from the true surface (the same true depth as --depth: kept objects are surface) in
    /// every view whose mask they project into (needs --data).
    #[arg(long)]
    pub scene: Option<PathBuf>,
    #[command(flatten)]
    pub thresholds: cogeo::eval::folder::SynthThresholds,
    #[command(flatten)]
    pub models: cogeo::eval::models::MetricModels,
    /// Map each render through the affine color map (3x3 and bias) fitted by least squares to its
    /// ground truth on the pixels outside the mask before scoring: for captures whose exposure
    /// changes from view to view, whose held-out views' exposure no scene knows. The JSON's
    /// "exposure" says which.
    #[arg(long)]
    pub fit_exposure: bool,
    /// Output JSON (written atomically).
    #[arg(long, default_value = "metrics.json")]
    pub out: PathBuf,
}

pub fn run(a: EvalArgs) -> Result<()> {
    use cogeo::eval::folder::{evaluate, EvalConfig};
    if (a.depth.is_some() || a.scene.is_some()) && a.data.is_none() {
        bail!("--depth and --scene need --data (the synth dataset with the true background depth)");
    }
    let cfg = EvalConfig {
        renders: a.renders,
        gt: a.gt,
        masks: a.masks,
        labels: a.labels,
        protocol: a.protocol,
        data: a.data,
        depth: a.depth,
        scene: a.scene,
        tau: a.thresholds.tau,
        leftover_margin: a.thresholds.leftover_margin,
        lpips: a.models.lpips_model.clone(),
        lpips_input: a.models.lpips_input(),
        lpips_min_side: a.models.lpips_min_side,
        fid: a.models.fid_model.clone(),
        fid_input: a.models.fid_input(),
        fit_exposure: a.fit_exposure,
    };
    let metrics = evaluate(&cfg)?;
    cogeo::io::write_atomic(&a.out, |w| {
        serde_json::to_writer_pretty(&mut *w, &metrics)?;
        Ok(())
    })?;
    let h = &metrics["headline"];
    eprintln!(
        "{} view(s), {:?} protocol: PSNR {:.2} dB, SSIM {:.4}; wrote {}",
        metrics["views"].as_array().map_or(0, |v| v.len()),
        cfg.protocol,
        h["psnr"].as_f64().unwrap_or(f64::NAN),
        h["ssim"].as_f64().unwrap_or(f64::NAN),
        a.out.display()
    );
    Ok(())
}
