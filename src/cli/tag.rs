//! `cogeo tag`: an object label for every Gaussian from per-view masks or text prompts.

use super::args::{load_scene, open_gpu, progress, CaptureArgs, DeviceArgs};
use anyhow::{bail, Context, Result};
use clap::Args;
use cogeo::scene::{ply, Camera};
use indicatif::{ProgressBar, ProgressStyle};
use std::io::IsTerminal;
use std::path::PathBuf;

#[derive(Args)]
pub struct TagArgs {
    /// Trained scene (INRIA PLY), e.g. the scene.ply of `cogeo train`. Not modified.
    #[arg(long)]
    pub scene: PathBuf,
    /// Dataset folder the scene was trained from (COLMAP model or transforms.json + images; cameras
    /// and the split).
    #[arg(long)]
    pub data: PathBuf,
    #[command(flatten)]
    pub capture: CaptureArgs,
    /// Masks: a folder of 8-bit instance maps named like the images (pixel value q = object q,
    /// 0 = background, 255 = ignore), or a folder of per-object subfolders holding binary masks
    /// (nonzero = object; objects numbered 1.. in sorted subfolder order). Relative paths are tried
    /// against the current directory, then inside --data.
    #[arg(long, required_unless_present = "prompt")]
    pub masks: Option<PathBuf>,
    /// Text prompts instead of masks, comma-separated or repeated (object q = the q-th prompt):
    /// needs --detector, --segmenter and --prompt-embeddings. The label maps made are written to
    /// `<out>_prompt_masks/` for inspection and reuse as --masks.
    #[arg(long, value_delimiter = ',', conflicts_with = "masks")]
    pub prompt: Vec<String>,
    #[command(flatten)]
    pub prompt_models: cogeo::tag::prompt::PromptModels,
    /// Output tagged PLY (properties f_obj_* for distill, label, label_prob); the sidecar
    /// `<out>.json` holds the classifier and the report.
    #[arg(long)]
    pub out: PathBuf,
    #[command(flatten)]
    pub options: cogeo::tag::TagOptions,
    #[command(flatten)]
    pub device: DeviceArgs,
}

pub fn run(a: TagArgs) -> Result<()> {
    use cogeo::tag::{self, labels, Method};
    let scene = load_scene(&a.scene)?;
    let opts = &a.options;
    if opts.distill.dim == 0 || opts.distill.dim > tag::distill::MAX_DIM {
        bail!("--dim must be 1..={}", tag::distill::MAX_DIM);
    }
    if opts.method == Method::Distill && (opts.distill.iters == 0 || opts.distill.knn == 0) {
        bail!("--iters and --knn must be positive");
    }
    if a.out.extension().and_then(|e| e.to_str()) != Some("ply") {
        bail!("{}: --out must name a .ply file", a.out.display());
    }
    let data = cogeo::scene::dataset::load(&a.data, &a.capture.images, a.capture.downscale)?;
    for w in &data.warnings {
        eprintln!("warning: {w}");
    }
    let train_cams: Vec<&Camera> = data.train.iter().map(|v| &v.camera).collect();
    let mut prompt_report = serde_json::Value::Null;
    let (masks, maps) = match &a.masks {
        Some(m) => {
            let masks = if m.is_dir() || m.is_absolute() { m.clone() } else { a.data.join(m) };
            let maps = labels::load(&masks, &data.train.iter().collect::<Vec<_>>())?;
            (masks, maps)
        }
        None => {
            let (Some(det), Some(seg), Some(emb)) =
                (&a.prompt_models.detector, &a.prompt_models.segmenter, &a.prompt_models.prompt_embeddings)
            else {
                bail!(
                    "text prompts need ONNX models: --detector, --segmenter and --prompt-embeddings (contracts in \
                     docs/usage.md); without them, give per-view masks with --masks"
                );
            };
            let mut seg = tag::prompt::PromptSegmenter::load(det, seg, emb, &a.prompt, a.prompt_models.box_threshold)?;
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
                "prompts": a.prompt, "detector": det, "segmenter": seg.segmenter_path(), "box_threshold": a.prompt_models.box_threshold,
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
    let iters = if opts.method == Method::Distill { opts.distill.iters as u64 } else { 0 };
    let bar = ProgressBar::new(iters);
    bar.set_style(
        ProgressStyle::with_template("tag [{bar:30}] {pos}/{len} {elapsed_precise} eta {eta} {msg}")
            .unwrap()
            .progress_chars("=> "),
    );
    let start = std::time::Instant::now();
    let cameras: Vec<Camera> = train_cams.iter().map(|c| (*c).clone()).collect();
    // without a terminal (a pipe, a log file, a batch job) the bar draws nothing: a plain line
    // about every 5 % of the distillation instead, as `train` prints
    let plain_every = (!std::io::stderr().is_terminal() && iters > 0).then(|| (iters / 20).max(1));
    let tagged = tag::tag_scene(&gpu, &scene, &cameras, &maps, opts, |it, losses| {
        bar.set_position(it as u64);
        if let Some((o, s)) = losses {
            bar.set_message(format!("L_obj {o:.4} L_space {s:.5}"));
        }
        if plain_every.is_some_and(|n| (it as u64).is_multiple_of(n)) {
            let losses = losses.map(|(o, s)| format!(" L_obj {o:.4} L_space {s:.5}")).unwrap_or_default();
            eprintln!("tag {it}/{iters} {:.0} s{losses}", start.elapsed().as_secs_f64());
        }
    })?;
    bar.finish_and_clear();
    let seconds = start.elapsed().as_secs_f64();
    let counts: Vec<usize> =
        (0..maps.classes()).map(|q| tagged.tags.labels.iter().filter(|&&l| l as usize == q).count()).collect();
    // held-out evaluation where masks for the test views exist
    let test_cams: Vec<&Camera> = data.test.iter().map(|v| &v.camera).collect();
    let held_out = match labels::load(&masks, &data.test.iter().collect::<Vec<_>>()) {
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
        "method": opts.method,
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
    if let Some(dir) = a.out.parent().filter(|d| !d.as_os_str().is_empty()) {
        std::fs::create_dir_all(dir).with_context(|| format!("{}: cannot create output folder", dir.display()))?;
    }
    let batch = cogeo::io::OutputBatch::begin();
    ply::write_ply(&out_scene, &a.out)?;
    let sidecar = a.out.with_extension("json");
    cogeo::io::write_atomic(&sidecar, |w| {
        serde_json::to_writer_pretty(&mut *w, &report)?;
        Ok(())
    })?;
    batch.commit()?;
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
