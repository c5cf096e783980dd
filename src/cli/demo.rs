//! `cogeo demo`, the main job on built-in data: a synthetic multi-object scene generated, trained,
//! tagged, and two or more objects removed, by running the other subcommands as a user would type
//! them; then scored against the exact ground truth beside plain deletion, with strips, a contact
//! sheet, metrics.json and report.md.

use super::args::DeviceArgs;
use anyhow::{anyhow, bail, Context, Result};
use clap::Args;
use cogeo::image_ops::hstack_rgb8;
use cogeo::pipeline::{self, Capture, Chosen, Layout, Objects};
use std::path::PathBuf;

#[derive(Args)]
pub struct DemoArgs {
    /// Output folder: data/, train/, tagged.ply, removal/, removal_only/, strips/,
    /// contact_sheet.png, metrics.json, report.md. A previous demo's folder is replaced; any other
    /// non-empty folder is refused.
    #[arg(long, default_value = "demo_out")]
    pub out: PathBuf,
    /// Small and fast (64x48, 16 views, 3 objects, 500 training iterations) instead of 256x192, 24
    /// views, 4 objects, 500 iterations: about 20 seconds instead of about 4-5 minutes on 2 CPU cores.
    #[arg(long)]
    pub quick: bool,
    /// Labels of the synth objects to remove at once (the scene has 3 in --quick, 4 otherwise).
    #[arg(long, value_delimiter = ',', default_value = "1,2", value_parser = cogeo::flag_values::parse_object_label)]
    pub labels: Vec<u8>,
    /// Scene seed (object placement and textures).
    #[arg(long, default_value_t = 2)]
    pub seed: u64,
    /// LPIPS and FID networks for the report (see `cogeo eval --help`); scripts/demo.sh passes the
    /// shared LPIPS network when it is there.
    #[command(flatten)]
    pub models: cogeo::eval::models::MetricModels,
    #[command(flatten)]
    pub device: DeviceArgs,
}

/// Rays per pixel along each axis of the demo's synth photos.
const SUPERSAMPLE: u32 = 4;

/// Marks a folder written by `cogeo demo`, so a rerun may replace it.
pub const DEMO_MARKER: &str = ".cogeo-demo";

/// Runs the demo; `run_command` runs one cogeo command line (the subcommands' own parser and
/// dispatch, passed in by the caller).
pub fn run(a: DemoArgs, run_command: &dyn Fn(&[String]) -> Result<()>) -> Result<()> {
    use cogeo::eval::folder::{evaluate, EvalConfig, Protocol};
    use cogeo::scene::dataset::{find_image, load_rgb};
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
    // The full demo is sized to finish in 5 minutes on 2 CPU cores through lavapipe: 1500 sparse
    // points per view (31.5k Gaussians; the synth default of one per 12 pixels would give 86k, and
    // every pass but the blends scales with them) and new Gaussians from every second hole pixel in
    // x and y (stride 2: 8k instead of 36k, which made refinement twice as slow for -0.05 dB).
    let (width, height, views, objects, iters) = if a.quick { (64, 48, 16, 3, 500) } else { (256, 192, 24, 4, 500) };
    let (points_per_view, stride) = if a.quick { (width * height / 12, 1) } else { (1500, 2) };
    if a.labels.is_empty() || a.labels.iter().any(|&l| l == 0 || l as usize > objects) {
        bail!("--labels must name objects 1..={objects} of the demo scene");
    }
    let p = |name: &str| out.join(name).to_string_lossy().into_owned();
    let labels = a.labels.iter().map(|l| l.to_string()).collect::<Vec<_>>().join(",");
    let device = a.device.command_line();
    let s = |v: &[&str]| v.iter().map(|x| x.to_string()).collect::<Vec<String>>();
    let (data, layout) = (out.join("data"), Layout { out });
    let capture = Capture::at(&data);
    let mut train = pipeline::train(&capture, &layout.train());
    train.extend(pipeline::synth_training(iters, a.seed));
    let remove = |dir: &str, extra: &[&str]| {
        let mut v = pipeline::remove(&layout.tagged(), &capture, Chosen::Labels(&labels), &out.join(dir));
        v.extend(s(&["--stride", &stride.to_string()]));
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
                "--points-per-view",
                &points_per_view.to_string(),
                // a camera integrates light over each pixel; one ray per pixel gives aliased
                // photos whose fine checkerboard no two views agree on (as the removal bench,
                // 4x4 rays: 6 s instead of 1 for the full demo)
                "--supersample",
                &SUPERSAMPLE.to_string(),
            ]),
        ),
        ("train", train),
        (
            "tag",
            pipeline::tag(
                &layout.trained_scene(),
                &capture,
                Objects::Masks("object_mask"),
                Some("vote"),
                &layout.tagged(),
            ),
        ),
        ("remove", remove("removal", &[])),
        ("removal-only baseline", remove("removal_only", &["--removal-only"])),
    ];
    let mut timings = serde_json::Map::new();
    let mut commands = Vec::new();
    for (i, (name, mut args)) in steps.into_iter().enumerate() {
        eprintln!("== {}/{} {name}", i + 1, 6);
        // synth ray-casts on the CPU and takes no device flags
        if name != "synth" {
            args.extend(device.iter().cloned());
        }
        let t = std::time::Instant::now();
        run_command(&args).with_context(|| format!("demo step {name}"))?;
        timings.insert(name.to_string(), t.elapsed().as_secs_f64().into());
        commands.push(format!("cogeo {}", args.join(" ")));
    }
    eprintln!("== 6/6 evaluate against the exact object-free ground truth");
    let t = std::time::Instant::now();
    let truth = cogeo::synth::ground_truth(&data, &a.labels);
    let thresholds = cogeo::eval::folder::SynthThresholds::default();
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
            tau: thresholds.tau,
            leftover_margin: thresholds.leftover_margin,
            lpips: a.models.lpips_model.clone(),
            lpips_input: a.models.lpips_input(),
            lpips_min_side: a.models.lpips_min_side,
            fid: a.models.fid_model.clone(),
            fid_input: a.models.fid_input(),
            fit_exposure: false,
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
        let (w, h, strip) = hstack_rgb8(&refs, width as usize, height as usize);
        cogeo::io::write_png(&out.join(format!("strips/{name}.png")), w, h, image::ColorType::Rgb8, &strip)?;
        if sheet_h > 0 {
            sheet.extend(std::iter::repeat_n(255u8, w as usize * 2 * 3));
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
            "| {name} | {} | {} | {} | {} | {} | {} | {} | {} | {} |\n",
            f(&m["mask"]["psnr"]),
            f3(&m["mask"]["ssim"]),
            f3(&m["lpips"]["mask"]),
            f(&m["bbox"]["psnr"]),
            f(&m["full"]["psnr"]),
            f(&m["seen_elsewhere"]["psnr"]),
            f(&m["never_seen"]["psnr"]),
            f3(&m["leftover"]),
            f(&m["floaters"]["score"]),
        )
    };
    let mut md = format!(
        "# cogeo demo: removing objects {labels} from a synthetic scene\n\n\
         {width}x{height} ({SUPERSAMPLE}x{SUPERSAMPLE} rays per pixel), {views} views ({} held out), {objects} objects, {iters} training iterations, on {}.\n\
         Total {total:.0} s.\n\n\
         Held-out views against the exact object-free ground truth (the scene ray-cast without the\n\
         objects), inside the removed objects' silhouettes:\n\n\
         | method | masked PSNR | masked SSIM | masked LPIPS | bbox PSNR | full PSNR | seen-elsewhere PSNR | never-seen PSNR | leftover | floaters |\n\
         |---|---:|---:|---:|---:|---:|---:|---:|---:|---:|\n",
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
