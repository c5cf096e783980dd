//! Tagging benchmark: the three methods on synthetic scenes of 100k and 1M Gaussians, with label maps
//! of three disc-shaped objects over a handful of views.
//!
//!   cargo bench --bench tag [-- --sizes 100000,1000000 --resolution 512x512 --views 4 --iters 3]
//!
//! Reports the kNN precomputation, the time per distillation iteration (forward features + cross-
//! entropy + feature backward + kNN KL + Adam), per vote view (forward + one-hot feature backward)
//! and the projection baseline, and writes bench/results/tag-<device>.json.

#[path = "common.rs"]
mod common;

use cogeo::scene::Camera;
use cogeo::tag::distill::{distill, nearest_neighbors, DistillConfig};
use cogeo::tag::labels::LabelMaps;
use cogeo::tag::{project_labels, vote_weights};
use std::time::Instant;

fn main() {
    let args = common::args();
    let sizes = common::counts(&args, "--sizes", "100000,1000000");
    let (w, h) = common::resolutions(&args, "--resolution", "512x512")[0];
    let views: usize = common::arg(&args, "--views").map(|v| v.parse().unwrap()).unwrap_or(4);
    let iters: u32 = common::arg(&args, "--iters").map(|v| v.parse().unwrap()).unwrap_or(3);
    let gpu = common::gpu();
    println!("device: {}", gpu.info().summary());
    let cameras: Vec<Camera> = (0..views)
        .map(|i| {
            let a = i as f64 * 0.3;
            Camera::look_at(
                &format!("v{i}"),
                w,
                h,
                60.0,
                [5.5 * a.sin(), -0.5, -5.5 * a.cos()],
                [0.0; 3],
                [0.0, -1.0, 0.0],
            )
        })
        .collect();
    // three discs of labels 1..3 per view, background 0
    let maps = cameras
        .iter()
        .map(|c| {
            let (cw, ch) = (c.width as f64, c.height as f64);
            (0..c.width * c.height)
                .map(|u| {
                    let (x, y) = ((u % c.width) as f64 / cw, (u / c.width) as f64 / ch);
                    let centers = [(0.3, 0.4), (0.6, 0.5), (0.45, 0.75)];
                    centers
                        .iter()
                        .position(|&(cx, cy)| (x - cx).powi(2) + (y - cy).powi(2) < 0.015)
                        .map_or(0, |q| q as u8 + 1)
                })
                .collect()
        })
        .collect();
    let labels = LabelMaps { num_objects: 3, names: vec!["a".into(), "b".into(), "c".into()], maps };
    let mut rows = Vec::new();
    for &n in &sizes {
        let scene = common::synthetic_scene(n, 0, 2);
        let t = Instant::now();
        nearest_neighbors(&scene.means, 5).unwrap();
        let knn_s = t.elapsed().as_secs_f64();

        let cfg = DistillConfig { iters, ..Default::default() };
        let mut stamps = Vec::new();
        let t = Instant::now();
        distill(&gpu, &scene, &cameras, &labels, &cfg, |_, _| stamps.push(Instant::now())).unwrap();
        let total = t.elapsed().as_secs_f64();
        // the first iteration also pays setup (upload, kNN); time the rest
        let per_iter = if stamps.len() > 1 {
            (stamps[stamps.len() - 1] - stamps[0]).as_secs_f64() / (stamps.len() - 1) as f64
        } else {
            total
        };
        let setup = total - per_iter * iters as f64;

        let t = Instant::now();
        vote_weights(&gpu, &scene, &cameras, &labels).unwrap();
        let vote_per_view = t.elapsed().as_secs_f64() / views as f64;
        let t = Instant::now();
        project_labels(&scene, &cameras, &labels);
        let project_s = t.elapsed().as_secs_f64();
        println!(
            "{n} Gaussians, {w}x{h}: kNN {knn_s:.2} s; distill setup {setup:.2} s + {per_iter:.2} s/iteration; \
             vote {vote_per_view:.2} s/view; project {project_s:.3} s for {views} views"
        );
        rows.push(serde_json::json!({"gaussians": n, "width": w, "height": h, "views": views,
            "knn_s": knn_s, "distill_setup_s": setup, "distill_s_per_iteration": per_iter,
            "vote_s_per_view": vote_per_view, "project_s": project_s}));
    }
    let mut table = common::Table::new("tag", &args, "", Some(&gpu.info().name), "| Gaussians | resolution | views | kNN s | distill setup s | distill s / iteration | vote s / view | project s |", "|---:|---|---:|---:|---:|---:|---:|---:|");
    for r in &rows {
        let f = |k: &str| r[k].as_f64().unwrap();
        table.line(format!(
            "| {} | {}x{} | {} | {:.2} | {:.2} | {:.2} | {:.2} | {:.3} |",
            r["gaussians"],
            r["width"],
            r["height"],
            r["views"],
            f("knn_s"),
            f("distill_setup_s"),
            f("distill_s_per_iteration"),
            f("vote_s_per_view"),
            f("project_s")
        ));
    }
    common::update_results(&args, "tag", &table.md);
    let path = common::results_path(&format!("tag-{}.json", common::device_slug(&gpu)));
    common::write_json(&path, &serde_json::json!({ "device": gpu.info().summary(), "rows": rows }));
}
