//! nerfstudio / instant-ngp `transforms.json` (scene/transforms.rs): the synth writes every capture
//! in both formats, so the two readers must give the same cameras and points, and training on
//! either must give the same scene.

mod common;

use cogeo::scene::colmap::read_colmap;
use cogeo::scene::transforms::{parse_transforms, read_transforms};
use cogeo::synth::{generate, Rig, SynthConfig};
use std::path::Path;

fn synth(dir: &Path, distortion: [f64; 4]) {
    let cfg = SynthConfig {
        width: 64,
        height: 48,
        views: 12,
        objects: 2,
        rig: Rig::Orbit,
        seed: 9,
        points_per_view: 150,
        gt_without: Vec::new(),
        supersample: 1,
        distortion,
        exposure_jitter: 0.0,
    };
    generate(&cfg, dir, &|_, _| {}).unwrap();
}

#[test]
fn both_formats_give_the_same_cameras_and_points() {
    let dir = common::scratch_dir("transforms_same");
    for (k, distortion) in [[0.0; 4], [-0.1, 0.02, 0.001, -0.002]].into_iter().enumerate() {
        let data = dir.join(format!("d{k}"));
        synth(&data, distortion);
        let a = read_colmap(&data).unwrap();
        let b = read_transforms(&data).unwrap();
        assert_eq!(a.cameras.len(), b.cameras.len());
        assert_eq!(a.lenses, b.lenses);
        for (x, y) in a.cameras.iter().zip(&b.cameras) {
            assert_eq!((&x.name, x.width, x.height), (&y.name, y.width, y.height));
            let d = |p: f64, q: f64| (p - q).abs();
            assert!(d(x.fx, y.fx) < 1e-5 && d(x.fy, y.fy) < 1e-5 && d(x.cx, y.cx) < 1e-5 && d(x.cy, y.cy) < 1e-5);
            for r in 0..3 {
                for c in 0..3 {
                    assert!(d(x.rotation[r][c], y.rotation[r][c]) < 1e-5, "{}: rotation {r},{c}", x.name);
                }
                assert!(d(x.translation[r], y.translation[r]) < 1e-5, "{}: translation", x.name);
            }
        }
        assert_eq!(a.points.len(), b.points.len());
        for (p, q) in a.points.iter().zip(&b.points) {
            assert!((0..3).all(|i| (p.xyz[i] - q.xyz[i]).abs() < 1e-5) && p.rgb == q.rgb);
        }
        assert!(b.warnings.is_empty(), "{:?}", b.warnings);
    }
}

#[test]
fn a_transforms_capture_trains_like_its_colmap_twin() {
    let gpu = common::gpu();
    let dir = common::scratch_dir("transforms_train");
    let colmap = dir.join("colmap");
    synth(&colmap, [0.0; 4]);
    // the same capture without its COLMAP model: the loader falls back to transforms.json
    let ns = dir.join("ns");
    std::fs::create_dir_all(ns.join("images")).unwrap();
    for f in ["transforms.json", "sparse_pc.ply"] {
        std::fs::copy(colmap.join(f), ns.join(f)).unwrap();
    }
    for e in std::fs::read_dir(colmap.join("images")).unwrap() {
        let p = e.unwrap().path();
        std::fs::copy(&p, ns.join("images").join(p.file_name().unwrap())).unwrap();
    }
    let psnr = |data: &Path| {
        use cogeo::train::trainer::{init_from_points, TrainConfig, Trainer};
        let ds = cogeo::scene::dataset::load(data, "images", 1).unwrap();
        let scene = init_from_points(&ds.points, 0).unwrap();
        let cfg = TrainConfig { iters: 150, sh_degree: 0, densify: false, seed: 1, ..Default::default() };
        let mut t = Trainer::new(&gpu, &ds, &scene, cfg).unwrap();
        while t.step < 150 {
            t.iterate(&ds, false).unwrap();
        }
        let psnr = t.evaluate(&ds.test).unwrap().psnr;
        // the removal's refinement report takes the same number without SSIM and the fitted scores
        let alone = t.mean_psnr(&ds.test).unwrap();
        assert!((alone - psnr).abs() < 1e-9, "mean_psnr {alone} against evaluate's {psnr}");
        psnr
    };
    let (a, b) = (psnr(&colmap), psnr(&ns));
    eprintln!("held-out PSNR after 150 iterations: COLMAP {a:.3} dB, transforms.json {b:.3} dB");
    // the same cameras, points and images: only the float atomics' order differs between runs
    assert!((a - b).abs() < 0.1, "COLMAP {a:.3} dB, transforms.json {b:.3} dB");
}

#[test]
fn malformed_files_get_one_line_naming_the_field() {
    let dir = common::scratch_dir("transforms_bad");
    let base = serde_json::json!({
        "fl_x": 50.0, "w": 64, "h": 48,
        "frames": [{"file_path": "images/a.png", "transform_matrix": [[1,0,0,0],[0,1,0,0],[0,0,1,4],[0,0,0,1]]}],
        "ply_file_path": "none.ply",
    });
    let err = |edit: &dyn Fn(&mut serde_json::Value)| {
        let mut j = base.clone();
        edit(&mut j);
        let e = parse_transforms(&j, &dir, "t.json").unwrap_err();
        let text = format!("{e:#}");
        assert!(!text.contains('\n'), "{text}");
        text
    };
    let e = err(&|j| {
        j.as_object_mut().unwrap().remove("fl_x");
    });
    assert!(e.contains("t.json: frames[0]: missing field \"fl_x\""), "{e}");
    let e = err(&|j| j["frames"][0]["transform_matrix"][1] = serde_json::json!([0, 1, 0]));
    assert!(e.contains("\"transform_matrix\"") && e.contains("not 4 numbers"), "{e}");
    let e = err(&|j| j["w"] = serde_json::json!("wide"));
    assert!(e.contains("field \"w\" is not a number"), "{e}");
    let e = err(&|j| j["frames"] = serde_json::json!({}));
    assert!(e.contains("missing field \"frames\""), "{e}");
    let e = err(&|j| j["camera_model"] = serde_json::json!("EQUIRECTANGULAR"));
    assert!(e.contains("\"camera_model\" = \"EQUIRECTANGULAR\""), "{e}");
    let e = err(&|j| j["applied_transform"] = serde_json::json!([[0, 0, 0, 0], [0, 0, 0, 0], [0, 0, 0, 0]]));
    assert!(e.contains("\"applied_transform\" is singular"), "{e}");
    // instant-ngp's field of view instead of a focal length; no point cloud: random points
    let mut j = base.clone();
    j.as_object_mut().unwrap().remove("fl_x");
    j.as_object_mut().unwrap().remove("ply_file_path");
    j["camera_angle_x"] = serde_json::json!(2.0 * (32.0f64 / 50.0).atan());
    let m = parse_transforms(&j, &dir, "t.json").unwrap();
    assert!((m.cameras[0].fx - 50.0).abs() < 1e-9 && (m.cameras[0].cx - 32.0).abs() < 1e-12);
    assert_eq!(m.points.len(), 100_000);
    assert_eq!(m.warnings.len(), 1);
}
