//! `cogeo remove`: the removal pipeline (src/removal) on a tagged scene, with its outputs: edited
//! and held-out views, masks, depth, the edited scene and report.json.

use super::args::{load_scene, open_gpu, parse_rgb, DeviceArgs, ScaleArgs};
use anyhow::{anyhow, bail, Context, Result};
use clap::Args;
use cogeo::io::{write_exr, write_png_rgb};
use cogeo::scene::{ply, Camera};
use indicatif::{ProgressBar, ProgressStyle};
use std::path::{Path, PathBuf};

#[derive(Args, Clone)]
pub struct RemovalFlags {
    /// Labels to remove, comma-separated (as in the tagged scene's `label` property).
    #[arg(long, value_delimiter = ',', required_unless_present = "prompt", value_parser = cogeo::flag_values::parse_object_label)]
    pub labels: Vec<u8>,
    /// Object names to remove, comma-separated, looked up in the tagging sidecar's names
    /// (`<scene>.json` of `cogeo tag`: mask subfolder names, or "object q").
    #[arg(long, value_delimiter = ',')]
    pub prompt: Vec<String>,
    /// The built-in inpainter: exemplar (texture copied patch by patch from around the hole, each
    /// background surface from itself; PatchMatch on the GPU) or harmonic (a smooth membrane fill,
    /// the ablation). Ignored with --inpaint-model or --inpainted.
    #[arg(long, value_enum, default_value = "exemplar")]
    pub inpainter: BuiltInInpainter,
    /// ONNX inpainting model with the LaMa contract (image [1,3,512,512] in [0,1] and mask
    /// [1,1,512,512], 1 = hole, in; RGB out), instead of the built-in inpainter.
    #[arg(long, conflicts_with = "inpainted")]
    pub inpaint_model: Option<PathBuf>,
    /// Bring your own inpainting: a folder of inpainted training views named like the images (the
    /// output of LaMa, Stable Diffusion, an image editor, ...), used as the RGB completion of those
    /// views exactly inside the holes; depth, color transfer, fusion and refinement run unchanged.
    /// Inpaint at least the removed objects' masks, dilated a few pixels (a previous run's `mask/`
    /// shows the region cogeo fills). Views of another size are resized.
    #[arg(long)]
    pub inpainted: Option<PathBuf>,
    /// ONNX monocular depth model (see --depth-contract). Default: the built-in prior (harmonic
    /// completion of the rendered inverse depth from the hole boundary).
    #[arg(long)]
    pub depth_model: Option<PathBuf>,
    /// Contract of --depth-model: depth-anything-v2 (ImageNet-normalized RGB, sides multiples of 14,
    /// affine-invariant disparity out) or depth-anything3 (504x504 in, depth out).
    #[arg(long, value_enum, default_value = "depth-anything-v2")]
    pub depth_contract: cogeo::removal::complete::depth::DepthContract,
    /// ONNX depth-inpainting denoiser run as a masked DDIM loop (inputs sample, timestep, alpha_bar,
    /// image, mask; output the predicted noise). Default: built-in edge-aware refinement.
    #[arg(long)]
    pub depth_refiner: Option<PathBuf>,
    /// Sweeps of the built-in edge-aware depth refinement (0 = keep the anchored depth).
    #[arg(long, default_value_t = 60)]
    pub depth_sweeps: usize,
    /// DDIM steps of --depth-refiner.
    #[arg(long, default_value_t = 20)]
    pub diffusion_steps: usize,
    /// Ablation: no depth prior; new Gaussians are placed at the depth rendered after removal, and
    /// the built-in inpainter fills without the background planes.
    #[arg(long)]
    pub no_depth_guidance: bool,
    /// Keep each hole's completed depth as it is (ablation). By default, before the color
    /// transfer and the fusion, it is corrected by photo-consistency: where two or more other
    /// views saw the hole's surface, the depth at which their photos agree on its color (one
    /// factor per hole, then per pixel within 3 % of it). Runs with --no-transfer too.
    #[arg(long)]
    pub no_photo_depth: bool,
    /// Ablation: no depth-guided color transfer (hole pixels that other views saw keep their render
    /// or are inpainted like the rest instead of taking those views' captured colors).
    #[arg(long)]
    pub no_transfer: bool,
    /// How new Gaussians are made: depth (back-projected completed depth, fused and pruned) or
    /// nearest-copy (baseline: each removed Gaussian replaced by a copy of its nearest remaining one).
    #[arg(long, value_enum, default_value = "depth")]
    pub fill: cogeo::removal::Fill,
    /// Ablation: only delete the Gaussians (no inpainting, no new Gaussians, no refinement).
    #[arg(long)]
    pub removal_only: bool,
    /// Skip the refinement stage.
    #[arg(long)]
    pub no_refine: bool,
    /// Skip pruning of sparse background Gaussians near the patch.
    #[arg(long)]
    pub no_prune: bool,
    /// Refinement iterations (the first half with geometry frozen).
    #[arg(long, default_value_t = 150)]
    pub refine_iters: u32,
    /// Refinement learning rate of the colors (SH coefficients) as a multiple of training's. Adam
    /// moves a coefficient by about its rate per step, so at training's rate the short refinement
    /// cannot recolor the Gaussians left behind the objects.
    #[arg(long, default_value_t = cogeo::removal::refine::COLOR_LR_GAIN)]
    pub refine_color_lr_gain: f32,
    /// Refinement learning rate of the Gaussians' scales and rotations as a multiple of
    /// training's: in the short second half the patch's footprint-sized ellipses must take the
    /// shape of the surface's texture, not just settle.
    #[arg(long, default_value_t = cogeo::removal::refine::SHAPE_LR_GAIN)]
    pub refine_shape_lr_gain: f32,
    /// Refinement loss weight of each view's hole pixels relative to its other pixels (>= 0).
    /// Outside the hole the target is the scene's own render, which only anchors the background;
    /// the hole is a tenth or so of a view and carries the colors the other views captured.
    #[arg(long, default_value_t = cogeo::removal::refine::HOLE_WEIGHT, value_parser = cogeo::flag_values::parse_weight, allow_negative_numbers = true)]
    pub refine_hole_weight: f32,
    /// Trust region of the second half: each Gaussian's per-step update of its position, of its
    /// log-scales and of its rotation is clipped to this Euclidean norm.
    #[arg(long, default_value_t = 0.01)]
    pub trust_radius: f32,
    /// A pixel is in the hole when the removed Gaussians carry more than this share of its weight.
    #[arg(long, default_value_t = 0.3)]
    pub hole_threshold: f32,
    /// Hole dilation in pixels.
    #[arg(long, default_value_t = 2.0)]
    pub dilate: f32,
    /// Hole pixels that a kept object (a remaining Gaussian with a nonzero label) covers with at
    /// least this alpha keep their render, unless it lies 1.25x behind the surfaces around the
    /// hole; 1 fills the whole hole. The background Gaussians left behind the removed objects never
    /// keep a pixel: it is filled (photo colors where other views saw it) and gets new Gaussians.
    #[arg(long, default_value_t = 0.9)]
    pub keep_alpha: f32,
    /// Feathering radius (pixels) of the soft mask that blends aligned prior and rendered depth.
    #[arg(long, default_value_t = 4.0)]
    pub soft_radius: f32,
    /// Sample every Nth hole pixel in x and y for new Gaussians.
    #[arg(long, default_value_t = 1)]
    pub stride: usize,
    /// Make each new Gaussian a sphere of its pixel's size (the earlier patch, for ablation) instead
    /// of a flat ellipse on the completed surface covering the pixel's footprint there.
    #[arg(long)]
    pub round_patch: bool,
    /// Pruning: distance to the nearest patch Gaussian that makes a background Gaussian a candidate
    /// (scene units; default twice the patch spacing).
    #[arg(long)]
    pub prune_near: Option<f64>,
    /// Pruning: neighbourhood radius of the density test (default three times the patch spacing).
    #[arg(long)]
    pub prune_radius: Option<f64>,
    /// Pruning: candidates with fewer background neighbours within the radius are pruned.
    #[arg(long, default_value_t = 4)]
    pub prune_min_neighbours: usize,
    /// Background color r,g,b in [0, 1] (the one the scene was trained with).
    #[arg(long, default_value = "0,0,0", value_parser = parse_rgb)]
    pub background: [f32; 3],
    /// Random seed (refinement view order, diffusion noise).
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
}

#[derive(Args)]
pub struct RemoveArgs {
    /// Tagged scene (`cogeo tag` output, with a `label` property). Not modified.
    #[arg(long)]
    pub scene: PathBuf,
    /// Dataset folder the scene was trained from: its training views are edited, its held-out views
    /// rendered (and scored against gt_background/ when it is a `cogeo synth` dataset).
    #[arg(long)]
    pub data: PathBuf,
    /// Image folder inside --data.
    #[arg(long, default_value = "images")]
    pub images: String,
    #[command(flatten)]
    pub scale: ScaleArgs,
    /// Output folder: scene.ply, report.json, before/ after/ removed/ inpainted/ mask/ depth/.
    #[arg(long)]
    pub out: PathBuf,
    #[command(flatten)]
    pub removal: RemovalFlags,
    #[command(flatten)]
    pub device: DeviceArgs,
}

/// The labels named by --labels and --prompt.
pub fn chosen_labels(flags: &RemovalFlags, scene_path: &Path) -> Result<Vec<u8>> {
    let mut labels = flags.labels.clone();
    if !flags.prompt.is_empty() {
        let sidecar = scene_path.with_extension("json");
        let text = std::fs::read_to_string(&sidecar)
            .with_context(|| format!("{}: --prompt needs the tagging sidecar", sidecar.display()))?;
        let report: serde_json::Value =
            serde_json::from_str(&text).with_context(|| format!("{}: not valid JSON", sidecar.display()))?;
        let names: Vec<String> = report["names"]
            .as_array()
            .map(|a| a.iter().filter_map(|v| v.as_str().map(str::to_lowercase)).collect())
            .unwrap_or_default();
        for p in &flags.prompt {
            let q = names
                .iter()
                .position(|n| *n == p.to_lowercase())
                .ok_or_else(|| anyhow!("{}: no object named {p:?} (names: {names:?})", sidecar.display()))?;
            labels.push(q as u8 + 1);
        }
    }
    if labels.contains(&0) {
        bail!("label 0 is the background and cannot be removed");
    }
    labels.sort();
    labels.dedup();
    Ok(labels)
}

pub fn write_views(dir: &Path, cameras: &[Camera], images: &[Vec<f32>]) -> Result<()> {
    std::fs::create_dir_all(dir).with_context(|| format!("{}: cannot create", dir.display()))?;
    for (c, img) in cameras.iter().zip(images) {
        write_png_rgb(&dir.join(format!("{}.png", c.name)), c.width, c.height, img)?;
    }
    Ok(())
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum BuiltInInpainter {
    Exemplar,
    Harmonic,
}

pub fn run(a: RemoveArgs) -> Result<()> {
    use cogeo::removal::complete::{depth::DepthPrior, diffusion::OnnxDenoiser, inpaint::Inpainter, Completer};
    let f = &a.removal;
    let labels = chosen_labels(f, &a.scene)?;
    let scene = load_scene(&a.scene)?;
    let scene_labels = cogeo::tag::scene_labels(&scene).ok_or_else(|| {
        anyhow!("{}: the scene has no `label` property; tag it first with `cogeo tag`", a.scene.display())
    })?;
    let data = cogeo::train::dataset::load(&a.data, &a.images, a.scale.downscale)?;
    // load models before any GPU work so a bad model path fails at once
    let mut completer = Completer {
        inpainter: match (&f.inpaint_model, &f.inpainted) {
            (Some(p), _) => Inpainter::onnx(p)?,
            (None, Some(dir)) => {
                let names: Vec<String> = data.train.iter().map(|v| v.camera.name.clone()).collect();
                let sizes: Vec<(u32, u32)> = data.train.iter().map(|v| (v.camera.width, v.camera.height)).collect();
                Inpainter::provided(dir, &names, &sizes)?
            }
            (None, None) => Inpainter::Harmonic,
        },
        prior: match &f.depth_model {
            Some(p) => DepthPrior::onnx(p, f.depth_contract)?,
            None => DepthPrior::BuiltIn,
        },
        refiner: f.depth_refiner.as_deref().map(OnnxDenoiser::load).transpose()?,
        soft_radius: f.soft_radius,
        refine_sweeps: f.depth_sweeps,
        diffusion_steps: f.diffusion_steps,
        depth_guidance: !f.no_depth_guidance,
        photo_depth: !f.no_photo_depth,
        seed: f.seed,
    };
    let opts = cogeo::removal::RemoveOptions {
        labels: labels.clone(),
        hole_threshold: f.hole_threshold,
        dilate: f.dilate,
        keep_alpha: f.keep_alpha,
        stages: cogeo::removal::Stages {
            complete: !f.removal_only,
            transfer: !f.no_transfer,
            prune: !f.no_prune,
            refine: !f.no_refine,
        },
        fill: f.fill,
        fuse: cogeo::removal::fuse::FuseConfig {
            stride: f.stride.max(1),
            surfels: !f.round_patch,
            ..Default::default()
        },
        prune: match (f.prune_near, f.prune_radius) {
            (None, None) => None,
            (near, radius) => {
                let near = near.or(radius.map(|r| r * 2.0 / 3.0)).unwrap();
                Some(cogeo::removal::fuse::PruneConfig {
                    near,
                    radius: radius.unwrap_or(near * 1.5),
                    min_neighbours: f.prune_min_neighbours,
                })
            }
        },
        refine: cogeo::removal::refine::RefineConfig {
            iters: f.refine_iters,
            trust_radius: f.trust_radius,
            background: f.background,
            seed: f.seed,
            color_lr_gain: f.refine_color_lr_gain,
            shape_lr_gain: f.refine_shape_lr_gain,
            hole_weight: f.refine_hole_weight,
            ..Default::default()
        },
        background: f.background,
    };
    let gpu = open_gpu(&a.device)?;
    if matches!(completer.inpainter, Inpainter::Harmonic) && f.inpainter == BuiltInInpainter::Exemplar {
        let exemplar = cogeo::removal::complete::exemplar::ExemplarFill::new(&gpu, f.seed)?;
        completer.inpainter = Inpainter::Exemplar(Box::new(exemplar));
    }
    let _folder = super::args::OutputFolder::create(&a.out)?;
    eprintln!(
        "removing label(s) {labels:?} from {} Gaussians; editing {} views on {}",
        scene.len(),
        data.train.len(),
        gpu.info().name
    );
    let cameras: Vec<Camera> = data.train.iter().map(|v| v.camera.clone()).collect();
    let bar = ProgressBar::new(0);
    bar.set_style(
        ProgressStyle::with_template("{msg:>9} [{bar:30}] {pos}/{len} {elapsed_precise}")
            .unwrap()
            .progress_chars("=> "),
    );
    let start = std::time::Instant::now();
    let removal = cogeo::removal::remove(
        &gpu,
        &scene,
        &scene_labels,
        &cameras,
        &data.train.iter().map(|v| v.image.clone()).collect::<Vec<_>>(),
        data.extent,
        &opts,
        &mut completer,
        &mut |stage, done, total| {
            bar.set_message(stage.to_string());
            bar.set_length(total as u64);
            bar.set_position(done as u64);
        },
    )?;
    bar.finish_and_clear();
    // outputs: edited views, then held-out views before / after
    let out = &a.out;
    let v = &removal.views;
    let batch = cogeo::io::OutputBatch::begin();
    write_views(&out.join("before"), &cameras, &v.iter().map(|x| x.before.clone()).collect::<Vec<_>>())?;
    write_views(&out.join("after"), &cameras, &v.iter().map(|x| x.after.clone()).collect::<Vec<_>>())?;
    write_views(&out.join("removed"), &cameras, &v.iter().map(|x| x.removed.clone()).collect::<Vec<_>>())?;
    std::fs::create_dir_all(out.join("mask"))?;
    for (c, x) in cameras.iter().zip(v) {
        // hole mask: 255 = synthesized, 128 = hole kept from other views' Gaussians
        let m: Vec<u8> = x
            .hole
            .iter()
            .zip(&x.fill)
            .map(|(&h, &f)| {
                if f {
                    255
                } else if h {
                    128
                } else {
                    0
                }
            })
            .collect();
        cogeo::io::write_png(&out.join(format!("mask/{}.png", c.name)), c.width, c.height, image::ColorType::L8, &m)?;
    }
    if !f.removal_only {
        write_views(&out.join("inpainted"), &cameras, &v.iter().map(|x| x.inpainted.clone()).collect::<Vec<_>>())?;
        std::fs::create_dir_all(out.join("depth"))?;
        for (c, x) in cameras.iter().zip(v) {
            write_exr(&out.join(format!("depth/{}.exr", c.name)), c.width, c.height, &[("Y", &x.depth)])?;
        }
    }
    let test_cams: Vec<Camera> = data.test.iter().map(|v| v.camera.clone()).collect();
    let test_before = cogeo::removal::render_rgb(&gpu, &scene, &test_cams, f.background)?;
    let test_after = cogeo::removal::render_rgb(&gpu, &removal.scene, &test_cams, f.background)?;
    write_views(&out.join("test_before"), &test_cams, &test_before)?;
    write_views(&out.join("test_after"), &test_cams, &test_after)?;
    // synth ground truth is stored at the dataset's resolution; a downscaled run is not scored
    let (synth, depth_error) = if a.scale.downscale == 1 {
        let synth = cogeo::eval::synth_metrics(&a.data, &test_cams, &test_after, &labels)?;
        let depth_error = cogeo::eval::synth_depth_error(
            &a.data,
            &labels,
            &cameras,
            &v.iter().map(|x| x.depth.clone()).collect::<Vec<_>>(),
            &v.iter().map(|x| x.fill.clone()).collect::<Vec<_>>(),
        )?;
        (synth, depth_error)
    } else {
        (None, None)
    };
    ply::write_ply(&removal.scene, &out.join("scene.ply"))?;
    let mut report = removal.report;
    report["scene"] = serde_json::json!(a.scene);
    report["device"] = serde_json::json!(gpu.info().name);
    report["total_seconds"] = serde_json::json!(start.elapsed().as_secs_f64());
    report["peak_rss_mib"] = serde_json::json!(cogeo::io::peak_rss_mib());
    report["held_out_vs_ground_truth"] = serde_json::json!(synth);
    report["fill_depth_vs_ground_truth"] =
        serde_json::json!(depth_error.map(|(rel, rmse)| serde_json::json!({"abs_rel": rel, "rmse": rmse})));
    cogeo::io::write_atomic(&out.join("report.json"), |w| {
        serde_json::to_writer_pretty(&mut *w, &report)?;
        Ok(())
    })?;
    batch.commit()?;
    let bg = report["background_psnr_vs_original"]["mean"].as_f64().unwrap_or(f64::NAN);
    let gt = synth
        .map(|m| format!("; held-out masked PSNR vs ground truth {:.2} dB (SSIM {:.3})", m.masked_psnr, m.masked_ssim))
        .unwrap_or_default();
    eprintln!(
        "done in {:.1} s: {} -> {} Gaussians; background PSNR vs original render {bg:.2} dB{gt}; wrote {}",
        start.elapsed().as_secs_f64(),
        scene.len(),
        removal.scene.len(),
        out.display()
    );
    Ok(())
}
