//! `cogeo remove`: the removal pipeline (src/removal) on a tagged scene, with its outputs: edited
//! and held-out views, masks, depth, the edited scene and report.json.

use super::args::{load_scene, open_gpu, CaptureArgs, DeviceArgs};
use anyhow::{anyhow, bail, Context, Result};
use clap::Args;
use cogeo::io::{write_exr, write_png_rgb};
use cogeo::removal::complete::Completer;
use cogeo::removal::held_out::{render_held_out, score_against_synth, GroundTruthScores};
use cogeo::removal::report::RemovalReport;
use cogeo::scene::exposure::ColorAffine;
use cogeo::scene::{ply, Camera};
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
    #[command(flatten)]
    pub completion: cogeo::removal::complete::CompletionConfig,
    #[command(flatten)]
    pub options: cogeo::removal::RemoveOptions,
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
    #[command(flatten)]
    pub capture: CaptureArgs,
    /// Output folder: scene.ply, report.json, before/ after/ removed/ inpainted/ mask/ depth/.
    #[arg(long)]
    pub out: PathBuf,
    #[command(flatten)]
    pub removal: RemovalFlags,
    /// The training views' exposure maps (`exposure.json` of `cogeo train --exposure`): each
    /// photo is taken back into the scene's colors through the inverse of its own map before
    /// the removal borrows its pixels, so a brighter source view leaves no brighter patch.
    /// `--inpainted` views, completions of those photos, are taken the same way, and `inpainted/`
    /// is written back in each photo's colors.
    #[arg(long, value_name = "EXPOSURE_JSON")]
    pub exposure: Option<PathBuf>,
    #[command(flatten)]
    pub device: DeviceArgs,
}

/// The training views' exposure maps of `--exposure`, one per view (None where the file names no
/// map for it, with a warning: that view's colors are used as they are).
fn view_exposures(train: &[cogeo::scene::dataset::View], path: &Path) -> Result<Vec<Option<ColorAffine>>> {
    let maps = cogeo::scene::exposure::Exposures::read(path)?;
    let per_view: Vec<Option<ColorAffine>> = train.iter().map(|v| maps.get(&v.camera.name).cloned()).collect();
    let missing: Vec<&str> =
        train.iter().zip(&per_view).filter(|(_, m)| m.is_none()).map(|(v, _)| v.camera.name.as_str()).collect();
    if !missing.is_empty() {
        eprintln!(
            "warning: {}: no exposure map for {} view(s) ({}); their photos are used as they are",
            path.display(),
            missing.len(),
            missing.join(", ")
        );
    }
    Ok(per_view)
}

/// `rgb` of view `i` out of its photo's colors into the scene's, through the inverse of the view's
/// map (`Exposures::read` checked that every map inverts); as it is without a map.
fn into_scene_colors(maps: &[Option<ColorAffine>], i: usize, rgb: &[f32]) -> Vec<f32> {
    match maps.get(i).and_then(Option::as_ref) {
        Some(map) => map.inverse().unwrap().apply(rgb),
        None => rgb.to_vec(),
    }
}

/// `rgb` of view `i` out of the scene's colors into its photo's, through the view's map; as it
/// is without a map (`into_scene_colors` undone).
fn into_photo_colors(maps: &[Option<ColorAffine>], i: usize, rgb: &[f32]) -> Vec<f32> {
    match maps.get(i).and_then(Option::as_ref) {
        Some(map) => map.apply(rgb),
        None => rgb.to_vec(),
    }
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

/// report.json: the removal's own report with what the command adds.
#[derive(serde::Serialize)]
struct RemoveReport<'a> {
    #[serde(flatten)]
    removal: &'a RemovalReport,
    scene: &'a Path,
    device: String,
    total_seconds: f64,
    peak_rss_mib: Option<f64>,
    #[serde(flatten)]
    scores: &'a GroundTruthScores,
}

/// Writes one PNG per camera into `dir`, the views spread over the cores (PNG encoding and each
/// file's sync are most of the time it takes).
pub fn write_views(dir: &Path, cameras: &[Camera], images: &[&[f32]]) -> Result<()> {
    std::fs::create_dir_all(dir).with_context(|| format!("{}: cannot create", dir.display()))?;
    let mut written: Vec<Result<()>> = cameras.iter().map(|_| Ok(())).collect();
    cogeo::parallel::for_each_item(&mut written, &mut |_, _| {}, |i, result| {
        let c = &cameras[i];
        *result = write_png_rgb(&dir.join(format!("{}.png", c.name)), c.width, c.height, images[i]);
    });
    written.into_iter().collect()
}

fn slices(images: &[Vec<f32>]) -> Vec<&[f32]> {
    images.iter().map(|x| x.as_slice()).collect()
}

/// The edited views' images: renders before, after and right after deletion, the hole masks and,
/// when completion ran, the inpainted views and completed depths. The inpainted views are written
/// in their photos' colors (through each view's map of `exposures`, under `--exposure`), as the
/// photos they complete, so that `--inpainted` takes a run's `inpainted/` back unchanged.
fn write_edited_views(
    out: &Path,
    cameras: &[Camera],
    v: &[cogeo::removal::ViewResult],
    completed: bool,
    exposures: Option<&[Option<ColorAffine>]>,
) -> Result<()> {
    let images = |f: fn(&cogeo::removal::ViewResult) -> &[f32]| v.iter().map(f).collect::<Vec<_>>();
    write_views(&out.join("before"), cameras, &images(|x| &x.before))?;
    write_views(&out.join("after"), cameras, &images(|x| &x.after))?;
    write_views(&out.join("removed"), cameras, &images(|x| &x.removed))?;
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
    if completed {
        match exposures {
            Some(maps) => {
                let recolored: Vec<Vec<f32>> =
                    v.iter().enumerate().map(|(i, x)| into_photo_colors(maps, i, &x.inpainted)).collect();
                write_views(&out.join("inpainted"), cameras, &slices(&recolored))?;
            }
            None => write_views(&out.join("inpainted"), cameras, &images(|x| &x.inpainted))?,
        }
        std::fs::create_dir_all(out.join("depth"))?;
        for (c, x) in cameras.iter().zip(v) {
            write_exr(&out.join(format!("depth/{}.exr", c.name)), c.width, c.height, &[("Y", &x.depth)])?;
        }
    }
    Ok(())
}

pub fn run(a: RemoveArgs) -> Result<()> {
    let f = &a.removal;
    let labels = chosen_labels(f, &a.scene)?;
    let scene = load_scene(&a.scene)?;
    let scene_labels = cogeo::tag::scene_labels(&scene).ok_or_else(|| {
        anyhow!("{}: the scene has no `label` property; tag it first with `cogeo tag`", a.scene.display())
    })?;
    let data = cogeo::scene::dataset::load(&a.data, &a.capture.images, a.capture.downscale)?;
    let mut opts = f.options.clone();
    opts.labels = labels.clone();
    opts.fuse.stride = opts.fuse.stride.max(1);
    let gpu = open_gpu(&a.device)?;
    let views: Vec<(String, (u32, u32))> =
        data.train.iter().map(|v| (v.camera.name.clone(), (v.camera.width, v.camera.height))).collect();
    let mut completer = Completer::load(&gpu, &f.completion, opts.seed, &views)?;
    // the photos and the views inpainted from them (`--inpainted`) come into the scene's colors
    let exposures = a.exposure.as_deref().map(|p| view_exposures(&data.train, p)).transpose()?;
    let photos: Vec<Vec<f32>> = match &exposures {
        Some(maps) => {
            completer.inpainter.map_provided(|i, rgb| into_scene_colors(maps, i, rgb));
            data.train.iter().enumerate().map(|(i, v)| into_scene_colors(maps, i, &v.image)).collect()
        }
        None => data.train.iter().map(|v| v.image.clone()).collect(),
    };
    let _folder = super::args::OutputFolder::create(&a.out)?;
    eprintln!(
        "removing label(s) {labels:?} from {} Gaussians; editing {} views on {}",
        scene.len(),
        data.train.len(),
        gpu.info().name
    );
    let cameras: Vec<Camera> = data.train.iter().map(|v| v.camera.clone()).collect();
    let stages = super::args::StageProgress::new("remove");
    let start = std::time::Instant::now();
    let removal = cogeo::removal::remove(
        &gpu,
        &scene,
        &scene_labels,
        &cameras,
        &photos,
        data.extent,
        &opts,
        &completer,
        &mut |stage, done, total| stages.set(stage, done, total),
    )?;
    stages.finish();
    // outputs: the edited views are encoded and written on other threads while the GPU renders
    // the held-out views
    let out = &a.out;
    let v = &removal.views;
    let batch = cogeo::io::OutputBatch::begin();
    let test_cams: Vec<Camera> = data.test.iter().map(|v| v.camera.clone()).collect();
    let held_out = std::thread::scope(|s| -> Result<_> {
        let writer = s.spawn(|| write_edited_views(out, &cameras, v, opts.stages.complete, exposures.as_deref()));
        let held_out = render_held_out(&gpu, &scene, &removal.scene, &test_cams, opts.background);
        writer.join().expect("the image writer panicked")?;
        held_out
    })?;
    write_views(&out.join("test_before"), &test_cams, &slices(&held_out.before))?;
    write_views(&out.join("test_after"), &test_cams, &slices(&held_out.after))?;
    // synth ground truth is stored at the dataset's resolution and in its photos' frame: it is
    // undistorted as the photos were; a downscaled run is not scored
    let frames: Vec<_> = data.test.iter().map(|v| v.undistortion.as_deref()).collect();
    let scores = if a.capture.downscale == 1 {
        score_against_synth(&a.data, &labels, &test_cams, &frames, &held_out, &cameras, v)?
    } else {
        GroundTruthScores::default()
    };
    ply::write_ply(&removal.scene, &out.join("scene.ply"))?;
    let report = RemoveReport {
        removal: &removal.report,
        scene: &a.scene,
        device: gpu.info().name.clone(),
        total_seconds: start.elapsed().as_secs_f64(),
        peak_rss_mib: cogeo::io::peak_rss_mib(),
        scores: &scores,
    };
    cogeo::io::write_atomic(&out.join("report.json"), |w| {
        serde_json::to_writer_pretty(&mut *w, &report)?;
        Ok(())
    })?;
    batch.commit()?;
    let bg = removal.report.background_psnr_vs_original.mean;
    let gt = scores
        .held_out_vs_ground_truth
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
