//! The removal results table: a fixed set of `cogeo synth` scenes (one object, and several objects
//! removed at once), each trained and tagged once, then removed with the full pipeline and with
//! each ablation / baseline. Scored on the held-out views against the exact object-free ground
//! truth with `cogeo eval`. Beside them, real-photo scenes (removal_real.rs): objects composited
//! into the shared captures, whose original photos are the ground truth. One scene's training,
//! variants and scoring are removal_training.rs.
//!
//!   cargo bench --bench removal [-- --scenes one,two-of-three,three-of-four --iters 500
//!                                  --width 160 --height 120 --views 16 --supersample 1 --repeat-full
//!                                  --retrain 2 --lpips-model lpips.onnx --fid-model inception.onnx
//!                                  --exposure-jitter 0.2 --variants "cogeo (full),removal only"
//!                                  --real-downscale 1 --real-iters 800 --reuse-composites
//!                                  --real-exposure cup --removal-seeds 3
//!                                  --no-results --remove-args "--refine-coverage-weight 1"]
//!
//! `--scenes` names scenes, or the groups `synth` (the default: the three rooms), `real`
//! (statue-one, statue-two-of-three, cup-one, cup-two-of-three; hours on 2 CPU cores at full
//! size, `--real-downscale 2` for a quicker look; per capture, e.g. `statue=1,cup=1.5`, where a
//! factor that is not whole resamples the photos) or `all`. Synth scenes write
//! bench/results/removal-<device>.json and .md, bench/results/removal-example.png (input,
//! removal only, cogeo, ground truth on one held-out view), and replace the table between the
//! `removal-table` markers of bench/RESULTS.md (unless --no-results); real scenes write
//! removal-real-<device>.json, removal-real-contact-sheet.png and the `removal-real-table`
//! markers; a rerun of some real scenes or variants keeps the others' rows (the real scenes
//! also have `CAPTURE_CEILING`, the capture trained without the objects, which removes
//! nothing: the ceiling of every variant), and `--real-table-only` rebuilds
//! the table and sheet from the stored rows without running anything. `--reuse-composites` keeps
//! each real scene's trained and tagged composite and reuses it on later runs (removal_real.rs),
//! so that runs of two commits compare on the same training. `--real-exposure cup` trains that
//! capture's composites with `--exposure` and scores them with `eval --fit-exposure` (its rows
//! say so). `--variants` keeps the
//! variants whose names start with one of the given prefixes.
//! `--supersample N` makes the scenes with
//! N x N rays per pixel (anti-aliased; files get an `-aaN` suffix). `--repeat-full` runs the full
//! pipeline a second time on the same trained scene, which shows the run-to-run spread (float
//! atomics in the GPU passes) that any difference between variants must exceed. `--retrain N`
//! trains each scene N more times with other seeds and runs the full pipeline and its closest
//! rivals (`RETRAIN_VARIANTS`) on each: the spread across trainings, in its own table.
//! `--removal-seeds N` runs the full pipeline and its rivals (`SEEDED_VARIANTS`) with `cogeo remove
//! --seed` 0 to N-1 on the same training: each row is the run of median masked LPIPS, and the
//! real scenes' first yardstick takes the median over the seeds of the difference at each seed.
//! `--remove-args "..."` adds those flags to every `cogeo remove` the bench runs, to measure a
//! lever on every variant and seed alike; it needs `--no-results` (a trial run, into a folder
//! under the system's temporary directory: `common::results_path`), and a trial's real table
//! keeps only the stored rows made with the same flags.
//! `--exposure-jitter X` makes scenes whose views' exposure gains vary by +-X and runs only the
//! full pipeline, on a training without and one with `--exposure`, into the `removal-exposure-table`
//! markers instead.

#[path = "common.rs"]
mod common;
#[path = "removal_real.rs"]
mod removal_real;
#[path = "removal_training.rs"]
mod removal_training;

use common::{cogeo, read_json, s};
use removal_training::Training;

use serde_json::{json, Value};
use std::path::{Path, PathBuf};

struct SceneSpec {
    name: &'static str,
    objects: usize,
    labels: &'static str,
    seed: u64,
}

const SCENES: [SceneSpec; 3] = [
    SceneSpec { name: "one", objects: 1, labels: "1", seed: 5 },
    SceneSpec { name: "two-of-three", objects: 3, labels: "1,2", seed: 2 },
    SceneSpec { name: "three-of-four", objects: 4, labels: "1,2,3", seed: 7 },
];

/// The diagnostic variant fed the ground truth itself as its per-view inpainting (`--inpainted`):
/// perfect 2D inpainting, the ceiling of the 3D half of the pipeline. Without color transfer
/// (`--no-transfer`): the transfer overwrites the inpainting wherever a photo saw the surface,
/// every fill pixel of the cup composites, where the variant with it scored the full pipeline's
/// numbers (cup-one 25.86 / 0.186 masked PSNR / LPIPS, 27.01 / 0.149 without it); the synth
/// rooms one / two-of-three / three-of-four, by hand on one training each, 27.37 / 26.81 / 27.58
/// with it and 27.73 / 27.41 / 28.11 without.
const PERFECT_INPAINTING: &str = "perfect inpainting (ground truth as --inpainted, no color transfer)";

/// The same fed on the median rendered depth (`--rendered-depth median`), beside the depth the
/// photos choose: on a glossy surface they choose the expected depth, which follows the
/// reflections behind it (4-10 % behind the cup composites' desk), while the median depth lies on
/// the surface. Fills that agree across views want the surface: by hand this variant scored
/// 0.9-2.4 dB over the one above on statue-one and the cups, at or above the capture's own
/// training (bench/JOURNAL.md, 2026-12-04). It is the 3D half's ceiling with its geometry right.
const PERFECT_INPAINTING_MEDIAN: &str =
    "perfect inpainting on the median depth (ground truth as --inpainted, no color transfer, --rendered-depth median)";

/// The diagnostic pair for inventions that disagree across views. The consistent source: the
/// built-in fill run with `--share-inventions` (one view invents each surface point no photo saw,
/// the others take its colours there, warped at their completed depths), its completed views
/// (`inpainted/` of a `--no-refine` run) fed back as `--inpainted`, once for each of seeds 1, 2
/// and 3. The disagreeing one: the plain built-in fill, each view its own search over its own
/// image (its randomness a hash of the seed, the pass and the pixel), so that no two views invent
/// a surface point alike, view i taken from the run of seed `rotation[i % 3]`, once for each of
/// the three rotations, so that every view meets each seed once. (Until the session of
/// 2026-12-03, 13:21 the first side was the plain fill of one seed: its views disagree as much as
/// the mixed seeds' do, so the yardstick compared two draws of one kind.) Each row is the run of
/// median masked LPIPS (`median_run`): a run's LPIPS moves with its seeds alone by several
/// percent, more than the yardstick between the two (the held-out renders as sharp with the
/// disagreeing views, masked LPIPS no worse than with one consistent source), so both sides are
/// the median of three.
const CONSISTENT_SOURCE: &str =
    "one consistent source (the fill of seed 1, 2 or 3 with shared inventions as --inpainted: the median run)";
const DISAGREEING: &str =
    "disagreeing inpaintings (seeds 1-3 view by view as --inpainted, in three rotations: the median run)";
const DISAGREEING_SEEDS: [u64; 3] = [1, 2, 3];
/// The disagreeing variant's runs: view i takes the fill of `rotation[i % 3]`.
const DISAGREEING_ROTATIONS: [[u64; 3]; 3] = [[1, 2, 3], [2, 3, 1], [3, 1, 2]];

/// The variants `--removal-seeds N` runs once per `cogeo remove --seed` (0 to N-1): the full
/// pipeline and the rivals its first yardstick compares it with (removal only has no seed). On
/// the real composites one removal's masked PSNR moves with its seed alone by up to 1.2 dB
/// (cup-two-of-three, seeds 0-2: the full pipeline 28.17 / 28.04 / 27.01, the harmonic fill 28.17
/// / 28.04 / 27.04), more than the margins that yardstick reads there.
const SEEDED_VARIANTS: [&str; 3] =
    ["cogeo (full)", "harmonic fill (no texture synthesis)", "nearest-copy fill (GG-style)"];

/// The diagnostic row of the real scenes without any removal: the capture trained on its own
/// photos, without the objects (the cached training the objects were composited by), rendered at
/// the held-out views. No removal can do better than a training that saw the background, so this
/// is the ceiling of every variant, and its masked PSNR against the perfect inpaintings' says how
/// much the composite's own training, not the fill, costs. The synth rooms have no such training.
const CAPTURE_CEILING: &str = "capture without the objects (its own training, no removal)";

/// (name, tagging method, extra `cogeo remove` flags)
const VARIANTS: [(&str, &str, &[&str]); 14] = [
    ("cogeo (full)", "vote", &[]),
    ("removal only", "vote", &["--removal-only"]),
    ("harmonic fill (no texture synthesis)", "vote", &["--inpainter", "harmonic"]),
    ("no depth guidance", "vote", &["--no-depth-guidance"]),
    ("no color transfer", "vote", &["--no-transfer"]),
    ("2D-projection selection", "project", &[]),
    ("no refinement", "vote", &["--no-refine"]),
    ("nearest-copy fill (GG-style)", "vote", &["--fill", "nearest-copy"]),
    (PERFECT_INPAINTING, "vote", &["--no-transfer"]),
    (PERFECT_INPAINTING_MEDIAN, "vote", &["--no-transfer", "--rendered-depth", "median"]),
    ("shared inventions (one per surface point)", "vote", &["--share-inventions"]),
    (CONSISTENT_SOURCE, "vote", &[]),
    (DISAGREEING, "vote", &[]),
    (CAPTURE_CEILING, "vote", &[]),
];

/// The variants run again on every extra training of `--retrain`: the full pipeline and the
/// strongest of the others in the table (the ablations closest to it, and the GG-style baseline).
const RETRAIN_VARIANTS: [&str; 4] =
    ["cogeo (full)", "harmonic fill (no texture synthesis)", "no color transfer", "nearest-copy fill (GG-style)"];

fn num(v: &Value, digits: usize) -> String {
    match v.as_f64() {
        Some(x) if x.is_finite() => format!("{x:.digits$}"),
        _ => "n/a".into(),
    }
}

fn main() {
    let args = common::args();
    let arg = |n: &str, d: &str| common::arg(&args, n).unwrap_or_else(|| d.to_string());
    let wanted: Vec<String> =
        arg("--scenes", "one,two-of-three,three-of-four").split(',').map(str::to_string).collect();
    let (iters, width, height, views) =
        (arg("--iters", "500"), arg("--width", "160"), arg("--height", "120"), arg("--views", "16"));
    let supersample = arg("--supersample", "1");
    let repeat_full = args.iter().any(|a| a == "--repeat-full");
    let retrain: u64 = arg("--retrain", "0").parse().expect("--retrain takes a count");
    let removal_seeds: u64 = arg("--removal-seeds", "1").parse().expect("--removal-seeds takes a count");
    // added to every variant's removals: only on a trial run (`--no-results`), since the rows'
    // names do not say them (each run's JSON does, `remove_args`)
    let remove_args = common::remove_args(&args);
    if !remove_args.is_empty() && !common::trial_run(&args) {
        eprintln!("--remove-args changes every variant, which the table's rows do not name: add --no-results");
        std::process::exit(2);
    }
    // captures whose views' exposure varies: every scene trained without and with --exposure,
    // the full pipeline on each, scored with the held-out views' exposure fitted (its own table)
    let jitter = arg("--exposure-jitter", "0");
    let jittered = jitter.parse::<f64>().expect("--exposure-jitter takes a number") > 0.0;
    let mut variants: Vec<(&str, &str, &[&str])> = VARIANTS.to_vec();
    if jittered {
        variants = vec![VARIANTS[0]];
    }
    // --variants "cogeo (full),removal only,...": only those (each a prefix of a variant's name)
    if let Some(only) = common::arg(&args, "--variants") {
        let prefixes: Vec<&str> = only.split(',').collect();
        variants.retain(|v| prefixes.iter().any(|p| v.0.starts_with(p)));
    }
    if repeat_full {
        variants.insert(1, ("cogeo (full, second run)", "vote", &[]));
    }
    // the real LPIPS network beside the project when no other is named (../shared/models)
    let shared_lpips = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../shared/models/lpips_alex_v0.1.onnx");
    let lpips = common::arg(&args, "--lpips-model")
        .or_else(|| shared_lpips.exists().then(|| shared_lpips.to_string_lossy().into_owned()));
    match &lpips {
        Some(m) => eprintln!("LPIPS network: {m}"),
        None => eprintln!("no LPIPS network (--lpips-model): LPIPS columns read n/a"),
    }
    let fid = common::arg(&args, "--fid-model");
    let root = std::env::temp_dir().join(format!("cogeo_bench_removal_{}", std::process::id()));
    let p = |x: &Path| x.to_string_lossy().into_owned();
    let mut rows = Vec::new();
    let mut retrained = Vec::new();
    let mut device = String::new();
    let mut example: Option<(PathBuf, PathBuf, PathBuf, PathBuf, &str)> = None;
    let named = |name: &str, group: &str| wanted.iter().any(|w| w == name || w == group || w == "all");
    let real: Vec<&removal_real::RealSpec> =
        removal_real::REAL_SCENES.iter().filter(|s| named(s.name, "real")).collect();
    if !real.is_empty() {
        removal_real::run(&args, &real, &variants, &lpips, &fid, &root, removal_seeds, &remove_args);
    }
    let synth: Vec<&SceneSpec> = SCENES.iter().filter(|s| named(s.name, "synth")).collect();
    if synth.is_empty() {
        std::fs::remove_dir_all(&root).ok();
        return;
    }
    for spec in synth.iter().copied() {
        eprintln!("scene {} ({} object(s), removing {})", spec.name, spec.objects, spec.labels);
        let dir = root.join(spec.name);
        let data = dir.join("data");
        cogeo(&s(&[
            "synth",
            "--out",
            &p(&data),
            "--width",
            &width,
            "--height",
            &height,
            "--views",
            &views,
            "--objects",
            &spec.objects.to_string(),
            "--seed",
            &spec.seed.to_string(),
            "--gt-without",
            spec.labels,
            "--supersample",
            &supersample,
            "--exposure-jitter",
            &jitter,
        ]));
        let labels: Vec<u8> = spec.labels.split(',').map(|l| l.parse().unwrap()).collect();
        let truth = cogeo::synth::ground_truth(&data, &labels);
        assert!(truth.exact, "{}: no exact ground truth for removing {}", data.display(), spec.labels);
        let mut run = Training {
            name: spec.name,
            labels: spec.labels,
            data: &data,
            truth: &truth.images,
            iters: &iters,
            lpips: &lpips,
            fid: &fid,
            exposure: false,
            fit_exposure: jittered,
            reuse: None,
            original: None,
            removal_seeds,
            remove_args: &remove_args,
        };
        for r in run.variants(&dir, spec.seed, &variants) {
            device = r["device"].as_str().unwrap_or("?").to_string();
            rows.push(r);
        }
        if jittered {
            run.exposure = true;
            rows.extend(run.variants(&dir.join("exposure"), spec.seed, &variants));
            continue;
        }
        for i in 1..=retrain {
            let seed = spec.seed + 1000 * i;
            eprintln!("scene {}: extra training {i} of {retrain} (seed {seed})", spec.name);
            let chosen: Vec<_> = variants.iter().filter(|v| RETRAIN_VARIANTS.contains(&v.0)).cloned().collect();
            retrained.extend(run.variants(&dir.join(format!("retrain_{i}")), seed, &chosen));
        }
        // variant 0 is the full pipeline
        // the example image needs removal only beside the full pipeline (--variants may leave it out)
        let Some(only) = variants.iter().position(|v| v.0 == "removal only") else { continue };
        if spec.name == "two-of-three" || example.is_none() {
            example = Some((
                data.clone(),
                truth.images.clone(),
                dir.join(format!("variant_{only}")),
                dir.join("variant_0"),
                spec.name,
            ));
        }
    }
    if jittered {
        exposure_table(&args, &rows, &jitter, &iters, &device);
        std::fs::remove_dir_all(&root).ok();
        return;
    }
    // the table
    let rays = if supersample == "1" {
        "one ray per pixel".to_string()
    } else {
        format!("{supersample}x{supersample} rays per pixel")
    };
    let mut md = format!(
        "Removal on `cogeo synth` scenes ({width}x{height}, {rays}, {views} views, every 8th held out; {iters} \
         training iterations; vote tags unless noted), `cargo bench --bench removal`, on {device}. Held-out views against \
         the exact ground truth (the scene ray-cast without the removed objects only): PSNR/SSIM inside the removed objects' silhouettes (mask), on the \
         silhouettes' bounding box (bbox), on the never-seen part of the mask; leftover = share of mask pixels that \
         still look like the object; floaters = opacity-weighted count of Gaussians off the true surface by more than \
         5 % in every view of the mask; time = the whole `cogeo remove` run; memory = its peak resident set.\n\n\
         | scene | variant | masked PSNR | masked SSIM | masked LPIPS | seen-elsewhere PSNR | seen-elsewhere LPIPS | never-seen PSNR | never-seen LPIPS | outside PSNR | bbox PSNR | leftover | floaters | time s | peak MiB |\n\
         |---|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|\n"
    );
    for r in &rows {
        let m = &r["metrics"];
        md += &format!(
            "| {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} |\n",
            r["scene"].as_str().unwrap(),
            r["variant"].as_str().unwrap(),
            num(&m["mask"]["psnr"], 2),
            num(&m["mask"]["ssim"], 3),
            num(&m["lpips"]["mask"], 3),
            num(&m["seen_elsewhere"]["psnr"], 2),
            num(&m["lpips"]["seen_elsewhere"], 3),
            num(&m["never_seen"]["psnr"], 2),
            num(&m["lpips"]["never_seen"], 3),
            num(&m["outside"]["psnr"], 2),
            num(&m["bbox"]["psnr"], 2),
            num(&m["leftover"], 3),
            num(&m["floaters"]["score"], 1),
            num(&r["total_seconds"], 1),
            num(&r["peak_rss_mib"], 0),
        );
    }
    md += "\nMean over the scenes:\n\n| variant | masked PSNR | masked SSIM | masked LPIPS | seen-elsewhere PSNR | never-seen PSNR | never-seen LPIPS | bbox PSNR |\n|---|---:|---:|---:|---:|---:|---:|---:|\n";
    for (variant, _, _) in variants.iter() {
        let sel: Vec<&Value> = rows.iter().filter(|r| r["variant"] == *variant).collect();
        let mean = |f: &dyn Fn(&Value) -> Option<f64>| {
            let v: Vec<f64> = sel.iter().filter_map(|r| f(&r["metrics"])).collect();
            if v.is_empty() {
                json!(null)
            } else {
                json!(v.iter().sum::<f64>() / v.len() as f64)
            }
        };
        md += &format!(
            "| {variant} | {} | {} | {} | {} | {} | {} | {} |\n",
            num(&mean(&|m| m["mask"]["psnr"].as_f64()), 2),
            num(&mean(&|m| m["mask"]["ssim"].as_f64()), 3),
            num(&mean(&|m| m["lpips"]["mask"].as_f64()), 3),
            num(&mean(&|m| m["seen_elsewhere"]["psnr"].as_f64()), 2),
            num(&mean(&|m| m["never_seen"]["psnr"].as_f64()), 2),
            num(&mean(&|m| m["lpips"]["never_seen"].as_f64()), 3),
            num(&mean(&|m| m["bbox"]["psnr"].as_f64()), 2)
        );
    }
    let stages = common::REMOVAL_STAGES;
    md += "\nSeconds per stage of the full pipeline:\n\n| scene |";
    for stage in stages {
        md += &format!(" {} |", stage.replace('_', " "));
    }
    md += &format!("\n|---|{}\n", "---:|".repeat(stages.len()));
    for r in rows.iter().filter(|r| r["variant"] == "cogeo (full)") {
        md += &format!("| {} |", r["scene"].as_str().unwrap());
        for stage in stages {
            let digits = if stage == "refine" { 1 } else { 2 };
            md += &format!(" {} |", num(&r["stage_seconds"][stage], digits));
        }
        md += "\n";
    }
    if retrain > 0 {
        md += &format!(
            "\nSpread across trainings (`--retrain {retrain}`): each scene trained {} times (seeds s, s + 1000, ...), \
             the full pipeline and its closest rivals run on each; min / median / max over the trainings:\n\n\
             | scene | variant | masked PSNR | masked LPIPS | seen-elsewhere gap dB | never-seen PSNR | never-seen LPIPS |\n|---|---|---|---|---|---|---|\n",
            retrain + 1
        );
        for spec in synth.iter() {
            for variant in RETRAIN_VARIANTS {
                let sel: Vec<&Value> = rows
                    .iter()
                    .chain(&retrained)
                    .filter(|r| r["scene"] == spec.name && r["variant"] == variant)
                    .map(|r| &r["metrics"])
                    .collect();
                let spread = |f: &dyn Fn(&Value) -> Option<f64>, digits: usize| {
                    let mut v: Vec<f64> = sel.iter().filter_map(|m| f(m)).collect();
                    if v.is_empty() {
                        return "n/a".to_string();
                    }
                    v.sort_by(f64::total_cmp);
                    let at = |x: f64| num(&json!(x), digits);
                    format!("{} / {} / {}", at(v[0]), at(v[v.len() / 2]), at(v[v.len() - 1]))
                };
                // the yardstick: held-out PSNR outside the masks minus seen-elsewhere PSNR
                let gap = |m: &Value| Some(m["outside"]["psnr"].as_f64()? - m["seen_elsewhere"]["psnr"].as_f64()?);
                md += &format!(
                    "| {} | {variant} | {} | {} | {} | {} | {} |\n",
                    spec.name,
                    spread(&|m| m["mask"]["psnr"].as_f64(), 2),
                    spread(&|m| m["lpips"]["mask"].as_f64(), 3),
                    spread(&gap, 2),
                    spread(&|m| m["never_seen"]["psnr"].as_f64(), 2),
                    spread(&|m| m["lpips"]["never_seen"].as_f64(), 3),
                );
            }
        }
    }
    println!("{md}");
    let slug: String =
        device_slug(&device) + &if supersample == "1" { String::new() } else { format!("-aa{supersample}") };
    common::write_json(
        &common::results_path(&format!("removal-{slug}.json")),
        &json!({ "device": device, "supersample": supersample, "rows": rows, "retrained": retrained }),
    );
    let md_path = common::results_path(&format!("removal-{slug}.md"));
    std::fs::write(&md_path, &md).unwrap();
    println!("wrote {}", md_path.display());
    // the example image: input | removal only | cogeo | ground truth, first held-out view
    let mut image_line = String::new();
    if let Some((data, truth, only, full, scene)) = &example {
        let first = read_json(&full.join("metrics.json"))["views"][0]["name"].as_str().unwrap().to_string();
        let imgs: Vec<image::RgbImage> =
            [data.join("images"), only.join("test_after"), full.join("test_after"), truth.clone()]
                .iter()
                .map(|d| image::open(d.join(format!("{first}.png"))).unwrap().to_rgb8())
                .collect();
        let (w, h) = imgs[0].dimensions();
        let k = 3;
        let mut strip = image::RgbImage::from_pixel(4 * w * k + 6, h * k, image::Rgb([255, 255, 255]));
        for (i, im) in imgs.iter().enumerate() {
            for y in 0..h * k {
                for x in 0..w * k {
                    strip.put_pixel(i as u32 * (w * k + 2) + x, y, *im.get_pixel(x / k, y / k));
                }
            }
        }
        let name = format!("removal-example{}.png", &slug[slug.find("-aa").unwrap_or(slug.len())..]);
        let path = common::results_path(&name);
        strip.save(&path).unwrap();
        println!("wrote {}", path.display());
        image_line = format!(
            "\n![input, removal only, cogeo, ground truth](results/{name})\n\n\
             Held-out view {first} of the {scene} scene: input, removal only, cogeo, ground truth.\n"
        );
    }
    common::update_results(&args, "removal-table", &format!("{md}{image_line}"));
    std::fs::remove_dir_all(&root).ok();
}

/// The first three words of the device's name, e.g. "llvmpipe-llvm-15".
fn device_slug(device: &str) -> String {
    device
        .to_lowercase()
        .split(|c: char| !c.is_ascii_alphanumeric())
        .filter(|w| !w.is_empty())
        .take(3)
        .collect::<Vec<_>>()
        .join("-")
}

/// The `--exposure-jitter` table: each scene's full pipeline trained without and with
/// `--exposure`, held-out views scored with their exposure fitted outside the mask.
fn exposure_table(args: &[String], rows: &[Value], jitter: &str, iters: &str, device: &str) {
    let mut md = format!(
        "Removal on `cogeo synth` scenes whose views' exposure gains are jittered by +-{jitter} per channel \
         (`cargo bench --bench removal -- --exposure-jitter {jitter}`; {iters} training iterations), on {device}: the \
         full pipeline on a scene trained without and with `--exposure` (whose maps `cogeo remove --exposure` \
         takes). Held-out views against the exact ground truth, each render mapped through the affine color map \
         fitted on its pixels outside the mask (`cogeo eval --fit-exposure`; the held-out photo's exposure is \
         unknown to any scene); train test PSNR is the training's held-out PSNR, raw / exposure fitted.\n\n\
         | scene | training | train test PSNR | masked PSNR | seen-elsewhere PSNR | never-seen PSNR | outside PSNR |\n\
         |---|---|---:|---:|---:|---:|---:|\n"
    );
    for r in rows {
        let m = &r["metrics"];
        md += &format!(
            "| {} | {} | {} / {} | {} | {} | {} | {} |\n",
            r["scene"].as_str().unwrap(),
            if r["exposure"].as_bool() == Some(true) { "--exposure" } else { "plain" },
            num(&r["train_test_psnr"], 2),
            num(&r["train_test_psnr_exposure_fitted"], 2),
            num(&m["mask"]["psnr"], 2),
            num(&m["seen_elsewhere"]["psnr"], 2),
            num(&m["never_seen"]["psnr"], 2),
            num(&m["outside"]["psnr"], 2),
        );
    }
    println!("{md}");
    common::write_json(
        &common::results_path("removal-exposure.json"),
        &json!({ "device": device, "jitter": jitter, "rows": rows }),
    );
    common::update_results(args, "removal-exposure-table", &md);
}
