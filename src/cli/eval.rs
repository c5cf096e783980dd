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
    /// Floater threshold, relative to the true depth.
    #[arg(long, default_value_t = 0.05)]
    pub tau: f64,
    /// Leftover score margin: a mask pixel counts as leftover when the render is closer to the
    /// image with the objects than to the ground truth by more than this mean RGB difference.
    #[arg(long, default_value_t = 0.05)]
    pub leftover_margin: f32,
    #[command(flatten)]
    pub models: MetricModels,
    /// Output JSON (written atomically).
    #[arg(long, default_value = "metrics.json")]
    pub out: PathBuf,
}

/// The learned-metric networks and how to feed them; defaults fit the published LPIPS (v0.1) and
/// TF-FID Inception-v3 exports, whose input names are read from the model.
#[derive(Args, Clone, Debug)]
pub struct MetricModels {
    /// LPIPS network (ONNX): two image inputs [1,3,H,W], one output value. Reports full-image,
    /// bounding-box and masked LPIPS (masked: the render pasted into the ground truth inside the
    /// mask only, cropped to the mask's box); with --data also never-seen and seen-elsewhere.
    #[arg(long)]
    pub lpips_model: Option<PathBuf>,
    /// The LPIPS inputs' names, e.g. `img0,img1` (default: the model's two inputs, in its order).
    #[arg(long, value_delimiter = ',', num_args = 2)]
    pub lpips_inputs: Option<Vec<String>>,
    /// LPIPS input = scale * rgb + offset, rgb in [0,1] (default 2, -1: the [-1,1] of LPIPS).
    #[arg(long, default_value_t = 2.0, allow_negative_numbers = true)]
    pub lpips_scale: f32,
    #[arg(long, default_value_t = -1.0, allow_negative_numbers = true)]
    pub lpips_offset: f32,
    /// Smallest side the LPIPS network accepts (AlexNet: 32): smaller images are upsampled and
    /// crops grown to it.
    #[arg(long, default_value_t = 32)]
    pub lpips_min_side: usize,
    /// FID feature network (ONNX): one image input [N,3,299,299] (resized bilinearly), output [N,D].
    #[arg(long)]
    pub fid_model: Option<PathBuf>,
    /// The FID input's name (default: the model's only input).
    #[arg(long)]
    pub fid_input: Option<String>,
    /// FID input = scale * rgb + offset, rgb in [0,1] (default 255/128, -1: TF-FID's x/128 - 1).
    #[arg(long, default_value_t = 255.0 / 128.0, allow_negative_numbers = true)]
    pub fid_scale: f32,
    #[arg(long, default_value_t = -1.0, allow_negative_numbers = true)]
    pub fid_offset: f32,
}

impl MetricModels {
    pub fn lpips_input(&self) -> cogeo::eval::models::NetworkInput {
        cogeo::eval::models::NetworkInput {
            names: self.lpips_inputs.clone(),
            scale: self.lpips_scale,
            offset: self.lpips_offset,
        }
    }

    pub fn fid_input(&self) -> cogeo::eval::models::NetworkInput {
        cogeo::eval::models::NetworkInput {
            names: self.fid_input.clone().map(|n| vec![n]),
            scale: self.fid_scale,
            offset: self.fid_offset,
        }
    }
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
        tau: a.tau,
        leftover_margin: a.leftover_margin,
        lpips: a.models.lpips_model.clone(),
        lpips_input: a.models.lpips_input(),
        lpips_min_side: a.models.lpips_min_side,
        fid: a.models.fid_model.clone(),
        fid_input: a.models.fid_input(),
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
