//! Render benchmark: per-pass GPU times (timestamps) over scene sizes and resolutions.
//!
//!   cargo bench --bench render [-- --sizes 100000,1000000,3000000 --resolutions 512x512,1920x1080 --frames 3]
//!
//! `--write-scenes DIR` also writes each scene as `DIR/scene-<n>.ply` and each camera as
//! `DIR/camera-<w>x<h>.json` (intrinsics and the 4x4 world-to-camera matrix), so that a peer
//! rasterizer (scripts/gsplat_peer.py) can time the very same scene and camera.
//!
//! Prints a table, writes bench/results/render-<device>.json and replaces the render table of
//! bench/RESULTS.md (unless --no-results).

#[path = "common.rs"]
mod common;

use cogeo::render::{Rasterizer, RenderSettings, SceneBuffers};
use cogeo::scene::Camera;
use std::time::Instant;

fn main() {
    let args = common::args();
    let sizes = common::counts(&args, "--sizes", "100000,1000000,3000000");
    let resolutions = common::resolutions(&args, "--resolutions", "512x512,1920x1080");
    let frames: usize = common::arg(&args, "--frames").map(|f| f.parse().unwrap()).unwrap_or(3);
    let write_dir = common::arg(&args, "--write-scenes").map(std::path::PathBuf::from);
    if let Some(dir) = &write_dir {
        std::fs::create_dir_all(dir).unwrap_or_else(|e| panic!("--write-scenes {}: {e}", dir.display()));
    }
    let gpu = common::gpu();
    println!("device: {}", gpu.info().summary());
    let roof = common::copy_bandwidth(&gpu);
    let mut rows = Vec::new();
    let mut raster = Rasterizer::new(&gpu).unwrap();
    for &n in &sizes {
        let t = Instant::now();
        let scene = common::synthetic_scene(n, 3, 1);
        let buffers = SceneBuffers::upload(&gpu, &scene, None).unwrap();
        if let Some(dir) = &write_dir {
            cogeo::scene::ply::write_ply(&scene, &dir.join(format!("scene-{n}.ply"))).unwrap();
        }
        drop(scene);
        println!("scene: {n} Gaussians, SH degree 3 (generated and uploaded in {:.1} s)", t.elapsed().as_secs_f64());
        for &(w, h) in &resolutions {
            let cam = Camera::look_at("bench", w, h, 60.0, [0.0, -0.5, -5.5], [0.0; 3], [0.0, -1.0, 0.0]);
            let settings = RenderSettings { timestamps: true, ..Default::default() };
            if let Some(dir) = &write_dir {
                write_camera(&cam, settings.near, &dir.join(format!("camera-{w}x{h}.json")));
            }
            // Warm-up: allocations and pipeline caches, and a second of frames. On a GPU this path
            // stays at its idle clock even so: a frame's readback of 8 planes keeps the GPU busy
            // only ~25 % of the time, and a lent H200's SM clock read 345 MHz during these frames
            // (1980 MHz under training), which is why its passes time 2-5x the same passes
            // inside a training iteration (bench/RESULTS.md, NVIDIA sections).
            let warm = Instant::now();
            while warm.elapsed().as_secs_f64() < 1.0 {
                raster.render(&buffers, &cam, &settings).unwrap();
            }
            let mut stats = common::PassStats::default();
            let mut wall = Vec::new();
            let mut isect = 0;
            for _ in 0..frames {
                let t = Instant::now();
                let out = raster.render(&buffers, &cam, &settings).unwrap();
                wall.push(t.elapsed().as_secs_f64() * 1e3);
                isect = out.num_intersections;
                stats.add(&out.timings);
            }
            let gpu_total: f64 = stats.medians().iter().map(|p| p.ms).sum();
            let wall_ms = common::median(wall);
            println!("  {w}x{h}: {isect} intersections, GPU {gpu_total:.1} ms, wall {wall_ms:.1} ms (incl. readback)");
            stats.print("      ", roof.roof_gbps());
            rows.push(serde_json::json!({
                "gaussians": n, "width": w, "height": h, "intersections": isect,
                "gpu_ms": gpu_total, "wall_ms": wall_ms, "passes": stats.json(roof.roof_gbps()),
            }));
        }
    }
    let what = format!("{frames} frames, median per pass (GPU timestamps), ms");
    let mut table = common::Table::new("render", &args, &what, Some(&gpu.info().name), "| Gaussians | resolution | intersections | project | depth sort | count scan | emit | tile sort | ranges | blend | GPU total ms | wall ms |", "|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|");
    for r in &rows {
        let pass = |name: &str| {
            r["passes"]
                .as_array()
                .unwrap()
                .iter()
                .find(|p| p["pass"] == name)
                .map(|p| p["ms"].as_f64().unwrap())
                .unwrap_or(0.0)
        };
        table.line(format!(
            "| {} | {}x{} | {} | {:.1} | {:.1} | {:.1} | {:.1} | {:.1} | {:.1} | {:.1} | {:.1} | {:.1} |",
            r["gaussians"],
            r["width"],
            r["height"],
            r["intersections"],
            pass("project"),
            pass("depth sort"),
            pass("tile count scan"),
            pass("emit intersections"),
            pass("tile sort"),
            pass("tile ranges"),
            pass("blend"),
            r["gpu_ms"].as_f64().unwrap(),
            r["wall_ms"].as_f64().unwrap()
        ));
    }
    common::update_results(&args, "render", &table.md);
    let path = common::results_path(&format!("render-{}.json", common::device_slug(&gpu)));
    common::write_json(
        &path,
        &serde_json::json!({ "device": gpu.info().summary(), "copy_bandwidth": roof, "frames": frames, "rows": rows }),
    );
}

/// The camera as a peer rasterizer takes it: pinhole intrinsics, world-to-camera 4x4 (row-major,
/// OpenCV axes as in conventions.md) and the near plane.
fn write_camera(cam: &Camera, near: f32, path: &std::path::Path) {
    let (r, t) = (cam.rotation, cam.translation);
    let view: Vec<[f64; 4]> = (0..3).map(|i| [r[i][0], r[i][1], r[i][2], t[i]]).chain([[0.0, 0.0, 0.0, 1.0]]).collect();
    let json = serde_json::json!({
        "width": cam.width, "height": cam.height, "fx": cam.fx, "fy": cam.fy, "cx": cam.cx, "cy": cam.cy,
        "viewmat": view, "near": near,
    });
    common::write_json(path, &json);
}
