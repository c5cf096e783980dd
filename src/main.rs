//! The `cogeo` command line.

use anyhow::{anyhow, bail, Context, Result};
use clap::{Args, Parser, Subcommand};
use cogeo::gpu::{DeviceChoice, Gpu};
use cogeo::io::{write_exr, write_png_gray, write_png_rgb};
use cogeo::render::{Rasterizer, RenderSettings, SceneBuffers};
use cogeo::scene::{camera, colmap, ply, Camera, GaussianScene};
use indicatif::{ProgressBar, ProgressStyle};
use std::io::IsTerminal;
use std::path::{Path, PathBuf};

#[derive(Parser)]
#[command(
    name = "cogeo",
    version,
    about = "Vulkan-native 3D Gaussian Splatting: render, train, tag and remove objects"
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Args, Clone)]
struct DeviceArgs {
    /// Vulkan device to use: index or case-insensitive name substring (see `cogeo devices`).
    /// Default: COGEO_DEVICE, else the first discrete GPU, then integrated, then CPU (lavapipe).
    #[arg(long, global = true)]
    device: Option<String>,
}

#[derive(Subcommand)]
enum Command {
    /// List Vulkan devices with the limits cogeo cares about.
    Devices,
    /// Render a Gaussian scene (INRIA PLY) from a set of cameras to PNG (and EXR depth).
    Render(RenderArgs),
    /// The main job on built-in data: generate a synthetic multi-object scene, train, tag, remove
    /// 2+ objects, evaluate against the exact ground truth; writes image strips, a contact sheet,
    /// metrics.json and report.md.
    Demo(DemoArgs),
    /// Generate a procedural dataset with exact ground truth for training and removal.
    Synth(SynthArgs),
    /// Train a Gaussian scene from a COLMAP capture (sparse model + images).
    Train(TrainArgs),
    /// Give every Gaussian an object label from per-view masks (identity features, voting, or the
    /// 2D-projection baseline); writes the tagged PLY and a JSON sidecar.
    Tag(TagArgs),
    /// Remove the objects of chosen labels from a tagged scene and complete the background behind
    /// them (hole masks, inpainting, depth completion, fusion, pruning, refinement).
    Remove(RemoveArgs),
    /// The whole path from a capture: train, tag, remove, in one command.
    Run(RunArgs),
    /// Score renders against ground-truth images inside masks (PSNR/SSIM on the mask, its bounding
    /// box and the full image; with a synth dataset also never-seen / seen-elsewhere subsets,
    /// leftover, depth error and floaters; LPIPS and FID through user-supplied ONNX models).
    Eval(EvalArgs),
}

#[derive(Args)]
struct EvalArgs {
    /// Rendered images (PNG/JPEG); every image here is scored.
    #[arg(long)]
    renders: PathBuf,
    /// Ground-truth images with the same names (for synth data: `gt_background/`).
    #[arg(long)]
    gt: PathBuf,
    /// 8-bit masks with the same names; a pixel counts when its value is nonzero (or in --labels).
    #[arg(long)]
    masks: PathBuf,
    /// Mask values that count, e.g. `1,2` (default: every nonzero value).
    #[arg(long, value_delimiter = ',')]
    labels: Vec<u8>,
    /// Region of the headline numbers: mask (mean over mask pixels), bbox (the mask's bounding-box
    /// crop, SPIn-NeRF) or full (whole image). All three are always in the JSON.
    #[arg(long, value_enum, default_value = "mask")]
    protocol: cogeo::eval::folder::Protocol,
    /// The `cogeo synth` dataset the renders come from: adds never-seen / seen-elsewhere subsets
    /// (`unseen_mask/`), the leftover-object score (`images/`), and enables --depth and --scene.
    #[arg(long)]
    data: Option<PathBuf>,
    /// Rendered depth (camera z) as `<name>.exr`: AbsRel and RMSE inside the mask against
    /// `depth_background/` (needs --data).
    #[arg(long)]
    depth: Option<PathBuf>,
    /// The edited scene (PLY): floater score = opacity-weighted count of Gaussians farther than
    /// --tau from the true surface in every view whose mask they project into (needs --data).
    #[arg(long)]
    scene: Option<PathBuf>,
    /// Floater threshold, relative to the true depth.
    #[arg(long, default_value_t = 0.05)]
    tau: f64,
    /// Leftover score margin: a mask pixel counts as leftover when the render is closer to the
    /// image with the objects than to the ground truth by more than this mean RGB difference.
    #[arg(long, default_value_t = 0.05)]
    leftover_margin: f32,
    /// LPIPS network (ONNX; inputs in0, in1 [1,3,H,W] in [-1,1]; one output value).
    #[arg(long)]
    lpips_model: Option<PathBuf>,
    /// FID feature network (ONNX; input images [N,3,299,299] in [0,1]; output [N,D]).
    #[arg(long)]
    fid_model: Option<PathBuf>,
    /// Output JSON (written atomically).
    #[arg(long, default_value = "metrics.json")]
    out: PathBuf,
}

#[derive(Args)]
struct RenderArgs {
    /// Gaussian scene in the INRIA PLY layout.
    #[arg(long, required_unless_present = "builtin", conflicts_with = "builtin")]
    scene: Option<PathBuf>,
    /// Render the built-in procedural scene (about 60k Gaussians) from an orbit of --views
    /// cameras instead of a PLY (writes scene.ply and cameras.json beside the renders).
    #[arg(long)]
    builtin: bool,
    /// Number of orbit views for --builtin.
    #[arg(long, default_value_t = 8, requires = "builtin")]
    views: usize,
    /// INRIA cameras.json with the views to render.
    #[arg(long, conflicts_with_all = ["colmap", "builtin"], required_unless_present_any = ["colmap", "builtin"])]
    cameras: Option<PathBuf>,
    /// COLMAP model folder (containing cameras/images .bin or .txt, or sparse/0 with them). Its poses
    /// are checked against the images in `images/` beside the model when that folder exists.
    #[arg(long, conflicts_with = "builtin")]
    colmap: Option<PathBuf>,
    /// Output folder (created if missing); files are written atomically.
    #[arg(long)]
    out: PathBuf,
    /// Also write expected depth as a single-channel 32-bit EXR `<name>_depth.exr`.
    #[arg(long)]
    depth: bool,
    /// Also write alpha (1 - final transmittance) as `<name>_alpha.png`.
    #[arg(long)]
    alpha: bool,
    /// Also blend the scene's identity features (PLY properties f_obj_0..) into `<name>_features.exr`.
    #[arg(long)]
    features: bool,
    /// Also render the per-Gaussian `label` property (from `cogeo tag`) as a colorized label map
    /// `<name>_labels.png` (each pixel: the label with the largest blending weight; dark gray = 0).
    #[arg(long)]
    labels: bool,
    /// Output width; intrinsics are scaled. With only one of --width/--height the aspect ratio is kept.
    #[arg(long)]
    width: Option<u32>,
    /// Output height; intrinsics are scaled.
    #[arg(long)]
    height: Option<u32>,
    /// Background color r,g,b in [0, 1].
    #[arg(long, default_value = "0,0,0", value_parser = parse_rgb)]
    background: [f32; 3],
    /// Near plane: Gaussians with view depth at or below it are culled (INRIA uses 0.2).
    #[arg(long, default_value_t = 0.01)]
    near: f32,
    /// Use at most this SH degree for color (default: the scene's).
    #[arg(long)]
    sh_degree: Option<u32>,
    /// Print per-pass GPU times for each view.
    #[arg(long)]
    timings: bool,
    #[command(flatten)]
    device: DeviceArgs,
}

#[derive(Args)]
struct DemoArgs {
    /// Output folder: data/, train/, tagged.ply, removal/, removal_only/, strips/,
    /// contact_sheet.png, metrics.json, report.md. A previous demo's folder is replaced; any other
    /// non-empty folder is refused.
    #[arg(long, default_value = "demo_out")]
    out: PathBuf,
    /// Small and fast (64x48, 16 views, 3 objects, 500 training iterations) instead of 96x72, 24
    /// views, 4 objects, 800 iterations: about 3 instead of about 10 minutes on 2 CPU cores.
    #[arg(long)]
    quick: bool,
    /// Labels of the synth objects to remove at once (the scene has 3 in --quick, 4 otherwise).
    #[arg(long, value_delimiter = ',', default_value = "1,2")]
    labels: Vec<u8>,
    /// Scene seed (object placement and textures).
    #[arg(long, default_value_t = 2)]
    seed: u64,
    #[command(flatten)]
    device: DeviceArgs,
}

/// Resolution at which a capture is used (train, tag, remove and run share it).
#[derive(Args, Clone, Copy)]
struct ScaleArgs {
    /// Box-filter every image by N x N pixels on load (intrinsics follow; masks are resized to the
    /// result): train, tag and edit a capture at 1/N resolution without writing a copy. Use the same
    /// value for train, tag and remove.
    #[arg(long, default_value_t = 1, value_parser = clap::value_parser!(u32).range(1..=16))]
    downscale: u32,
}

#[derive(Args)]
struct TrainArgs {
    /// Dataset folder: COLMAP model (here or in sparse/0) and an image folder.
    #[arg(long)]
    data: PathBuf,
    /// Output folder: scene.ply, metrics.json and checkpoint/ (created if missing).
    #[arg(long)]
    out: PathBuf,
    /// Image folder inside --data (e.g. images_2, images_4 for downscaled copies; intrinsics are scaled).
    #[arg(long, default_value = "images")]
    images: String,
    #[command(flatten)]
    scale: ScaleArgs,
    /// Training iterations.
    #[arg(long, default_value_t = 30_000)]
    iters: u32,
    /// Continue from the last checkpoint in --out (starts fresh when there is none).
    #[arg(long)]
    resume: bool,
    /// Write a checkpoint every this many iterations (0 = only at the end).
    #[arg(long, default_value_t = 1000)]
    checkpoint_every: u32,
    /// Highest SH degree (one more band every 1000 iterations).
    #[arg(long, default_value_t = 3)]
    sh_degree: u32,
    /// Disable densification (no clone / split / prune / opacity reset, no MCMC relocation).
    #[arg(long)]
    no_densify: bool,
    /// Densification strategy: adc = INRIA adaptive density control (clone / split / prune, opacity
    /// reset); mcmc = 3DGS-MCMC (relocate transparent Gaussians onto opaque ones, grow by 5 % every
    /// 100 iterations up to --max-gaussians, opacity/scale regularizers and position noise).
    #[arg(long, value_enum, default_value = "adc")]
    strategy: cogeo::train::trainer::Strategy,
    /// Gaussian budget: adc never grows past it; mcmc grows to it.
    #[arg(long, default_value_t = 3_000_000)]
    max_gaussians: usize,
    /// Densify until this iteration (INRIA: 15000; scaled down automatically for short runs).
    #[arg(long)]
    densify_until: Option<u32>,
    /// Background color r,g,b in [0, 1] behind the Gaussians.
    #[arg(long, default_value = "0,0,0", value_parser = parse_rgb)]
    background: [f32; 3],
    /// Random seed (view order, splits).
    #[arg(long, default_value_t = 0)]
    seed: u64,
    #[command(flatten)]
    device: DeviceArgs,
}

#[derive(Args)]
struct TagArgs {
    /// Trained scene (INRIA PLY), e.g. the scene.ply of `cogeo train`. Not modified.
    #[arg(long)]
    scene: PathBuf,
    /// Dataset folder the scene was trained from (COLMAP model + images; cameras and the split).
    #[arg(long)]
    data: PathBuf,
    /// Image folder inside --data (e.g. images_2); masks are resized to its images if needed.
    #[arg(long, default_value = "images")]
    images: String,
    #[command(flatten)]
    scale: ScaleArgs,
    /// Masks: a folder of 8-bit instance maps named like the images (pixel value q = object q,
    /// 0 = background, 255 = ignore), or a folder of per-object subfolders holding binary masks
    /// (nonzero = object; objects numbered 1.. in sorted subfolder order). Relative paths are tried
    /// against the current directory, then inside --data.
    #[arg(long, required_unless_present = "prompt")]
    masks: Option<PathBuf>,
    /// Text prompts instead of masks, comma-separated or repeated (object q = the q-th prompt):
    /// needs --detector, --segmenter and --prompt-embeddings. The label maps made are written to
    /// `<out>_prompt_masks/` for inspection and reuse as --masks.
    #[arg(long, value_delimiter = ',', conflicts_with = "masks")]
    prompt: Vec<String>,
    /// Open-vocabulary detector (ONNX): inputs image [1,3,H,W] in [0,1] and text_embeds [Q,E];
    /// outputs boxes [Q,K,4] (normalized x0,y0,x1,y1) and scores [Q,K].
    #[arg(long)]
    detector: Option<PathBuf>,
    /// Box-prompted segmenter (ONNX, SAM-style): inputs image [1,3,H,W] in [0,1] and box [1,4]
    /// (pixels x0,y0,x1,y1); output mask_logits [1,1,H,W] (> 0 = object).
    #[arg(long)]
    segmenter: Option<PathBuf>,
    /// JSON object mapping each prompt to its text embedding (from the detector's text encoder).
    #[arg(long)]
    prompt_embeddings: Option<PathBuf>,
    /// A prompt's best box is used when its detection score reaches this.
    #[arg(long, default_value_t = 0.3)]
    box_threshold: f32,
    /// distill: identity features + classifier (cross-entropy + kNN KL); vote: closed-form blending
    /// weight vote; project: label under each Gaussian's projected center (naive baseline).
    #[arg(long, value_enum, default_value = "distill")]
    method: cogeo::tag::Method,
    /// Output tagged PLY (properties f_obj_* for distill, label, label_prob); the sidecar
    /// `<out>.json` holds the classifier and the report.
    #[arg(long)]
    out: PathBuf,
    /// Distillation iterations (one training view each).
    #[arg(long, default_value_t = 1000)]
    iters: u32,
    /// Identity feature dimension D (1..32).
    #[arg(long, default_value_t = 16)]
    dim: usize,
    /// Weight lambda of the kNN KL spatial loss (0 disables it).
    #[arg(long, default_value_t = 0.1)]
    lambda: f32,
    /// Neighbours k of the spatial loss.
    #[arg(long, default_value_t = 5)]
    knn: usize,
    /// Vote: an object label needs a vote share at least this much above the background's.
    #[arg(long, default_value_t = 0.0)]
    margin: f32,
    /// Random seed (feature and classifier initialization, view order, KL samples).
    #[arg(long, default_value_t = 0)]
    seed: u64,
    #[command(flatten)]
    device: DeviceArgs,
}

#[derive(Args, Clone)]
struct RemovalFlags {
    /// Labels to remove, comma-separated (as in the tagged scene's `label` property).
    #[arg(long, value_delimiter = ',', required_unless_present = "prompt")]
    labels: Vec<u8>,
    /// Object names to remove, comma-separated, looked up in the tagging sidecar's names
    /// (`<scene>.json` of `cogeo tag`: mask subfolder names, or "object q").
    #[arg(long, value_delimiter = ',')]
    prompt: Vec<String>,
    /// ONNX inpainting model with the LaMa contract (image [1,3,512,512] in [0,1] and mask
    /// [1,1,512,512], 1 = hole, in; RGB out). Default: the built-in harmonic inpainter.
    #[arg(long)]
    inpaint_model: Option<PathBuf>,
    /// ONNX monocular depth model (see --depth-contract). Default: the built-in prior (harmonic
    /// completion of the rendered inverse depth from the hole boundary).
    #[arg(long)]
    depth_model: Option<PathBuf>,
    /// Contract of --depth-model: depth-anything-v2 (ImageNet-normalized RGB, sides multiples of 14,
    /// affine-invariant disparity out) or depth-anything3 (504x504 in, depth out).
    #[arg(long, value_enum, default_value = "depth-anything-v2")]
    depth_contract: cogeo::removal::complete::depth::DepthContract,
    /// ONNX depth-inpainting denoiser run as a masked DDIM loop (inputs sample, timestep, alpha_bar,
    /// image, mask; output the predicted noise). Default: built-in edge-aware refinement.
    #[arg(long)]
    depth_refiner: Option<PathBuf>,
    /// Sweeps of the built-in edge-aware depth refinement (0 = keep the anchored depth).
    #[arg(long, default_value_t = 60)]
    depth_sweeps: usize,
    /// DDIM steps of --depth-refiner.
    #[arg(long, default_value_t = 20)]
    diffusion_steps: usize,
    /// Ablation: no depth prior; new Gaussians are placed at the depth rendered after removal, and
    /// the built-in inpainter fills without the background planes.
    #[arg(long)]
    no_depth_guidance: bool,
    /// Ablation: no depth-guided color transfer (hole pixels that other views saw keep their render
    /// or are inpainted like the rest instead of taking those views' captured colors).
    #[arg(long)]
    no_transfer: bool,
    /// How new Gaussians are made: depth (back-projected completed depth, fused and pruned) or
    /// nearest-copy (baseline: each removed Gaussian replaced by a copy of its nearest remaining one).
    #[arg(long, value_enum, default_value = "depth")]
    fill: cogeo::removal::Fill,
    /// Ablation: only delete the Gaussians (no inpainting, no new Gaussians, no refinement).
    #[arg(long)]
    removal_only: bool,
    /// Skip the refinement stage.
    #[arg(long)]
    no_refine: bool,
    /// Skip pruning of sparse background Gaussians near the patch.
    #[arg(long)]
    no_prune: bool,
    /// Refinement iterations (the first half with geometry frozen).
    #[arg(long, default_value_t = 150)]
    refine_iters: u32,
    /// Trust region: per-step update norm bound of each geometry tensor in the second half.
    #[arg(long, default_value_t = 0.01)]
    trust_radius: f32,
    /// A pixel is in the hole when the removed Gaussians carry more than this share of its weight.
    #[arg(long, default_value_t = 0.3)]
    hole_threshold: f32,
    /// Hole dilation in pixels.
    #[arg(long, default_value_t = 2.0)]
    dilate: f32,
    /// Hole pixels the remaining Gaussians already cover with at least this alpha keep their render
    /// (background seen from other views); 1 inpaints the whole hole.
    #[arg(long, default_value_t = 0.9)]
    keep_alpha: f32,
    /// Feathering radius (pixels) of the soft mask that blends aligned prior and rendered depth.
    #[arg(long, default_value_t = 4.0)]
    soft_radius: f32,
    /// Sample every Nth hole pixel in x and y for new Gaussians.
    #[arg(long, default_value_t = 1)]
    stride: usize,
    /// Pruning: distance to the nearest patch Gaussian that makes a background Gaussian a candidate
    /// (scene units; default twice the patch spacing).
    #[arg(long)]
    prune_near: Option<f64>,
    /// Pruning: neighbourhood radius of the density test (default three times the patch spacing).
    #[arg(long)]
    prune_radius: Option<f64>,
    /// Pruning: candidates with fewer background neighbours within the radius are pruned.
    #[arg(long, default_value_t = 4)]
    prune_min_neighbours: usize,
    /// Background color r,g,b in [0, 1] (the one the scene was trained with).
    #[arg(long, default_value = "0,0,0", value_parser = parse_rgb)]
    background: [f32; 3],
    /// Random seed (refinement view order, diffusion noise).
    #[arg(long, default_value_t = 0)]
    seed: u64,
}

#[derive(Args)]
struct RemoveArgs {
    /// Tagged scene (`cogeo tag` output, with a `label` property). Not modified.
    #[arg(long)]
    scene: PathBuf,
    /// Dataset folder the scene was trained from: its training views are edited, its held-out views
    /// rendered (and scored against gt_background/ when it is a `cogeo synth` dataset).
    #[arg(long)]
    data: PathBuf,
    /// Image folder inside --data.
    #[arg(long, default_value = "images")]
    images: String,
    #[command(flatten)]
    scale: ScaleArgs,
    /// Output folder: scene.ply, report.json, before/ after/ removed/ inpainted/ mask/ depth/.
    #[arg(long)]
    out: PathBuf,
    #[command(flatten)]
    removal: RemovalFlags,
    #[command(flatten)]
    device: DeviceArgs,
}

#[derive(Args)]
struct RunArgs {
    /// Dataset folder: COLMAP model and images.
    #[arg(long)]
    data: PathBuf,
    /// Masks for tagging (see `cogeo tag --masks`).
    #[arg(long)]
    masks: PathBuf,
    /// Image folder inside --data.
    #[arg(long, default_value = "images")]
    images: String,
    #[command(flatten)]
    scale: ScaleArgs,
    /// Output folder: train/, tagged.ply (+ .json), removal/.
    #[arg(long)]
    out: PathBuf,
    /// Training iterations.
    #[arg(long, default_value_t = 30_000)]
    iters: u32,
    /// Highest SH degree of training.
    #[arg(long, default_value_t = 3)]
    sh_degree: u32,
    /// Tagging method.
    #[arg(long, value_enum, default_value = "distill")]
    tag_method: cogeo::tag::Method,
    /// Distillation iterations.
    #[arg(long, default_value_t = 1000)]
    tag_iters: u32,
    #[command(flatten)]
    removal: RemovalFlags,
    #[command(flatten)]
    device: DeviceArgs,
}

#[derive(Args)]
struct SynthArgs {
    /// Output folder (created; must be empty): COLMAP text model in sparse/0, images/, object_mask/,
    /// gt_background/, depth/, depth_background/ (EXR), unseen_mask/, synth.json.
    #[arg(long)]
    out: PathBuf,
    /// Image width.
    #[arg(long, default_value_t = 96)]
    width: u32,
    /// Image height.
    #[arg(long, default_value_t = 72)]
    height: u32,
    /// Number of views; every 8th (0, 8, ...) is a held-out test view.
    #[arg(long, default_value_t = 24)]
    views: usize,
    /// Number of objects, 1..8 (labels 1..N in object_mask/).
    #[arg(long, default_value_t = 3)]
    objects: usize,
    /// Camera rig: forward-facing arc or 360-degree orbit.
    #[arg(long, value_enum, default_value = "forward")]
    rig: cogeo::synth::Rig,
    /// Random seed (object placement, textures, point noise).
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Sparse points sampled from each training view (default: pixels / 12).
    #[arg(long)]
    points_per_view: Option<usize>,
    /// Also write the exact ground truth of removing only these objects, e.g. `1,2`:
    /// `without_1-2/` with images/, depth/ and unseen_mask/ (objects kept behind removed ones
    /// stay visible there, unlike in gt_background/).
    #[arg(long, value_delimiter = ',')]
    gt_without: Vec<u8>,
    /// Color rays per pixel side: each pixel is the mean of N x N rays over its area, as a camera
    /// integrates light (anti-aliased textures that look the same from every view); 1 = one ray
    /// through the pixel center. Depth, masks and points always use the center ray.
    #[arg(long, default_value_t = 1, value_parser = clap::value_parser!(u32).range(1..=16))]
    supersample: u32,
}

fn parse_rgb(s: &str) -> Result<[f32; 3], String> {
    let v: Vec<f32> = s
        .split(',')
        .map(|x| x.trim().parse::<f32>())
        .collect::<Result<_, _>>()
        .map_err(|_| format!("expected r,g,b numbers, got {s:?}"))?;
    if v.len() != 3 || v.iter().any(|c| !(0.0..=1.0).contains(c)) {
        return Err(format!("expected three values in [0, 1] as r,g,b, got {s:?}"));
    }
    Ok([v[0], v[1], v[2]])
}

fn progress(len: usize, what: &str) -> ProgressBar {
    let bar = ProgressBar::new(len as u64);
    bar.set_style(
        ProgressStyle::with_template("{msg:>10} [{bar:40}] {pos}/{len} {elapsed_precise} eta {eta}")
            .unwrap()
            .progress_chars("=> "),
    );
    bar.set_message(what.to_string());
    bar
}

fn open_gpu(device: &DeviceArgs) -> Result<Gpu> {
    Gpu::new(&DeviceChoice::from_env(device.device.clone()))
}

fn load_scene(path: &Path) -> Result<GaussianScene> {
    let scene = ply::read_ply(path)?;
    scene.validate(&path.display().to_string())?;
    Ok(scene)
}

fn resize_cameras(cameras: Vec<Camera>, width: Option<u32>, height: Option<u32>) -> Result<Vec<Camera>> {
    if width == Some(0) || height == Some(0) {
        bail!("--width and --height must be positive");
    }
    Ok(cameras
        .into_iter()
        .map(|c| match (width, height) {
            (None, None) => c,
            (Some(w), Some(h)) => c.resized(w, h),
            (Some(w), None) => {
                let h = ((c.height as f64 * w as f64 / c.width as f64).round() as u32).max(1);
                c.resized(w, h)
            }
            (None, Some(h)) => {
                let w = ((c.width as f64 * h as f64 / c.height as f64).round() as u32).max(1);
                c.resized(w, h)
            }
        })
        .collect())
}

/// Renders every camera and writes the requested files into `out`.
fn render_views(
    gpu: &Gpu,
    scene: &GaussianScene,
    cameras: &[Camera],
    out: &Path,
    settings: &RenderSettings,
    depth: bool,
    alpha: bool,
    print_timings: bool,
) -> Result<()> {
    let features = if settings.features {
        Some(scene.feature_matrix("f_obj_").ok_or_else(|| anyhow!("--features: the scene has no f_obj_* properties"))?)
    } else {
        None
    };
    let buffers = SceneBuffers::upload(gpu, scene, features.as_ref().map(|(f, d)| (f.as_slice(), *d)))?;
    let mut raster = Rasterizer::new(gpu)?;
    let bar = progress(cameras.len(), "render");
    for cam in cameras {
        let r = raster.render(&buffers, cam, settings)?;
        write_png_rgb(&out.join(format!("{}.png", cam.name)), r.width, r.height, &r.rgb)?;
        if alpha {
            write_png_gray(&out.join(format!("{}_alpha.png", cam.name)), r.width, r.height, &r.alpha)?;
        }
        if depth {
            write_exr(&out.join(format!("{}_depth.exr", cam.name)), r.width, r.height, &[("Y", &r.expected_depth)])?;
        }
        if r.feature_dim > 0 {
            let hw = (r.width * r.height) as usize;
            let names: Vec<String> = (0..r.feature_dim).map(|c| format!("f{c:02}")).collect();
            let channels: Vec<(&str, &[f32])> =
                names.iter().enumerate().map(|(c, n)| (n.as_str(), &r.features[c * hw..(c + 1) * hw])).collect();
            write_exr(&out.join(format!("{}_features.exr", cam.name)), r.width, r.height, &channels)?;
        }
        if print_timings {
            let parts: Vec<String> = r.timings.iter().map(|t| format!("{} {:.2} ms", t.pass, t.ms)).collect();
            bar.println(format!("{}: {} intersections; {}", cam.name, r.num_intersections, parts.join(", ")));
        }
        bar.inc(1);
    }
    bar.finish();
    Ok(())
}

fn cmd_render(a: RenderArgs) -> Result<()> {
    // Read and check every input before creating anything in --out.
    let scene_path = a.scene.clone().unwrap_or_else(|| PathBuf::from("<built-in scene>"));
    let scene = match &a.scene {
        Some(p) => load_scene(p)?,
        None => cogeo::scene::builtin::default_scene(),
    };
    let cameras = if a.builtin {
        if a.views == 0 {
            bail!("--views must be positive");
        }
        cogeo::scene::builtin::orbit_cameras(a.views, a.width.unwrap_or(640), a.height.unwrap_or(480))
    } else if let Some(path) = &a.cameras {
        camera::read_cameras_json(path)?
    } else {
        let dir = a.colmap.as_ref().unwrap();
        let mut model = colmap::read_colmap(dir)?;
        // the same pose check as training, against the full-size images where they are
        let image_dir = dir.join("images");
        if image_dir.is_dir() {
            cogeo::train::dataset::repair_rotations(&mut model, dir, &image_dir)?;
        }
        for w in &model.warnings {
            eprintln!("warning: {w}");
        }
        model.cameras
    };
    let cameras = if a.builtin { cameras } else { resize_cameras(cameras, a.width, a.height)? };
    if a.features && scene.feature_matrix("f_obj_").is_none() {
        bail!("{}: --features needs f_obj_* properties in the scene (run `cogeo tag` first)", scene_path.display());
    }
    if !(a.near > 0.0) {
        bail!("--near must be positive");
    }
    let labels = if a.labels {
        Some(cogeo::tag::scene_labels(&scene).ok_or_else(|| {
            anyhow!("{}: --labels needs a `label` property in the scene (run `cogeo tag` first)", scene_path.display())
        })?)
    } else {
        None
    };
    let gpu = open_gpu(&a.device)?;
    std::fs::create_dir_all(&a.out).with_context(|| format!("{}: cannot create output folder", a.out.display()))?;
    let settings = RenderSettings {
        background: a.background,
        near: a.near,
        sh_degree: a.sh_degree,
        features: a.features,
        timestamps: a.timings,
    };
    render_views(&gpu, &scene, &cameras, &a.out, &settings, a.depth, a.alpha, a.timings)?;
    if a.builtin {
        ply::write_ply(&scene, &a.out.join("scene.ply"))?;
        camera::write_cameras_json(&cameras, &a.out.join("cameras.json"))?;
    }
    if let Some(labels) = &labels {
        let mut renderer = cogeo::tag::LabelRenderer::new(&gpu, &scene, labels)?;
        for cam in &cameras {
            let map = renderer.render(cam)?;
            let rgb: Vec<u8> = map.iter().flat_map(|&l| cogeo::tag::labels::label_color(l)).collect();
            cogeo::io::write_png(
                &a.out.join(format!("{}_labels.png", cam.name)),
                cam.width,
                cam.height,
                image::ColorType::Rgb8,
                &rgb,
            )?;
        }
    }
    eprintln!("wrote {} view(s) to {}", cameras.len(), a.out.display());
    Ok(())
}

/// Runs a cogeo subcommand from its command line, as a user would type it.
fn run_command(args: &[String]) -> Result<()> {
    let cli = Cli::try_parse_from(std::iter::once("cogeo".to_string()).chain(args.iter().cloned()))
        .map_err(|e| anyhow!("internal command line {args:?}: {e}"))?;
    dispatch(cli.command)
}

/// Marks a folder written by `cogeo demo`, so a rerun may replace it.
const DEMO_MARKER: &str = ".cogeo-demo";

/// Concatenates planar RGB images of one height side by side, 2-pixel white gaps, into RGB8.
fn hstack(images: &[&[f32]], w: usize, h: usize) -> (u32, u32, Vec<u8>) {
    let gap = 2;
    let total_w = images.len() * w + (images.len() - 1) * gap;
    let mut out = vec![255u8; total_w * h * 3];
    for (k, img) in images.iter().enumerate() {
        let x0 = k * (w + gap);
        for y in 0..h {
            for x in 0..w {
                for c in 0..3 {
                    out[(y * total_w + x0 + x) * 3 + c] = cogeo::io::to_u8(img[c * w * h + y * w + x]);
                }
            }
        }
    }
    (total_w as u32, h as u32, out)
}

fn cmd_demo(a: DemoArgs) -> Result<()> {
    use cogeo::eval::folder::{evaluate, EvalConfig, Protocol};
    use cogeo::train::dataset::{find_image, load_rgb};
    let start = std::time::Instant::now();
    let out = &a.out;
    if out.exists() {
        let non_empty =
            std::fs::read_dir(out).with_context(|| format!("{}: cannot read", out.display()))?.next().is_some();
        if non_empty && !out.join(DEMO_MARKER).exists() {
            bail!("{}: exists and is not empty (and is not a previous demo); choose another --out", out.display());
        }
        if non_empty {
            std::fs::remove_dir_all(out)
                .with_context(|| format!("{}: cannot replace the previous demo", out.display()))?;
        }
    }
    std::fs::create_dir_all(out).with_context(|| format!("{}: cannot create output folder", out.display()))?;
    std::fs::write(out.join(DEMO_MARKER), "written by cogeo demo; a rerun replaces this folder\n")?;
    let (width, height, views, objects, iters, densify) =
        if a.quick { (64, 48, 16, 3, 500, false) } else { (96, 72, 24, 4, 800, false) };
    if a.labels.is_empty() || a.labels.iter().any(|&l| l == 0 || l as usize > objects) {
        bail!("--labels must name objects 1..={objects} of the demo scene");
    }
    let p = |name: &str| out.join(name).to_string_lossy().into_owned();
    let labels = a.labels.iter().map(|l| l.to_string()).collect::<Vec<_>>().join(",");
    let mut device = Vec::new();
    if let Some(d) = &a.device.device {
        device = vec!["--device".to_string(), d.clone()];
    }
    let s = |v: &[&str]| v.iter().map(|x| x.to_string()).collect::<Vec<String>>();
    let mut train = s(&["train", "--data", &p("data"), "--out", &p("train"), "--iters", &iters.to_string()]);
    train.extend(s(&["--sh-degree", "1", "--checkpoint-every", "0", "--seed", &a.seed.to_string()]));
    if !densify {
        train.push("--no-densify".into());
    }
    let remove = |dir: &str, extra: &[&str]| {
        let mut v =
            s(&["remove", "--scene", &p("tagged.ply"), "--data", &p("data"), "--labels", &labels, "--out", &p(dir)]);
        v.extend(s(extra));
        v
    };
    let steps: Vec<(&str, Vec<String>)> = vec![
        (
            "synth",
            s(&[
                "synth",
                "--out",
                &p("data"),
                "--width",
                &width.to_string(),
                "--height",
                &height.to_string(),
                "--views",
                &views.to_string(),
                "--objects",
                &objects.to_string(),
                "--seed",
                &a.seed.to_string(),
                "--gt-without",
                &labels,
            ]),
        ),
        ("train", train),
        (
            "tag",
            s(&[
                "tag",
                "--scene",
                &p("train/scene.ply"),
                "--data",
                &p("data"),
                "--masks",
                "object_mask",
                "--method",
                "vote",
                "--out",
                &p("tagged.ply"),
            ]),
        ),
        ("remove", remove("removal", &[])),
        ("removal-only baseline", remove("removal_only", &["--removal-only"])),
    ];
    let mut timings = serde_json::Map::new();
    let mut commands = Vec::new();
    for (i, (name, mut args)) in steps.into_iter().enumerate() {
        eprintln!("== {}/{} {name}", i + 1, 6);
        args.extend(device.iter().cloned());
        let t = std::time::Instant::now();
        run_command(&args).with_context(|| format!("demo step {name}"))?;
        timings.insert(name.to_string(), t.elapsed().as_secs_f64().into());
        commands.push(format!("cogeo {}", args.join(" ")));
    }
    eprintln!("== 6/6 evaluate against the exact object-free ground truth");
    let t = std::time::Instant::now();
    let data = out.join("data");
    let truth = cogeo::synth::ground_truth(&data, &a.labels);
    let eval = |dir: &str| {
        evaluate(&EvalConfig {
            renders: out.join(dir).join("test_after"),
            gt: truth.images.clone(),
            masks: data.join("object_mask"),
            labels: a.labels.clone(),
            protocol: Protocol::Mask,
            data: Some(data.clone()),
            depth: None,
            scene: Some(out.join(dir).join("scene.ply")),
            tau: 0.05,
            leftover_margin: 0.05,
            lpips: None,
            fid: None,
        })
    };
    let (ours, only) = (eval("removal")?, eval("removal_only")?);
    // before/after strips per held-out view: input | removal only | cogeo | ground truth
    std::fs::create_dir_all(out.join("strips"))?;
    let mut sheet: Vec<u8> = Vec::new();
    let (mut sheet_w, mut sheet_h) = (0u32, 0u32);
    for v in ours["views"].as_array().unwrap() {
        let name = v["name"].as_str().unwrap();
        let load = |dir: PathBuf| -> Result<Vec<f32>> {
            let path = find_image(&dir, name).ok_or_else(|| anyhow!("{}: no image {name}", dir.display()))?;
            Ok(load_rgb(&path)?.2)
        };
        let images = [
            load(data.join("images"))?,
            load(out.join("removal_only/test_after"))?,
            load(out.join("removal/test_after"))?,
            load(truth.images.clone())?,
        ];
        let refs: Vec<&[f32]> = images.iter().map(|v| v.as_slice()).collect();
        let (w, h, strip) = hstack(&refs, width as usize, height as usize);
        cogeo::io::write_png(&out.join(format!("strips/{name}.png")), w, h, image::ColorType::Rgb8, &strip)?;
        if sheet_h > 0 {
            sheet.extend(std::iter::repeat(255u8).take(w as usize * 2 * 3));
            sheet_h += 2;
        }
        sheet.extend_from_slice(&strip);
        sheet_w = w;
        sheet_h += h;
    }
    // small demo images are enlarged (nearest neighbour) so the sheet is readable
    let k = (800 / sheet_w.max(1)).clamp(1, 4) as usize;
    let (big_w, big_h) = (sheet_w as usize * k, sheet_h as usize * k);
    let mut big = vec![0u8; big_w * big_h * 3];
    for y in 0..big_h {
        for x in 0..big_w {
            let src = ((y / k) * sheet_w as usize + x / k) * 3;
            big[(y * big_w + x) * 3..(y * big_w + x) * 3 + 3].copy_from_slice(&sheet[src..src + 3]);
        }
    }
    cogeo::io::write_png(&out.join("contact_sheet.png"), big_w as u32, big_h as u32, image::ColorType::Rgb8, &big)?;
    timings.insert("evaluate".into(), t.elapsed().as_secs_f64().into());
    let total = start.elapsed().as_secs_f64();
    let removal_report: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("removal/report.json"))?)?;
    let metrics = serde_json::json!({
        "settings": { "quick": a.quick, "width": width, "height": height, "views": views, "objects": objects,
                      "removed_labels": a.labels, "train_iters": iters, "seed": a.seed },
        "cogeo": ours,
        "removal_only": only,
        "background_psnr_vs_original": removal_report["background_psnr_vs_original"],
        "removal_stage_seconds": removal_report["seconds"],
        "seconds": timings,
        "total_seconds": total,
        "device": removal_report["device"],
        "commands": commands,
    });
    cogeo::io::write_atomic(&out.join("metrics.json"), |w| {
        serde_json::to_writer_pretty(&mut *w, &metrics)?;
        Ok(())
    })?;
    let f = |v: &serde_json::Value| v.as_f64().map(|x| format!("{x:.2}")).unwrap_or_else(|| "n/a".into());
    let f3 = |v: &serde_json::Value| v.as_f64().map(|x| format!("{x:.3}")).unwrap_or_else(|| "n/a".into());
    let row = |name: &str, m: &serde_json::Value| {
        format!(
            "| {name} | {} | {} | {} | {} | {} | {} | {} |\n",
            f(&m["mask"]["psnr"]),
            f3(&m["mask"]["ssim"]),
            f(&m["bbox"]["psnr"]),
            f(&m["full"]["psnr"]),
            f(&m["never_seen"]["psnr"]),
            f3(&m["leftover"]),
            f(&m["floaters"]["score"]),
        )
    };
    let mut md = format!(
        "# cogeo demo: removing objects {labels} from a synthetic scene\n\n\
         {width}x{height}, {views} views ({} held out), {objects} objects, {iters} training iterations, on {}.\n\
         Total {total:.0} s.\n\n\
         Held-out views against the exact object-free ground truth (the scene ray-cast without the\n\
         objects), inside the removed objects' silhouettes:\n\n\
         | method | masked PSNR | masked SSIM | bbox PSNR | full PSNR | never-seen PSNR | leftover | floaters |\n\
         |---|---:|---:|---:|---:|---:|---:|---:|\n",
        ours["views"].as_array().map_or(0, |v| v.len()),
        removal_report["device"].as_str().unwrap_or("?"),
    );
    md += &row("removal only", &only);
    md += &row("cogeo (full pipeline)", &ours);
    md += &format!(
        "\nBackground outside the holes vs the original render: {} dB.\n\n\
         ![input, removal only, cogeo, ground truth](contact_sheet.png)\n\n\
         Columns: input with the objects, removal only, cogeo, ground truth. Per view: `strips/`.\n\n\
         Seconds per step: {}\n\nCommands run:\n\n```\n{}\n```\n",
        f(&removal_report["background_psnr_vs_original"]["mean"]),
        timings.iter().map(|(k, v)| format!("{k} {:.1}", v.as_f64().unwrap_or(0.0))).collect::<Vec<_>>().join(", "),
        commands.join("\n"),
    );
    cogeo::io::write_atomic(&out.join("report.md"), |w| {
        use std::io::Write;
        w.write_all(md.as_bytes())?;
        Ok(())
    })?;
    eprintln!(
        "held-out masked PSNR vs ground truth: cogeo {} dB, removal only {} dB; {total:.0} s; see {}",
        f(&ours["mask"]["psnr"]),
        f(&only["mask"]["psnr"]),
        out.join("report.md").display()
    );
    Ok(())
}

fn cmd_tag(a: TagArgs) -> Result<()> {
    use cogeo::tag::{self, distill::DistillConfig, labels, Method};
    let scene = load_scene(&a.scene)?;
    if a.dim == 0 || a.dim > tag::distill::MAX_DIM {
        bail!("--dim must be 1..={}", tag::distill::MAX_DIM);
    }
    if a.method == Method::Distill && (a.iters == 0 || a.knn == 0) {
        bail!("--iters and --knn must be positive");
    }
    if a.out.extension().and_then(|e| e.to_str()) != Some("ply") {
        bail!("{}: --out must name a .ply file", a.out.display());
    }
    let data = cogeo::train::dataset::load(&a.data, &a.images, a.scale.downscale)?;
    for w in &data.warnings {
        eprintln!("warning: {w}");
    }
    let train_cams: Vec<&Camera> = data.train.iter().map(|v| &v.camera).collect();
    let mut prompt_report = serde_json::Value::Null;
    let (masks, maps) = match &a.masks {
        Some(m) => {
            let masks = if m.is_dir() || m.is_absolute() { m.clone() } else { a.data.join(m) };
            let maps = labels::load(&masks, &train_cams)?;
            (masks, maps)
        }
        None => {
            let (Some(det), Some(seg), Some(emb)) = (&a.detector, &a.segmenter, &a.prompt_embeddings) else {
                bail!(
                    "text prompts need ONNX models: --detector, --segmenter and --prompt-embeddings (contracts in the \
                     README); without them, give per-view masks with --masks"
                );
            };
            let mut seg = tag::prompt::PromptSegmenter::load(det, seg, emb, &a.prompt, a.box_threshold)?;
            let views: Vec<(&[f32], usize, usize)> = data
                .train
                .iter()
                .map(|v| (v.image.as_slice(), v.camera.width as usize, v.camera.height as usize))
                .collect();
            let bar = progress(views.len(), "prompts");
            let mut maps = Vec::new();
            let mut detections = Vec::new();
            for v in &views {
                let (m, d) = seg.label_map(v.0, v.1, v.2)?;
                maps.push(m);
                detections.push(d);
                bar.inc(1);
            }
            bar.finish_and_clear();
            let maps = labels::LabelMaps { num_objects: a.prompt.len(), names: a.prompt.clone(), maps };
            let dir = a.out.with_file_name(format!(
                "{}_prompt_masks",
                a.out.file_stem().and_then(|s| s.to_str()).unwrap_or("tagged")
            ));
            std::fs::create_dir_all(&dir).with_context(|| format!("{}: cannot create", dir.display()))?;
            for (c, m) in train_cams.iter().zip(&maps.maps) {
                cogeo::io::write_png(&dir.join(format!("{}.png", c.name)), c.width, c.height, image::ColorType::L8, m)?;
            }
            let hits: Vec<usize> =
                (0..a.prompt.len()).map(|q| detections.iter().filter(|d| d[q].is_some()).count()).collect();
            for (p, n) in a.prompt.iter().zip(&hits) {
                eprintln!("prompt {p:?}: detected in {n} of {} views", views.len());
            }
            prompt_report = serde_json::json!({
                "prompts": a.prompt, "detector": det, "segmenter": seg.segmenter_path(), "box_threshold": a.box_threshold,
                "views_detected": hits, "masks_written_to": dir,
                "detections": train_cams.iter().zip(&detections).map(|(c, d)| serde_json::json!({"view": c.name, "found": d})).collect::<Vec<_>>(),
            });
            (dir, maps)
        }
    };
    eprintln!(
        "tagging {} Gaussians with {} object label(s) from {} views ({})",
        scene.len(),
        maps.num_objects,
        train_cams.len(),
        masks.display()
    );
    let gpu = open_gpu(&a.device)?;
    let opts = tag::TagOptions {
        method: a.method,
        distill: DistillConfig {
            dim: a.dim,
            iters: a.iters,
            lambda: a.lambda,
            knn: a.knn,
            seed: a.seed,
            ..Default::default()
        },
        margin: a.margin,
    };
    let bar = ProgressBar::new(if a.method == Method::Distill { a.iters as u64 } else { 0 });
    bar.set_style(
        ProgressStyle::with_template("tag [{bar:30}] {pos}/{len} {elapsed_precise} eta {eta} {msg}")
            .unwrap()
            .progress_chars("=> "),
    );
    let start = std::time::Instant::now();
    let cameras: Vec<Camera> = train_cams.iter().map(|c| (*c).clone()).collect();
    let tagged = tag::tag_scene(&gpu, &scene, &cameras, &maps, &opts, |it, losses| {
        bar.set_position(it as u64);
        if let Some((o, s)) = losses {
            bar.set_message(format!("L_obj {o:.4} L_space {s:.5}"));
        }
    })?;
    bar.finish_and_clear();
    let seconds = start.elapsed().as_secs_f64();
    let counts: Vec<usize> =
        (0..maps.classes()).map(|q| tagged.tags.labels.iter().filter(|&&l| l as usize == q).count()).collect();
    // held-out evaluation where masks for the test views exist
    let test_cams: Vec<&Camera> = data.test.iter().map(|v| &v.camera).collect();
    let held_out = match labels::load(&masks, &test_cams) {
        Ok(truth) if !test_cams.is_empty() && a.masks.is_some() => {
            let cams: Vec<Camera> = test_cams.iter().map(|c| (*c).clone()).collect();
            let (per, mean) = tag::evaluate_labels(&gpu, &scene, &tagged.tags.labels, &cams, &truth)?;
            Some(serde_json::json!({ "views": cams.len(), "miou": mean, "iou_per_label": per }))
        }
        _ => None,
    };
    let mut out_scene = scene.clone();
    tag::attach(&mut out_scene, &tagged.tags, tagged.features.as_ref().map(|(f, d)| (f.as_slice(), *d)));
    let report = serde_json::json!({
        "method": a.method,
        "scene": a.scene,
        "masks": masks,
        "labels": maps.num_objects,
        "names": maps.names,
        "prompts": prompt_report,
        "gaussians_per_label": counts,
        "seconds": seconds,
        "final_losses": tagged.losses.map(|(o, s)| serde_json::json!({"obj": o, "space": s})),
        "classifier": tagged.classifier,
        "held_out": held_out,
    });
    ply::write_ply(&out_scene, &a.out)?;
    let sidecar = a.out.with_extension("json");
    cogeo::io::write_atomic(&sidecar, |w| {
        serde_json::to_writer_pretty(&mut *w, &report)?;
        Ok(())
    })?;
    let miou = held_out
        .as_ref()
        .map(|h| format!("; held-out mIoU {:.3}", h["miou"].as_f64().unwrap_or(0.0)))
        .unwrap_or_default();
    eprintln!(
        "done in {seconds:.1} s: Gaussians per label {counts:?}{miou}; wrote {} and {}",
        a.out.display(),
        sidecar.display()
    );
    Ok(())
}

fn cmd_synth(a: SynthArgs) -> Result<()> {
    let cfg = cogeo::synth::SynthConfig {
        width: a.width,
        height: a.height,
        views: a.views,
        objects: a.objects,
        rig: a.rig,
        seed: a.seed,
        points_per_view: a.points_per_view.unwrap_or((a.width * a.height / 12) as usize),
        gt_without: a.gt_without.clone(),
        supersample: a.supersample,
    };
    let bar = progress(2 * a.views, "synth");
    let objects = cogeo::synth::generate(&cfg, &a.out, &|done, _| bar.set_position(done as u64))?;
    bar.finish();
    eprintln!("wrote {} views with {} objects to {}", a.views, objects.len(), a.out.display());
    Ok(())
}

fn cmd_train(a: TrainArgs) -> Result<()> {
    use cogeo::train::{checkpoint, dataset, trainer};
    if a.iters == 0 {
        bail!("--iters must be positive");
    }
    if a.sh_degree > 3 {
        bail!("--sh-degree must be 0..3");
    }
    let data = dataset::load(&a.data, &a.images, a.scale.downscale)?;
    for w in &data.warnings {
        eprintln!("warning: {w}");
    }
    let gpu = open_gpu(&a.device)?;
    std::fs::create_dir_all(&a.out).with_context(|| format!("{}: cannot create output folder", a.out.display()))?;
    let densify_until = a.densify_until.unwrap_or_else(|| (a.iters / 2).min(15_000));
    let cfg = trainer::TrainConfig {
        iters: a.iters,
        sh_degree: a.sh_degree,
        densify: !a.no_densify,
        densify_from: 500.min(a.iters / 10),
        densify_until,
        // INRIA's fixed interval: short runs end densification before any reset, which suits them
        // (a reset needs thousands of iterations to recover)
        opacity_reset_interval: 3000,
        max_gaussians: a.max_gaussians,
        strategy: a.strategy,
        seed: a.seed,
        background: a.background,
        ..Default::default()
    };
    let resumed = if a.resume { checkpoint::load(&a.out)? } else { None };
    if a.resume && resumed.is_none() {
        eprintln!("no checkpoint in {}; starting from the sparse points", a.out.display());
    }
    let scene = match &resumed {
        Some(c) => c.scene.clone(),
        None => trainer::init_from_points(&data.points, a.sh_degree)?,
    };
    let mut t = trainer::Trainer::new(&gpu, &data, &scene, cfg)?;
    if let Some(c) = &resumed {
        t.set_step(c.step);
        t.load_moments(&c.moments)?;
        eprintln!("resumed at iteration {} with {} Gaussians", c.step, scene.len());
    }
    eprintln!(
        "training {} views ({} held out), {} Gaussians, extent {:.2}, on {}",
        data.train.len(),
        data.test.len(),
        t.num_gaussians(),
        data.extent,
        gpu.info().name
    );
    let bar = ProgressBar::new(a.iters as u64);
    bar.set_style(
        ProgressStyle::with_template("train [{bar:30}] {pos}/{len} {elapsed_precise} eta {eta} {msg}")
            .unwrap()
            .progress_chars("=> "),
    );
    bar.set_position(t.step as u64);
    let start = std::time::Instant::now();
    let first_step = t.step;
    let mut test_psnr = None;
    // Without a terminal (a pipe, a log file, CI) the bar draws nothing: print a plain line about
    // every 5 % of the run instead, on the steps that read the loss back anyway.
    let plain_every = (!std::io::stderr().is_terminal()).then(|| (a.iters / 20 / 50).max(1) * 50);
    while t.step < a.iters {
        let log = (t.step + 1) % 50 == 0;
        t.iterate(&data, log)?;
        if a.checkpoint_every > 0 && t.step % a.checkpoint_every == 0 && t.step < a.iters {
            checkpoint::save(&t, &a.out)?;
            test_psnr = Some(t.evaluate(&data.test)?.psnr);
        }
        if let Some((loss, l1)) = t.last_loss.filter(|_| log) {
            let psnr = test_psnr.map(|p| format!(" test PSNR {p:.2}")).unwrap_or_default();
            let msg = format!("loss {loss:.4} L1 {l1:.4}{psnr} | {} Gaussians", t.num_gaussians());
            if plain_every.is_some_and(|n| t.step % n == 0) {
                eprintln!("train {}/{} {:.0} s {msg}", t.step, a.iters, start.elapsed().as_secs_f64());
            }
            bar.set_message(msg);
        }
        bar.set_position(t.step as u64);
    }
    bar.finish();
    let seconds = start.elapsed().as_secs_f64();
    let scene = t.download_scene()?;
    ply::write_ply(&scene, &a.out.join("scene.ply"))?;
    checkpoint::save(&t, &a.out)?;
    let test = t.evaluate(&data.test)?;
    let train = t.evaluate(&data.train)?;
    let report = serde_json::json!({
        "iterations": t.step,
        "gaussians": scene.len(),
        "seconds": seconds,
        "iterations_per_second": (t.step - first_step) as f64 / seconds.max(1e-9),
        "test": test,
        "train": train,
        "device": gpu.info().name,
    });
    let text = serde_json::to_string_pretty(&report)?;
    cogeo::io::write_atomic(&a.out.join("metrics.json"), |w| {
        use std::io::Write;
        w.write_all(text.as_bytes()).map_err(Into::into)
    })?;
    eprintln!(
        "done: {} Gaussians; test PSNR {:.2} dB SSIM {:.4} ({} views); train PSNR {:.2}; {:.1} it/s; wrote {}",
        scene.len(),
        test.psnr,
        test.ssim,
        test.views,
        train.psnr,
        (t.step - first_step) as f64 / seconds.max(1e-9),
        a.out.join("scene.ply").display()
    );
    Ok(())
}

/// The labels named by --labels and --prompt.
fn chosen_labels(flags: &RemovalFlags, scene_path: &Path) -> Result<Vec<u8>> {
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

fn write_views(dir: &Path, cameras: &[Camera], images: &[Vec<f32>]) -> Result<()> {
    std::fs::create_dir_all(dir).with_context(|| format!("{}: cannot create", dir.display()))?;
    for (c, img) in cameras.iter().zip(images) {
        write_png_rgb(&dir.join(format!("{}.png", c.name)), c.width, c.height, img)?;
    }
    Ok(())
}

fn cmd_remove(a: RemoveArgs) -> Result<()> {
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
        inpainter: match &f.inpaint_model {
            Some(p) => Inpainter::onnx(p)?,
            None => Inpainter::BuiltIn,
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
        fuse: cogeo::removal::fuse::FuseConfig { stride: f.stride.max(1), ..Default::default() },
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
            ..Default::default()
        },
        background: f.background,
    };
    let gpu = open_gpu(&a.device)?;
    std::fs::create_dir_all(&a.out).with_context(|| format!("{}: cannot create output folder", a.out.display()))?;
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

fn cmd_run(a: RunArgs) -> Result<()> {
    std::fs::create_dir_all(&a.out).with_context(|| format!("{}: cannot create output folder", a.out.display()))?;
    let train_dir = a.out.join("train");
    eprintln!("== 1/3 train");
    cmd_train(TrainArgs {
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
    cmd_tag(TagArgs {
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
    cmd_remove(RemoveArgs {
        scene: tagged,
        data: a.data,
        images: a.images,
        scale: a.scale,
        out: a.out.join("removal"),
        removal: a.removal,
        device: a.device,
    })
}

fn cmd_eval(a: EvalArgs) -> Result<()> {
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
        lpips: a.lpips_model,
        fid: a.fid_model,
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

fn dispatch(command: Command) -> Result<()> {
    match command {
        Command::Devices => cogeo::gpu::list_devices().map(|devs| {
            if devs.is_empty() {
                println!("no Vulkan devices found");
            }
            for d in devs {
                println!("{}", d.summary());
            }
        }),
        Command::Render(a) => cmd_render(a),
        Command::Demo(a) => cmd_demo(a),
        Command::Synth(a) => cmd_synth(a),
        Command::Train(a) => cmd_train(a),
        Command::Tag(a) => cmd_tag(a),
        Command::Remove(a) => cmd_remove(a),
        Command::Run(a) => cmd_run(a),
        Command::Eval(a) => cmd_eval(a),
    }
}

fn main() {
    let cli = Cli::parse();
    if let Err(e) = dispatch(cli.command) {
        // one line: the error and its causes
        let chain: Vec<String> = e.chain().map(|c| c.to_string()).collect();
        eprintln!("error: {}", chain.join(": "));
        std::process::exit(1);
    }
}
