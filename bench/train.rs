//! Training-iteration benchmark: forward + loss + backward + Adam per pass (GPU timestamps), on
//! synthetic scenes against a fixed target image, densification off.
//!
//!   cargo bench --bench train [-- --sizes 100000,1000000 --resolution 512x512 --iters 5 --full-sh]
//!   cargo bench --bench train -- --scene run/scene.ply --data data/ [--iters 20]
//!
//! With --scene and --data, a trained scene is benchmarked on its own training views (in turn)
//! instead of synthetic scenes: trained scenes have the overlap and sizes real training sees.
//!
//! Synthetic scenes are SH degree 3 but train, like any run's first 1000 iterations, at degree 0;
//! `--full-sh` uses all bands from the first step (the state of 90 % of a 30k-iteration run). A
//! trained scene renders the bands it learnt (`GaussianScene::learnt_sh_degree`), or all with
//! `--full-sh`.
//! `--apart` runs the projection backward and Adam as separate passes (train/fused.rs) instead of
//! fused, for a comparison in one binary.
//!
//! Prints a table and writes bench/results/train-<device>.json.

#[path = "common.rs"]
mod common;

use cogeo::rng::Rng;
use cogeo::scene::dataset::{Dataset, View};
use cogeo::scene::{Camera, GaussianScene};
use cogeo::train::trainer::{TrainConfig, Trainer};
use std::time::Instant;

fn main() {
    let args = common::args();
    let sizes = common::counts(&args, "--sizes", "100000,1000000");
    let (w, h) = common::resolutions(&args, "--resolution", "512x512")[0];
    let iters: usize = common::arg(&args, "--iters").map(|v| v.parse().unwrap()).unwrap_or(5);
    let gpu = common::gpu();
    println!("device: {}", gpu.info().summary());
    let roof = common::copy_bandwidth(&gpu);
    let trained = common::arg(&args, "--scene").map(|ply| {
        let data = common::arg(&args, "--data").expect("--scene needs --data (the scene's dataset)");
        let scene = cogeo::scene::ply::read_ply(std::path::Path::new(&ply)).expect("cannot read --scene");
        let images = common::arg(&args, "--images").unwrap_or_else(|| "images".into());
        let data = cogeo::scene::dataset::load(std::path::Path::new(&data), &images, 1).expect("cannot load --data");
        (scene, data)
    });
    let is_trained = trained.is_some();
    let full_sh = args.iter().any(|a| a == "--full-sh");
    let apart = args.iter().any(|a| a == "--apart");
    // synthetic scenes are made one at a time, as they are benchmarked
    let cases: Box<dyn Iterator<Item = (GaussianScene, Dataset)>> = match trained {
        Some(t) => Box::new(std::iter::once(t)),
        None => Box::new(sizes.iter().map(|&n| (common::synthetic_scene(n, 3, 2), synthetic_target(w, h)))),
    };
    let mut rows = Vec::new();
    for (scene, data) in cases {
        let n = scene.len();
        let (w, h) = (data.train[0].camera.width, data.train[0].camera.height);
        let cfg = TrainConfig { iters: 30_000, sh_degree: scene.sh_degree, densify: false, ..Default::default() };
        let mut trainer = Trainer::new(&gpu, &data, &scene, cfg).unwrap();
        trainer.profile = true;
        // a trained scene renders the bands it learnt, as the removal's refinement does
        trainer.fixed_sh_degree =
            if full_sh { Some(cogeo::scene::MAX_SH_DEGREE) } else { is_trained.then(|| scene.learnt_sh_degree()) };
        let sh_degree = trainer.active_sh_degree();
        trainer.fused_step = !apart;
        // Warm-up: one iteration, and at least a second of them, so that a GPU has left its idle
        // clock before the timed ones (a lent H200's SM clock read 345-465 MHz during the first
        // 1M iteration after one warm-up iteration, 1980 MHz once busy for ~0.3 s)
        let warm = Instant::now();
        trainer.iterate(&data, false).unwrap();
        while warm.elapsed().as_secs_f64() < 1.0 {
            trainer.iterate(&data, false).unwrap();
        }
        let mut stats = common::PassStats::default();
        let mut wall = Vec::new();
        let trips_before = gpu.round_trips();
        for _ in 0..iters {
            let t = Instant::now();
            trainer.iterate(&data, false).unwrap();
            wall.push(t.elapsed().as_secs_f64() * 1e3);
            stats.add(&trainer.last_timings);
        }
        let trips = gpu.round_trips() - trips_before;
        let (submits, readbacks) = (trips.submits as f64 / iters as f64, trips.readbacks as f64 / iters as f64);
        let total: f64 = stats.medians().iter().map(|p| p.ms).sum();
        let wall_ms = common::median(wall);
        println!(
            "{n} Gaussians at {w}x{h}: GPU {total:.1} ms, wall {wall_ms:.1} ms per iteration; \
             {submits} submits and {readbacks} readbacks per iteration"
        );
        stats.print("    ", roof.roof_gbps());
        rows.push(serde_json::json!({"gaussians": n, "width": w, "height": h, "full_sh": full_sh, "sh_degree": sh_degree, "fused_step": !apart, "gpu_ms": total, "wall_ms": wall_ms,
            "submits_per_iteration": submits, "readbacks_per_iteration": readbacks,
            "passes": stats.json(roof.roof_gbps())}));
    }
    let what = format!("median of {iters} iterations after a warm-up, ms, copy roof {:.1} GB/s", roof.roof_gbps());
    let mut table = common::Table::new(
        "train",
        &args,
        &what,
        Some(&gpu.info().name),
        "| Gaussians | resolution | SH | step | blend | loss | blend backward | project backward (+ Adam) | GPU ms | wall ms | submits / readbacks |",
        "|---:|---|---|---|---:|---:|---:|---:|---:|---:|---|",
    );
    for r in &rows {
        // the projection backward's name says whether Adam rode in it ("project backward + adam")
        let pass = |name: &str| -> String {
            let ms: f64 = r["passes"]
                .as_array()
                .unwrap()
                .iter()
                .filter(|p| {
                    let pass = p["pass"].as_str().unwrap();
                    pass == name || (name == "project backward" && pass.starts_with(name))
                })
                .map(|p| p["ms"].as_f64().unwrap())
                .sum();
            format!("{ms:.1}")
        };
        let f = |k: &str| r[k].as_f64().unwrap();
        table.line(format!(
            "| {} | {}x{} | {} | {} | {} | {} | {} | {} | {:.1} | {:.1} | {} / {} |",
            r["gaussians"],
            r["width"],
            r["height"],
            match (r["full_sh"] == true, r["sh_degree"].as_u64()) {
                (true, _) => "all bands".to_string(),
                (false, d) => format!("degree {}", d.unwrap_or(0)),
            },
            if r["fused_step"] == true { "fused" } else { "apart" },
            pass("blend"),
            pass("loss"),
            pass("blend backward"),
            pass("project backward"),
            f("gpu_ms"),
            f("wall_ms"),
            r["submits_per_iteration"],
            r["readbacks_per_iteration"]
        ));
    }
    common::update_results(&args, "train", &table.md);
    let path = common::results_path(&format!("train-{}.json", common::device_slug(&gpu)));
    common::write_json(
        &path,
        &serde_json::json!({ "device": gpu.info().summary(), "copy_bandwidth": roof, "iterations": iters, "rows": rows }),
    );
}

/// One view of a random target image, looking at the synthetic scene's box.
fn synthetic_target(w: u32, h: u32) -> Dataset {
    let camera = Camera::look_at("bench", w, h, 60.0, [0.0, -0.5, -5.5], [0.0; 3], [0.0, -1.0, 0.0]);
    let mut rng = Rng::new(3);
    let image: Vec<f32> = (0..3 * (w * h) as usize).map(|_| rng.uniform() as f32).collect();
    Dataset {
        train: vec![View { camera, image, path: "target".into(), undistortion: None }],
        test: Vec::new(),
        points: Vec::new(),
        extent: 3.0,
        warnings: Vec::new(),
        pose_check: None,
    }
}
