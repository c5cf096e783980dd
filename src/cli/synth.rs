//! `cogeo synth`: a procedural dataset with exact removal ground truth.

use super::args::progress;
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
