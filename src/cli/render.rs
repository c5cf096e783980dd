//! `cogeo render`: a Gaussian scene (or the built-in one) to PNG, with depth, alpha, features and
//! labels on request.

use super::args::{load_scene, open_gpu, parse_rgb, progress, DeviceArgs};
use anyhow::{anyhow, bail, Result};
use clap::Args;
use cogeo::gpu::Gpu;
use cogeo::io::{write_exr, write_png_gray, write_png_rgb};
use cogeo::render::{RenderSettings, SceneRenderer};
use cogeo::scene::camera::resize_cameras;
use cogeo::scene::{camera, ply, Camera, GaussianScene};
use std::path::{Path, PathBuf};

#[derive(Args)]
pub struct RenderArgs {
    /// Gaussian scene in the INRIA PLY layout.
    #[arg(long, required_unless_present = "builtin", conflicts_with = "builtin")]
    pub scene: Option<PathBuf>,
    /// Render the built-in procedural scene (about 60k Gaussians) from an orbit of --views
    /// cameras instead of a PLY (writes scene.ply and cameras.json beside the renders).
    #[arg(long)]
    pub builtin: bool,
    /// Number of orbit views for --builtin.
    #[arg(long, default_value_t = 8, requires = "builtin")]
    pub views: usize,
    /// INRIA cameras.json with the views to render.
    #[arg(long, conflicts_with_all = ["colmap", "builtin"], required_unless_present_any = ["colmap", "builtin"])]
    pub cameras: Option<PathBuf>,
    /// Capture folder: a COLMAP model (cameras/images .bin or .txt, here or in sparse/0) or a
    /// nerfstudio / instant-ngp transforms.json. Its poses are checked against the images in
    /// `images/` beside the model when that folder exists; cameras with lens distortion are
    /// rendered as the undistorted pinhole cameras cogeo trains in.
    #[arg(long, conflicts_with = "builtin")]
    pub colmap: Option<PathBuf>,
    /// Output folder (created if missing); files are written atomically.
    #[arg(long)]
    pub out: PathBuf,
    /// Also write expected depth as a single-channel 32-bit EXR `<name>_depth.exr`.
    #[arg(long)]
    pub depth: bool,
    /// Also write alpha (1 - final transmittance) as `<name>_alpha.png`.
    #[arg(long)]
    pub alpha: bool,
    /// Also blend the scene's identity features (PLY properties f_obj_0..) into `<name>_features.exr`.
    #[arg(long)]
    pub features: bool,
    /// Also render the per-Gaussian `label` property (from `cogeo tag`) as a colorized label map
    /// `<name>_labels.png` (each pixel: the label with the largest blending weight; dark gray = 0).
    #[arg(long)]
    pub labels: bool,
    /// Output width; intrinsics are scaled. With only one of --width/--height the aspect ratio is kept.
    #[arg(long)]
    pub width: Option<u32>,
    /// Output height; intrinsics are scaled.
    #[arg(long)]
    pub height: Option<u32>,
    /// Background color r,g,b in [0, 1].
    #[arg(long, default_value = cogeo::flag_values::DEFAULT_BACKGROUND, value_parser = parse_rgb)]
    pub background: [f32; 3],
    /// Near plane: Gaussians with view depth at or below it are culled (INRIA uses 0.2).
    #[arg(long, default_value_t = RenderSettings::default().near)]
    pub near: f32,
    /// Use at most this SH degree for color (default: the scene's).
    #[arg(long)]
    pub sh_degree: Option<u32>,
    /// Print per-pass GPU times for each view.
    #[arg(long)]
    pub timings: bool,
    #[command(flatten)]
    pub device: DeviceArgs,
}

/// Renders every camera and writes the requested files into `out`.
#[allow(clippy::too_many_arguments)]
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
    let mut renderer = SceneRenderer::new(gpu, scene, features.as_ref().map(|(f, d)| (f.as_slice(), *d)))?;
    let bar = progress(cameras.len(), "render");
    for cam in cameras {
        let r = renderer.render(cam, settings)?;
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

pub fn run(a: RenderArgs) -> Result<()> {
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
        let mut model = cogeo::scene::dataset::read_capture(dir)?;
        // the same pose check as training, against the full-size images where they are
        let image_dir = dir.join("images");
        if image_dir.is_dir() {
            cogeo::scene::dataset::repair_rotations(&mut model, dir, &image_dir)?;
        }
        for w in &model.warnings {
            eprintln!("warning: {w}");
        }
        // cogeo trains on the photos undistorted into pinhole cameras: render those
        let lenses = model.lenses.iter().filter(|l| !l.is_pinhole()).count();
        if lenses > 0 {
            eprintln!(
                "{lenses} of {} cameras have lens distortion: rendering their undistorted pinhole cameras (the \
                 frame cogeo trains in), not the distorted photos",
                model.cameras.len()
            );
        }
        model
            .cameras
            .iter()
            .zip(&model.lenses)
            .map(|(c, &lens)| {
                cogeo::scene::undistort::pinhole_camera(c, lens, &format!("{}: {}", dir.display(), c.name))
            })
            .collect::<Result<Vec<_>>>()?
    };
    let cameras = if a.builtin { cameras } else { resize_cameras(cameras, a.width, a.height)? };
    if a.features && scene.feature_matrix("f_obj_").is_none() {
        bail!("{}: --features needs f_obj_* properties in the scene (run `cogeo tag` first)", scene_path.display());
    }
    if a.near.is_nan() || a.near <= 0.0 {
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
    let _folder = super::args::OutputFolder::create(&a.out)?;
    let settings = RenderSettings {
        background: a.background,
        near: a.near,
        sh_degree: a.sh_degree,
        features: a.features,
        timestamps: a.timings,
        median_depth: false,
        only_tiles: None,
        after_removal: false,
    };
    let batch = cogeo::io::OutputBatch::begin();
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
    batch.commit()?;
    eprintln!("wrote {} view(s) to {}", cameras.len(), a.out.display());
    Ok(())
}
