//! Removal at real size: `cargo bench --bench removal_speed [-- --baseline OLD_COGEO --repeat 2]`.
//!
//! Trains `../shared/data/statue` at `images_2` (504x378) for 800 iterations and tags it from its
//! removal masks (vote), both cached under target/bench-cache/statue/speed-* so that every run and
//! every binary removes from the same tagged scene. Then times `cogeo remove --labels 1` with the
//! defaults, per stage (the report's stage clock), `--repeat` times: this build's binary and, with
//! `--baseline PATH`, an older one (built in a git worktree), alternately, so that both see the
//! same machine load. `--remove-args "..."` adds flags to every remove (e.g. `--no-refine` for a
//! quick look at the stages before the refinement).
//!
//! The stages that are GPU passes get a roofline: one profiled render of the hole-mask stage (the
//! original scene with the removed Gaussians' weight as a feature), and an iteration of training
//! on the trained scene beside one on the refined scene (the refinement is that training loop,
//! with the scene's learnt SH bands), pass by pass with bytes moved and share of the copy
//! bandwidth, as the train bench shows them.

#[path = "common.rs"]
mod common;

use cogeo::render::{RenderSettings, SceneRenderer};
use cogeo::scene::dataset::Dataset;
use cogeo::scene::GaussianScene;
use cogeo::train::trainer::{TrainConfig, Trainer};
use std::path::{Path, PathBuf};

/// The capture, its images, masks and training, as the speed issue specifies the scene.
const CAPTURE: &str = "statue";
const IMAGES: &str = "images_2";
const MASKS: &str = "images_2/label";
const TRAIN_ITERS: u32 = 800;

fn main() {
    let args = common::args();
    let repeat: usize = common::arg(&args, "--repeat").map_or(2, |r| r.parse().expect("--repeat: a count"));
    let baseline = common::arg(&args, "--baseline").map(PathBuf::from);
    if let Some(b) = &baseline {
        assert!(b.is_file(), "--baseline {}: no such binary", b.display());
    }
    let extra = common::remove_args(&args);
    let capture = common::shared_capture(CAPTURE);
    assert!(capture.is_dir(), "{}: the shared capture is missing", capture.display());
    let cache = prepare(&capture);
    let tagged = cache.join("tagged.ply");

    // the removals, this build and the baseline alternately
    let this_build = PathBuf::from(env!("CARGO_BIN_EXE_cogeo"));
    let mut binaries = vec![("this build", this_build)];
    binaries.extend(baseline.map(|b| ("baseline", b)));
    let scratch = std::env::temp_dir().join(format!("cogeo_bench_removal_speed_{}", std::process::id()));
    let mut runs: Vec<Vec<serde_json::Value>> = vec![Vec::new(); binaries.len()];
    for r in 0..repeat {
        for (b, (name, exe)) in binaries.iter().enumerate() {
            let out = scratch.join(format!("{b}-{r}"));
            let mut a = common::s(&["remove", "--scene"]);
            a.push(tagged.display().to_string());
            a.extend(common::s(&["--data"]));
            a.push(capture.display().to_string());
            a.extend(common::s(&["--images", IMAGES, "--labels", "1", "--out"]));
            a.push(out.display().to_string());
            a.extend(extra.iter().cloned());
            eprintln!("run {} of {repeat}, {name}:", r + 1);
            let wall = common::run_binary(exe, &a);
            let report = common::read_json(&out.join("report.json"));
            runs[b].push(serde_json::json!({"wall_seconds": wall, "seconds": report["seconds"],
                "views": report["views"].as_array().map_or(0, |v| v.len()),
                "refine_iters": report["refine"]["iters"], "gaussians": report["gaussians"]}));
            if b == 0 && r + 1 == repeat && out.join("scene.ply").is_file() {
                std::fs::copy(out.join("scene.ply"), scratch.join("refined.ply"))
                    .expect("cannot keep the refined scene");
            }
            if b > 0 || r + 1 < repeat {
                std::fs::remove_dir_all(&out).ok();
            }
        }
    }

    // GPU profiles: a hole-mask render, a training and a refinement iteration
    let gpu = common::gpu();
    let roof = common::copy_bandwidth(&gpu).roof_gbps();
    let trained = cogeo::scene::ply::read_ply(&tagged).expect("cannot read the tagged scene");
    let data = cogeo::scene::dataset::load(&capture, IMAGES, 1).expect("cannot load the capture");
    let mask_render = profile_mask_render(&gpu, &trained, &data);
    let train_iter = profile_iteration(&gpu, &trained, &data);
    let refined = scratch.join("refined.ply");
    let refine_iter =
        refined.is_file().then(|| profile_iteration(&gpu, &cogeo::scene::ply::read_ply(&refined).unwrap(), &data));
    std::fs::remove_dir_all(&scratch).ok();

    let md = table(&args, &gpu, &binaries, &runs, roof, &mask_render, &train_iter, refine_iter.as_ref());
    common::update_results(&args, "removal-speed", &md);
    let path = common::results_path(&format!("removal_speed-{}.json", common::device_slug(&gpu)));
    let profile = |p: &Profile| {
        serde_json::json!({"gpu_ms": p.stats.medians().iter().map(|t| t.ms).sum::<f64>(),
        "wall_ms": p.wall_ms, "gaussians": p.gaussians, "passes": p.stats.json(roof)})
    };
    common::write_json(
        &path,
        &serde_json::json!({
            "device": gpu.info().summary(), "copy_bandwidth_gbps": roof, "capture": CAPTURE, "images": IMAGES,
            "train_iters": TRAIN_ITERS, "remove_args": extra,
            "binaries": binaries.iter().map(|(n, p)| serde_json::json!({"name": n, "path": p})).collect::<Vec<_>>(),
            "runs": runs, "mask_render": profile(&mask_render), "training_iteration": profile(&train_iter),
            "refinement_iteration": refine_iter.as_ref().map(profile),
        }),
    );
}

/// The trained and tagged capture, made once: target/bench-cache/statue/speed-images_2-800.
fn prepare(capture: &Path) -> PathBuf {
    let cache = common::bench_cache().join(CAPTURE).join(format!("speed-{IMAGES}-{TRAIN_ITERS}"));
    if cache.join("tagged.ply").is_file() {
        eprintln!("reusing the trained and tagged {CAPTURE} in {}", cache.display());
        return cache;
    }
    eprintln!("training and tagging {CAPTURE} into {} (cached for later runs)", cache.display());
    common::make_folder(&cache, |tmp| {
        let cap = capture.display().to_string();
        let run_dir = tmp.join("run").display().to_string();
        let iters = TRAIN_ITERS.to_string();
        common::cogeo(&common::s(&["train", "--data", &cap, "--images", IMAGES, "--iters", &iters, "--out", &run_dir]));
        let scene = tmp.join("run/scene.ply").display().to_string();
        let tagged = tmp.join("tagged.ply").display().to_string();
        common::cogeo(&common::s(&[
            "tag", "--scene", &scene, "--data", &cap, "--images", IMAGES, "--masks", MASKS, "--method", "vote",
            "--out", &tagged,
        ]));
    });
    cache
}

/// GPU passes (median over a few frames or iterations) and the wall time of one.
struct Profile {
    stats: common::PassStats,
    wall_ms: f64,
    gaussians: usize,
}

impl Profile {
    fn gpu_ms(&self) -> f64 {
        self.stats.medians().iter().map(|t| t.ms).sum()
    }

    /// "GPU x ms of y ms wall; the two dearest passes with their share of the copy roof".
    fn summary(&self, roof: f64) -> String {
        let mut passes = self.stats.medians();
        passes.sort_by(|a, b| b.ms.partial_cmp(&a.ms).unwrap());
        let dearest: Vec<String> = passes
            .iter()
            .take(2)
            .map(|t| match t.gbps() {
                Some(g) => format!(
                    "{} {:.0} ms, {:.1} MB at {:.1} % of copy",
                    t.pass,
                    t.ms,
                    t.bytes as f64 / 1e6,
                    100.0 * g / roof
                ),
                None => format!("{} {:.0} ms", t.pass, t.ms),
            })
            .collect();
        format!("GPU {:.0} of {:.0} ms wall; {}", self.gpu_ms(), self.wall_ms, dearest.join("; "))
    }
}

/// One render of the hole-mask stage: the scene with the removed Gaussians' (label 1) weight as
/// a feature, every plane read back, over the first edited view; 3 frames after a warm-up.
fn profile_mask_render(gpu: &cogeo::gpu::Gpu, scene: &GaussianScene, data: &Dataset) -> Profile {
    let labels = cogeo::tag::scene_labels(scene).expect("the tagged scene has no labels");
    let marked: Vec<f32> = labels.iter().map(|&l| (l == 1) as u8 as f32).collect();
    let mut renderer = SceneRenderer::new(gpu, scene, Some((&marked, 1))).unwrap();
    let settings = RenderSettings { features: true, timestamps: true, ..Default::default() };
    let camera = &data.train[0].camera;
    renderer.render(camera, &settings).unwrap();
    let (mut stats, mut wall) = (common::PassStats::default(), Vec::new());
    for _ in 0..3 {
        let t = std::time::Instant::now();
        let o = renderer.render(camera, &settings).unwrap();
        wall.push(t.elapsed().as_secs_f64() * 1e3);
        stats.add(&o.timings);
    }
    Profile { stats, wall_ms: common::median(wall), gaussians: scene.len() }
}

/// A training iteration on `scene` over the capture's views, with the scene's learnt SH bands
/// (what the refinement renders and steps); median of 5 after a warm-up.
fn profile_iteration(gpu: &cogeo::gpu::Gpu, scene: &GaussianScene, data: &Dataset) -> Profile {
    let cfg = TrainConfig { iters: 30_000, sh_degree: scene.sh_degree, densify: false, ..Default::default() };
    let mut trainer = Trainer::new(gpu, data, scene, cfg).unwrap();
    trainer.profile = true;
    trainer.fixed_sh_degree = Some(scene.learnt_sh_degree());
    trainer.iterate(data, false).unwrap();
    let (mut stats, mut wall) = (common::PassStats::default(), Vec::new());
    for _ in 0..5 {
        let t = std::time::Instant::now();
        trainer.iterate(data, false).unwrap();
        wall.push(t.elapsed().as_secs_f64() * 1e3);
        stats.add(&trainer.last_timings);
    }
    Profile { stats, wall_ms: common::median(wall), gaussians: scene.len() }
}

/// Median and spread of `xs` as "m [lo-hi]" (one run: just the value).
fn spread(xs: &[f64], digits: usize) -> String {
    let m = common::median(xs.to_vec());
    let (lo, hi) = xs.iter().fold((f64::MAX, f64::MIN), |(a, b), &x| (a.min(x), b.max(x)));
    if xs.len() < 2 {
        format!("{m:.digits$}")
    } else {
        format!("{m:.digits$} [{lo:.digits$}-{hi:.digits$}]")
    }
}

#[allow(clippy::too_many_arguments)]
fn table(
    args: &[String],
    gpu: &cogeo::gpu::Gpu,
    binaries: &[(&str, PathBuf)],
    runs: &[Vec<serde_json::Value>],
    roof: f64,
    mask_render: &Profile,
    train_iter: &Profile,
    refine_iter: Option<&Profile>,
) -> String {
    let stage =
        |b: usize, s: &str| -> Vec<f64> { runs[b].iter().map(|r| r["seconds"][s].as_f64().unwrap_or(0.0)).collect() };
    let walls = |b: usize| -> Vec<f64> { runs[b].iter().map(|r| r["wall_seconds"].as_f64().unwrap()).collect() };
    let first = &runs[0][0];
    let views = first["views"].as_u64().unwrap_or(0) as f64;
    let iters = first["refine_iters"].as_f64().unwrap_or(0.0);
    let baseline = binaries.len() > 1;
    let what = format!(
        "seconds per stage, median [min-max] of {} runs, {CAPTURE} {IMAGES} trained {TRAIN_ITERS} iterations, {} Gaussians, {} edited views, copy roof {roof:.1} GB/s",
        runs[0].len(),
        first["gaussians"]["input"],
        views
    );
    let mut t = common::Table::new(
        "removal_speed",
        args,
        &what,
        Some(&gpu.info().name),
        if baseline {
            "| stage | this build s | baseline s | this / baseline | per view or iteration (this build) | GPU roofline |"
        } else {
            "| stage | this build s | per view or iteration | GPU roofline |"
        },
        if baseline { "|---|---:|---:|---:|---:|---|" } else { "|---|---:|---:|---|" },
    );
    let mut rows: Vec<(String, Vec<Vec<f64>>)> = common::REMOVAL_STAGES
        .iter()
        .map(|s| (s.to_string(), (0..binaries.len()).map(|b| stage(b, s)).collect()))
        .collect();
    rows.push(("**total (wall)**".into(), (0..binaries.len()).map(walls).collect()));
    for (name, per_binary) in rows {
        let this = common::median(per_binary[0].clone());
        let per = match name.as_str() {
            "masks" | "complete" | "photo_depth" | "transfer" if views > 0.0 => {
                format!("{:.2} s per view", this / views)
            }
            "refine" if iters > 0.0 => format!("{:.3} s per iteration", this / iters),
            _ => String::new(),
        };
        let roofline = match name.as_str() {
            "masks" => format!("one render: {}", mask_render.summary(roof)),
            "refine" => {
                // the stage's own iterations run over each view's window (and include two PSNR
                // evaluations); the profiles are whole frames, the reference a training iteration is
                let measured = if iters > 0.0 { 1e3 * this / iters } else { 0.0 };
                let whole = refine_iter.map_or(String::new(), |p| {
                    format!(
                        "; an iteration over whole frames of the refined scene ({} Gaussians): {}",
                        p.gaussians,
                        p.summary(roof)
                    )
                });
                format!(
                    "stage / iterations {measured:.0} ms = {:.2}x a training iteration on the trained scene ({} Gaussians, whole frames: {}){whole}",
                    measured / train_iter.wall_ms,
                    train_iter.gaussians,
                    train_iter.summary(roof),
                )
            }
            _ => String::new(),
        };
        if baseline {
            let old = common::median(per_binary[1].clone());
            let ratio = if old > 0.0 { format!("{:.2}", this / old) } else { String::new() };
            t.line(format!(
                "| {name} | {} | {} | {ratio} | {per} | {roofline} |",
                spread(&per_binary[0], 1),
                spread(&per_binary[1], 1)
            ));
        } else {
            t.line(format!("| {name} | {} | {per} | {roofline} |", spread(&per_binary[0], 1)));
        }
    }
    if let Some((_, b)) = binaries.get(1) {
        t.line(format!("\nBaseline binary: `{}`.", b.display()));
    }
    t.md
}
