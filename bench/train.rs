//! Training-iteration benchmark: forward + loss + backward + Adam per pass (GPU timestamps), on
//! synthetic scenes against a fixed target image, densification off.
//!
//!   cargo bench --bench train [-- --sizes 100000,1000000 --resolution 512x512 --iters 5]
//!
//! Prints a table and writes bench/results/train-<device>.json.

#[path = "common.rs"]
mod common;

use cogeo::rng::Rng;
use cogeo::scene::Camera;
use cogeo::train::dataset::{Dataset, View};
use cogeo::train::trainer::{TrainConfig, Trainer};
use std::collections::BTreeMap;
use std::time::Instant;

fn main() {
    let args = common::args();
    let sizes = common::counts(&args, "--sizes", "100000,1000000");
    let (w, h) = common::resolutions(&args, "--resolution", "512x512")[0];
    let iters: usize = common::arg(&args, "--iters").map(|v| v.parse().unwrap()).unwrap_or(5);
    let gpu = common::gpu();
    println!("device: {}", gpu.info().summary());
    let mut rows = Vec::new();
    for &n in &sizes {
        let scene = common::synthetic_scene(n, 3, 2);
        let camera = Camera::look_at("bench", w, h, 60.0, [0.0, -0.5, -5.5], [0.0; 3], [0.0, -1.0, 0.0]);
        let mut rng = Rng::new(3);
        let image: Vec<f32> = (0..3 * (w * h) as usize).map(|_| rng.uniform() as f32).collect();
        let data = Dataset {
            train: vec![View { camera, image, path: "target".into() }],
            test: Vec::new(),
            points: Vec::new(),
            extent: 3.0,
            warnings: Vec::new(),
            pose_check: None,
        };
        let cfg = TrainConfig { iters: 30_000, densify: false, ..Default::default() };
        let mut trainer = Trainer::new(&gpu, &data, &scene, cfg).unwrap();
        trainer.profile = true;
        trainer.iterate(&data, false).unwrap(); // warm-up
        let mut per_pass: BTreeMap<String, Vec<f64>> = BTreeMap::new();
        let mut order = Vec::new();
        let mut wall = Vec::new();
        for _ in 0..iters {
            let t = Instant::now();
            trainer.iterate(&data, false).unwrap();
            wall.push(t.elapsed().as_secs_f64() * 1e3);
            for p in &trainer.last_timings {
                if !order.contains(&p.pass) {
                    order.push(p.pass.clone());
                }
                per_pass.entry(p.pass.clone()).or_default().push(p.ms);
            }
        }
        let passes: Vec<(String, f64)> =
            order.iter().map(|p| (p.clone(), common::median(per_pass[p].clone()))).collect();
        let total: f64 = passes.iter().map(|p| p.1).sum();
        let wall_ms = common::median(wall);
        println!("{n} Gaussians at {w}x{h}: GPU {total:.1} ms, wall {wall_ms:.1} ms per iteration");
        for (p, ms) in &passes {
            println!("    {p:<20} {ms:>10.2} ms");
        }
        rows.push(serde_json::json!({"gaussians": n, "width": w, "height": h, "gpu_ms": total, "wall_ms": wall_ms,
            "passes": passes.iter().map(|(p, ms)| serde_json::json!({"pass": p, "ms": ms})).collect::<Vec<_>>()}));
    }
    let path = common::results_path(&format!("train-{}.json", common::device_slug(&gpu)));
    common::write_json(
        &path,
        &serde_json::json!({ "device": gpu.info().summary(), "iterations": iters, "rows": rows }),
    );
}
