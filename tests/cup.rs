//! The real cup capture (`../shared/data/cup`): 77 photos, each with its own COLMAP camera
//! (SIMPLE_PINHOLE, focal lengths 588 to 602 px). It trains, and renders, with each image's camera.

mod common;

use std::process::Command;

fn psnr(a: &[f32], b: &[f32]) -> f64 {
    let se: f64 = a.iter().zip(b).map(|(x, y)| ((x - y) as f64).powi(2)).sum::<f64>() / a.len() as f64;
    10.0 * (1.0 / se).log10()
}

#[test]
fn the_cup_trains_and_renders_with_each_images_own_camera() {
    let Some(cup) = common::shared_data("cup") else {
        return;
    };
    // every image keeps its own intrinsics, scaled by --downscale
    let model = cogeo::scene::colmap::read_colmap(&cup).unwrap();
    let ds = cogeo::scene::dataset::load(&cup, "images", 4).unwrap();
    assert_eq!(ds.train.len() + ds.test.len(), 77);
    for v in ds.train.iter().chain(&ds.test) {
        let own = model.cameras.iter().find(|c| c.name == v.camera.name).unwrap();
        assert!((v.camera.fx - own.fx / 4.0).abs() < 1e-9, "{}: fx {} for {}", v.camera.name, v.camera.fx, own.fx);
    }
    let mut focal: Vec<i64> = model.cameras.iter().map(|c| (c.fx * 10.0) as i64).collect();
    focal.sort();
    focal.dedup();
    assert!(focal.len() > 30, "{} distinct focal lengths", focal.len());

    let exe = env!("CARGO_BIN_EXE_cogeo");
    let root = common::scratch_dir("cup");
    let run = |args: &[&str]| {
        let out = Command::new(exe).args(args).output().unwrap();
        assert!(out.status.success(), "cogeo {args:?}: {}", String::from_utf8_lossy(&out.stderr));
        String::from_utf8_lossy(&out.stderr).into_owned()
    };
    let (data, train) = (cup.to_string_lossy(), root.join("train"));
    let train_dir = train.to_string_lossy();
    let args = ["train", "--data", &data, "--out", &train_dir, "--iters", "150", "--downscale", "4"];
    run(&[&args[..], &["--checkpoint-every", "0", "--sh-degree", "0"]].concat());
    let metrics: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(train.join("metrics.json")).unwrap()).unwrap();
    let test_psnr = metrics["test"]["psnr"].as_f64().unwrap();
    eprintln!("cup, 150 iterations at 200x150: held-out PSNR {test_psnr:.2} dB");
    assert!(test_psnr > 18.0, "held-out PSNR {test_psnr:.2} dB");
    // `render --colmap` uses each image's own camera: a held-out view's render fits its photo
    let renders = root.join("renders");
    run(&[
        "render",
        "--scene",
        &train.join("scene.ply").to_string_lossy(),
        "--colmap",
        &data,
        "--out",
        &renders.to_string_lossy(),
        "--width",
        "200",
    ]);
    let view = &ds.test[1];
    let (w, h, render) = cogeo::scene::dataset::load_rgb(&renders.join(format!("{}.png", view.camera.name))).unwrap();
    assert_eq!((w, h), (view.camera.width, view.camera.height));
    let p = psnr(&render, &view.image);
    eprintln!("{}: render --colmap against its photo {p:.2} dB", view.camera.name);
    assert!(p > test_psnr - 2.0, "{p:.2} dB against a held-out PSNR of {test_psnr:.2} dB");
}
