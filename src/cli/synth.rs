//! `cogeo synth`: a procedural dataset with exact removal ground truth.

use super::args::{open_gpu, progress, DeviceArgs, StageProgress};
use anyhow::{bail, Result};
use clap::Args;
use std::path::PathBuf;

#[derive(Args)]
pub struct SynthArgs {
    /// Output folder (created; must be empty): COLMAP text model in sparse/0 and the same cameras as
    /// a nerfstudio transforms.json (+ sparse_pc.ply), images/, object_mask/,
    /// gt_background/, depth/, depth_background/ (EXR), unseen_mask/, synth.json.
    #[arg(long)]
    pub out: PathBuf,
    /// Image width.
    #[arg(long, default_value_t = 96)]
    pub width: u32,
    /// Image height.
    #[arg(long, default_value_t = 72)]
    pub height: u32,
    /// Number of views; every 8th (0, 8, ...) is a held-out test view.
    #[arg(long, default_value_t = 24)]
    pub views: usize,
    /// Number of objects, 1..8 (labels 1..N in object_mask/).
    #[arg(long, default_value_t = 3)]
    pub objects: usize,
    /// Camera rig: forward-facing arc or 360-degree orbit.
    #[arg(long, value_enum, default_value = "forward")]
    pub rig: cogeo::synth::Rig,
    /// Random seed (object placement, textures, point noise).
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Sparse points sampled from each training view (default: pixels / 12).
    #[arg(long)]
    pub points_per_view: Option<usize>,
    /// Also write the exact ground truth of removing only these objects, e.g. `1,2`:
    /// `without_1-2/` with images/, depth/ and unseen_mask/ (objects kept behind removed ones
    /// stay visible there, unlike in gt_background/).
    #[arg(long, value_delimiter = ',')]
    pub gt_without: Vec<u8>,
    /// Color rays per pixel side: each pixel is the mean of N x N rays over its area, as a camera
    /// integrates light (anti-aliased textures that look the same from every view); 1 = one ray
    /// through the pixel center. Depth, masks and points always use the center ray.
    #[arg(long, default_value_t = 1, value_parser = clap::value_parser!(u32).range(1..=16))]
    pub supersample: u32,
    /// Lens distortion of every view, k1,k2,p1,p2 (COLMAP's OPENCV model): the images, masks and
    /// ground truth are ray-cast through that lens, as a phone's photos are, and cameras.txt says
    /// OPENCV. Default: a pinhole.
    #[arg(long, value_delimiter = ',', num_args = 1, allow_negative_numbers = true, value_name = "K1,K2,P1,P2")]
    pub distortion: Vec<f64>,
    /// Exposure jitter X: each view's photos (and its ground truth) are multiplied per channel by
    /// a gain drawn uniformly from [1-X, 1+X], saturating at white, as a phone's exposure and
    /// white balance change between shots; synth.json lists the gains. Default: 0 (none).
    #[arg(long, default_value_t = 0.0, value_name = "X", value_parser = parse_jitter)]
    pub exposure_jitter: f64,
    /// A removal benchmark on real photos instead of a generated room: composite --objects
    /// virtual objects (boxes and cylinders) into the photos of this capture (COLMAP model or
    /// transforms.json), standing on its supporting surface as --scene's depth shows it, each
    /// drawn only where it is nearer than that scene. The original photos are the ground truth;
    /// the folder has the synth layout (one PINHOLE camera per image, in the undistorted frame).
    /// Objects after the first stand near it, so that in some views one is partly behind another.
    #[arg(long, value_name = "CAPTURE", requires = "scene",
          conflicts_with_all = ["width", "height", "views", "rig", "distortion", "exposure_jitter", "points_per_view"])]
    pub composite_into: Option<PathBuf>,
    /// With --composite-into: the capture's scene trained without the objects (cogeo train's
    /// scene.ply); its rendered depth locates the surfaces and hides objects behind them.
    #[arg(long, value_name = "PLY", requires = "composite_into")]
    pub scene: Option<PathBuf>,
    /// With --composite-into: the capture's image folder.
    #[arg(long, default_value = cogeo::scene::dataset::DEFAULT_IMAGE_FOLDER, requires = "composite_into")]
    pub images: String,
    /// With --composite-into: box-filter every photo by N x N pixels first.
    #[arg(long, default_value_t = 1, requires = "composite_into")]
    pub downscale: u32,
    /// With --composite-into: the objects' half size as a fraction of the median distance from
    /// the cameras to what they look at (each object varies by -20..+12 %).
    #[arg(long, default_value_t = 0.06, requires = "composite_into")]
    pub object_size: f64,
    /// With --composite-into: darken the ground around each object's footprint by up to this
    /// fraction (a soft contact shadow; outside the object masks, so removal must not leave it
    /// either). Default 0: none.
    #[arg(long, default_value_t = 0.0, requires = "composite_into")]
    pub contact_shadow: f64,
    /// With --composite-into: the COLMAP model's sparse points are the capture's own (less those
    /// the objects stand on or hide) plus points on the objects, as many as sampling this many
    /// points on the training views' composited surfaces puts there; a capture with under 1000
    /// points gets this many composited-surface points instead.
    #[arg(long, default_value_t = 40_000, requires = "composite_into")]
    pub sparse_points: usize,
    /// With --composite-into: stand the objects where an earlier composite's synth.json says
    /// (its ground plane and objects, used as they are; --objects must match) instead of placing
    /// them anew; --seed still draws their textures and the sparse points. Placement reads
    /// --scene's depth, which differs from one training of the capture to the next: this keeps a
    /// benchmark's objects where they were.
    #[arg(long, value_name = "SYNTH_JSON", requires = "composite_into")]
    pub placement: Option<PathBuf>,
    #[command(flatten)]
    pub device: DeviceArgs,
}

fn parse_jitter(s: &str) -> Result<f64, String> {
    let x: f64 = s.parse().map_err(|_| format!("{s:?} is not a number"))?;
    if (0.0..1.0).contains(&x) {
        Ok(x)
    } else {
        Err(format!("{x} is not in [0, 1)"))
    }
}

pub fn run(a: SynthArgs) -> Result<()> {
    if let Some(capture) = &a.composite_into {
        return composite(&a, capture);
    }
    let distortion = match a.distortion[..] {
        [] => [0.0; 4],
        [k1, k2, p1, p2] if a.distortion.iter().all(|v| v.is_finite()) => [k1, k2, p1, p2],
        _ => bail!("--distortion takes four finite numbers k1,k2,p1,p2, got {:?}", a.distortion),
    };
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
        distortion,
        exposure_jitter: a.exposure_jitter,
    };
    let bar = progress(2 * a.views, "synth");
    let objects = cogeo::synth::generate(&cfg, &a.out, &|done, _| bar.set_position(done as u64))?;
    bar.finish();
    eprintln!("wrote {} views with {} objects to {}", a.views, objects.len(), a.out.display());
    Ok(())
}

fn composite(a: &SynthArgs, capture: &std::path::Path) -> Result<()> {
    if !(0.0..1.0).contains(&a.contact_shadow) {
        bail!("--contact-shadow must be in [0, 1), got {}", a.contact_shadow);
    }
    let cfg = cogeo::synth::composite::CompositeConfig {
        capture: capture.to_path_buf(),
        images: a.images.clone(),
        downscale: a.downscale,
        scene: a.scene.clone().expect("clap requires --scene"),
        objects: a.objects,
        seed: a.seed,
        supersample: a.supersample,
        gt_without: a.gt_without.clone(),
        object_size: a.object_size,
        contact_shadow: a.contact_shadow,
        points: a.sparse_points,
        placement: a.placement.clone(),
    };
    let gpu = open_gpu(&a.device)?;
    let stages = StageProgress::new("synth");
    let summary =
        cogeo::synth::composite::composite(&gpu, &cfg, &a.out, &|stage, done, total| stages.set(stage, done, total))?;
    stages.finish();
    eprintln!(
        "composited {} objects into {} views of {} ({} views with one object partly behind another; {} capture \
         points left out, hidden by the objects) into {}",
        summary.objects.len(),
        summary.views,
        capture.display(),
        summary.views_with_overlap,
        summary.points_hidden,
        a.out.display()
    );
    Ok(())
}
