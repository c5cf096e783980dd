//! Multi-object removal end to end through the CLI on a trained `cogeo synth` scene, scored against
//! the exact object-free ground truth on held-out views: the full pipeline against removal only,
//! and the outputs `cogeo remove` promises. Also every ONNX model path through the CLI.

mod common;

use common::{onnx, run_cogeo};

fn report(dir: &str) -> serde_json::Value {
    serde_json::from_str(&std::fs::read_to_string(format!("{dir}/report.json")).unwrap()).unwrap()
}

fn masked_psnr(r: &serde_json::Value) -> f64 {
    r["held_out_vs_ground_truth"]["masked_psnr"].as_f64().unwrap()
}

/// `cogeo demo --quick` (synth with 3 objects, 500 training iterations, vote tags, objects 1 and 2
/// removed at once, evaluation), then more `cogeo remove` runs on the demo's tagged scene.
#[test]
fn demo_quick_beats_removal_only_and_remove_keeps_the_background() {
    let exe = env!("CARGO_BIN_EXE_cogeo");
    let root = std::env::temp_dir().join(format!("cogeo_remove_{}", std::process::id()));
    let path = |p: &str| root.join(p).to_string_lossy().into_owned();
    let run = |args: &[&str]| run_cogeo(exe, args);
    let demo = path("demo");
    run(&["demo", "--quick", "--out", &demo]);
    let m: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(root.join("demo/metrics.json")).unwrap()).unwrap();
    let (ours, only) = (&m["cogeo"], &m["removal_only"]);
    let (f, o) = (ours["mask"]["psnr"].as_f64().unwrap(), only["mask"]["psnr"].as_f64().unwrap());
    eprintln!("demo: held-out masked PSNR cogeo {f:.2} dB, removal only {o:.2} dB");
    assert!(f > o + 0.5, "demo: full pipeline {f:.2} dB does not beat removal only {o:.2} dB");
    // the objects are gone from the held-out views: less of them is left than after removal only
    assert!(ours["leftover"].as_f64().unwrap() < only["leftover"].as_f64().unwrap());
    let views = ours["views"].as_array().unwrap().len();
    assert_eq!(views, 2);
    assert_eq!(std::fs::read_dir(root.join("demo/strips")).unwrap().count(), views);
    let sheet = image::open(root.join("demo/contact_sheet.png")).unwrap();
    assert!(sheet.width() >= 4 * 64 && sheet.height() >= 2 * 48);
    let md = std::fs::read_to_string(root.join("demo/report.md")).unwrap();
    assert!(md.contains("| cogeo (full pipeline) |") && md.contains("contact_sheet.png"));
    // a non-empty folder that no demo wrote is refused, not overwritten
    std::fs::create_dir_all(root.join("mine")).unwrap();
    std::fs::write(root.join("mine/keep.txt"), "x").unwrap();
    let refused = std::process::Command::new(exe).args(["demo", "--quick", "--out", &path("mine")]).output().unwrap();
    assert!(!refused.status.success());
    assert!(String::from_utf8_lossy(&refused.stderr).contains("not empty"));
    assert!(root.join("mine/keep.txt").exists());

    let data = format!("{demo}/data");
    let tagged = format!("{demo}/tagged.ply");
    let remove = |out: &str, extra: &[&str]| {
        let out = path(out);
        run(&[&["remove", "--scene", &tagged, "--data", &data, "--labels", "1,2", "--out", &out][..], extra].concat());
        report(&out)
    };
    let full = report(&format!("{demo}/removal"));
    let only = report(&format!("{demo}/removal_only"));
    // cogeo remove's own scores agree with the demo's evaluation
    assert!((masked_psnr(&full) - f).abs() < 0.05 && (masked_psnr(&only) - o).abs() < 0.05);
    // the background outside the dilated holes stays as it was rendered
    let bg = full["background_psnr_vs_original"]["mean"].as_f64().unwrap();
    assert!(bg >= 35.0, "background PSNR vs the original render {bg:.2} dB");
    // the removed Gaussians are gone, new ones were added, and the stages reported what they did
    let g = &full["gaussians"];
    assert!(g["removed"].as_u64().unwrap() > 0);
    assert!(full["fusion"]["patch_gaussians"].as_u64().unwrap() > 0);
    assert_eq!(full["refine"]["iters"].as_u64().unwrap(), 150);
    assert_eq!(full["options"]["refine"]["hole_weight"].as_f64().unwrap(), cogeo::removal::refine::HOLE_WEIGHT as f64);
    assert!(full["refine"]["psnr_after"].as_f64().unwrap() > full["refine"]["psnr_before"].as_f64().unwrap());
    for stage in ["masks", "complete", "fuse", "refine"] {
        assert!(full["seconds"][stage].as_f64().is_some(), "no time for {stage}");
    }
    // completed depth is closer to the true background than the raw render's depth would be
    assert!(full["fill_depth_vs_ground_truth"]["abs_rel"].as_f64().unwrap() < 0.2);
    // outputs: the clean scene and per-view images
    let clean = cogeo::scene::ply::read_ply(&root.join("demo/removal/scene.ply")).unwrap();
    assert_eq!(clean.len() as u64, g["output"].as_u64().unwrap());
    for sub in ["before", "after", "removed", "inpainted", "mask", "depth", "test_before", "test_after"] {
        let n = std::fs::read_dir(root.join("demo/removal").join(sub)).unwrap().count();
        assert!(n > 0, "{sub}/ is empty");
    }
    // a label nobody carries is an error naming it
    let out = std::process::Command::new(exe)
        .args(["remove", "--scene", &tagged, "--data", &data, "--labels", "7", "--out", &path("none")])
        .output()
        .unwrap();
    assert!(!out.status.success());
    assert!(String::from_utf8_lossy(&out.stderr).contains("label(s) [7]"));
    // a negative loss weight is refused before any work, naming the flag
    let out = std::process::Command::new(exe)
        .args(["remove", "--scene", &tagged, "--data", &data, "--labels", "1", "--out", &path("none")])
        .args(["--refine-hole-weight", "-1"])
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success() && err.contains("--refine-hole-weight") && err.contains(">= 0"), "{err}");

    // the hole's loss weight reaches the refinement: at 0 the hole pixels do not count and the
    // render fits the completed views there only as well as the fused patch did; at the default
    // 4 it fits them better (measured: 21.49 vs 20.38 dB; unweighted, the two would agree to
    // within run-to-run noise, ~0.05 dB)
    let hole_fit = |dir: &std::path::Path| {
        let (mut se, mut n) = (0.0f64, 0usize);
        for entry in std::fs::read_dir(dir.join("inpainted")).unwrap() {
            let name = entry.unwrap().file_name();
            let load = |sub: &str| image::open(dir.join(sub).join(&name)).unwrap().to_rgb8();
            let (after, target) = (load("after"), load("inpainted"));
            let hole = image::open(dir.join("mask").join(&name)).unwrap().to_luma8();
            for (i, _) in hole.pixels().enumerate().filter(|(_, m)| m[0] == 255) {
                let (x, y) = (i as u32 % hole.width(), i as u32 / hole.width());
                for c in 0..3 {
                    let d = after.get_pixel(x, y)[c] as f64 - target.get_pixel(x, y)[c] as f64;
                    se += d * d;
                    n += 1;
                }
            }
        }
        10.0 * (255.0f64 * 255.0 * n as f64 / se).log10()
    };
    remove("hole_weight_0", &["--refine-hole-weight", "0"]);
    let (weighted, left_out) = (hole_fit(&root.join("demo/removal")), hole_fit(&root.join("hole_weight_0")));
    eprintln!(
        "refined render vs completed views inside the holes: weight 4 {weighted:.2} dB, weight 0 {left_out:.2} dB"
    );
    assert!(weighted > left_out + 0.5, "hole weight 4: {weighted:.2} dB, 0: {left_out:.2} dB");

    // bring-your-own inpainting: the exact object-free views as a perfect inpainter's output are
    // used exactly inside the holes, the render elsewhere, and beat the smooth built-in fill
    // (both without color transfer, which would overwrite most of either)
    let truth = cogeo::synth::ground_truth(std::path::Path::new(&data), &[1, 2]);
    let truth_dir = truth.images.to_string_lossy().into_owned();
    let no_transfer = ["--no-transfer"];
    let own = remove("own_inpainting", &[&["--inpainted", &truth_dir][..], &no_transfer].concat());
    let builtin = remove("builtin_inpainting", &[&["--inpainter", "harmonic"][..], &no_transfer].concat());
    assert!(own["completion"]["inpainter"].as_str().unwrap().contains(&truth_dir));
    // the hole depth is corrected for the fusion even without the color transfer
    assert_eq!(own["completion"]["photo_consistent_hole_depth"], true);
    assert!(own["views"].as_array().unwrap().iter().all(|v| v["hole_depth_scale"]["scale"].as_f64().is_some()));
    assert!(own["views"].as_array().unwrap().iter().all(|v| v.get("transferred_pixels").is_none()));
    let (po, pb) = (masked_psnr(&own), masked_psnr(&builtin));
    eprintln!("--inpainted with the true background: held-out masked PSNR {po:.2} dB, harmonic {pb:.2} dB");
    // measured on one tagged scene, with refinement: 16.91 vs 15.14 dB. Without it the unrefined
    // patch's blur hid the difference once covered background was filled too (14.95 vs 14.78;
    // 14.85 vs 14.28 before); retraining moves the gap by about 0.1 dB
    assert!(po > pb + 1.0, "provided inpainting {po:.2} dB vs built-in {pb:.2} dB");
    let mut filled = 0;
    for entry in std::fs::read_dir(root.join("own_inpainting/inpainted")).unwrap() {
        let name = entry.unwrap().file_name().into_string().unwrap();
        let load = |dir: std::path::PathBuf| image::open(dir.join(&name)).unwrap().to_rgb8();
        let (mine, theirs, render) = (
            load(root.join("own_inpainting/inpainted")),
            load(truth.images.clone()),
            load(root.join("builtin_inpainting/removed")),
        );
        let mask = image::open(root.join("own_inpainting/mask").join(&name)).unwrap().to_luma8();
        for (i, m) in mask.pixels().enumerate() {
            let (x, y) = (i as u32 % mask.width(), i as u32 / mask.width());
            if m[0] == 255 {
                assert_eq!(mine.get_pixel(x, y), theirs.get_pixel(x, y), "{name} ({x}, {y}) inside the hole");
                filled += 1;
            } else {
                assert_eq!(mine.get_pixel(x, y), render.get_pixel(x, y), "{name} ({x}, {y}) outside the hole");
            }
        }
    }
    assert!(filled > 0);
    // a missing view is an error naming the folder and the view
    let partial = root.join("partial");
    std::fs::create_dir_all(&partial).unwrap();
    // every view but the first edited one
    let mut edited: Vec<_> =
        std::fs::read_dir(root.join("own_inpainting/inpainted")).unwrap().map(|e| e.unwrap().file_name()).collect();
    edited.sort();
    for e in std::fs::read_dir(&truth.images).unwrap() {
        let p = e.unwrap().path();
        if p.file_name().unwrap() != edited[0] {
            std::fs::copy(&p, partial.join(p.file_name().unwrap())).unwrap();
        }
    }
    let out = std::process::Command::new(exe)
        .args(["remove", "--scene", &tagged, "--data", &data, "--labels", "1,2", "--out", &path("partial_out")])
        .args(["--inpainted", &partial.to_string_lossy()])
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success() && err.contains("partial") && err.contains("no inpainted view for image"), "{err}");

    // with --exposure the provided views, completions of the photos, are taken into the scene's
    // colors through each view's inverse map, and `inpainted/` is written back through the map:
    // inside the holes the provided truth comes back as it was, outside them the render (scene
    // colors) through the view's map. Per-view gains; the check fails if either way is skipped.
    let names: Vec<String> = edited.iter().map(|n| n.to_string_lossy().trim_end_matches(".png").to_string()).collect();
    let gain = |k: usize| [0.8 - 0.01 * k as f64, 0.9, 0.7 + 0.01 * k as f64];
    let maps: Vec<serde_json::Value> = names
        .iter()
        .enumerate()
        .map(|(k, n)| {
            let g = gain(k);
            serde_json::json!({ "name": n, "matrix": [[g[0], 0, 0], [0, g[1], 0], [0, 0, g[2]]], "bias": [0, 0, 0] })
        })
        .collect();
    let exposure = root.join("exposure.json");
    std::fs::write(&exposure, serde_json::json!({ "views": maps }).to_string()).unwrap();
    let exposure = exposure.to_string_lossy().into_owned();
    remove(
        "own_inpainting_exposure",
        &["--inpainted", &truth_dir, "--no-transfer", "--no-refine", "--exposure", &exposure],
    );
    let (mut inside, mut outside) = (0, 0);
    for (k, name) in names.iter().enumerate() {
        let file = format!("{name}.png");
        let load = |dir: std::path::PathBuf| image::open(dir.join(&file)).unwrap().to_rgb8();
        let (mine, theirs, render) = (
            load(root.join("own_inpainting_exposure/inpainted")),
            load(truth.images.clone()),
            load(root.join("own_inpainting_exposure/removed")),
        );
        let mask = image::open(root.join("own_inpainting_exposure/mask").join(&file)).unwrap().to_luma8();
        for (i, m) in mask.pixels().enumerate() {
            let (x, y) = (i as u32 % mask.width(), i as u32 / mask.width());
            let expected: [f64; 3] = if m[0] == 255 {
                inside += 1;
                theirs.get_pixel(x, y).0.map(f64::from)
            } else {
                outside += 1;
                let r = render.get_pixel(x, y).0;
                std::array::from_fn(|c| (r[c] as f64 * gain(k)[c]).min(255.0))
            };
            let got = mine.get_pixel(x, y).0;
            // the render's own 8-bit rounding, scaled by the gain, plus the output's
            let off = (0..3).map(|c| (got[c] as f64 - expected[c]).abs()).fold(0.0, f64::max);
            assert!(off <= 1.0, "{file} ({x}, {y}): {got:?} against {expected:?} (hole mask {})", m[0]);
        }
    }
    assert!(inside > 0 && outside > 0);

    // every ONNX path through the CLI (tiny models; no refinement to keep it short)
    let models = root.join("models");
    let lama = onnx::write(&models, "lama.onnx", &onnx::tiny_lama());
    let depth = onnx::write(&models, "depth.onnx", &onnx::tiny_depth());
    let den = onnx::write(&models, "denoiser.onnx", &onnx::tiny_denoiser());
    let (lama, depth, den) = (lama.to_string_lossy(), depth.to_string_lossy(), den.to_string_lossy());
    for contract in ["depth-anything-v2", "depth-anything3"] {
        let r = remove(
            &format!("onnx_{contract}"),
            &[
                "--inpaint-model",
                &lama,
                "--depth-model",
                &depth,
                "--depth-contract",
                contract,
                "--depth-refiner",
                &den,
                "--diffusion-steps",
                "4",
                "--no-refine",
            ],
        );
        let c = &r["completion"];
        assert!(c["inpainter"].as_str().unwrap().contains("lama.onnx"));
        assert!(c["depth_prior"].as_str().unwrap().contains("depth.onnx"));
        assert!(c["depth_refiner"].as_str().unwrap().contains("denoiser.onnx"));
        assert!(r["fusion"]["patch_gaussians"].as_u64().unwrap() > 0);
    }
    // a depth model whose output cannot be anchored is an error naming the view
    let flat = onnx::write(&models, "flat_depth.onnx", &onnx::flat_depth());
    let out = std::process::Command::new(exe)
        .args(["remove", "--scene", &tagged, "--data", &data, "--labels", "1,2", "--out", &path("flat_out")])
        .args(["--depth-model", &flat.to_string_lossy(), "--no-refine"])
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    // every view fails; the first to run names itself (under `--rendered-depth auto` one of the
    // views with the largest holes, which are completed first)
    let stem = |e: &std::ffi::OsString| std::path::Path::new(e).file_stem().unwrap().to_string_lossy().into_owned();
    let named = edited.iter().any(|e| err.contains(&format!("completing view {}:", stem(e))));
    assert!(!out.status.success() && named && err.contains("the prior is constant"), "{err}");
    std::fs::remove_dir_all(&root).ok();
}

/// `cogeo run`: train, tag and remove in one command (tiny settings).
#[test]
fn run_does_train_tag_and_remove_in_one_command() {
    let exe = env!("CARGO_BIN_EXE_cogeo");
    let root = std::env::temp_dir().join(format!("cogeo_run_{}", std::process::id()));
    let path = |p: &str| root.join(p).to_string_lossy().into_owned();
    let data = path("data");
    run_cogeo(exe, &["synth", "--out", &data, "--width", "32", "--height", "24", "--views", "8", "--objects", "2"]);
    let out = path("run");
    let stderr = run_cogeo(
        exe,
        &[
            "run",
            "--data",
            &data,
            "--masks",
            "object_mask",
            "--out",
            &out,
            "--iters",
            "60",
            "--sh-degree",
            "0",
            "--tag-method",
            "vote",
            "--labels",
            "1",
            "--refine-iters",
            "10",
        ],
    );
    // stderr is a pipe here, not a terminal: the removal's stages show as plain lines, in order
    let stage_line =
        |stage: &str| stderr.find(&format!("remove: {stage} ")).unwrap_or_else(|| panic!("no {stage} line:\n{stderr}"));
    let order: Vec<usize> = ["masks", "complete", "refine", "render"].iter().map(|s| stage_line(s)).collect();
    assert!(order.windows(2).all(|p| p[0] < p[1]), "stages out of order:\n{stderr}");
    assert!(root.join("run/train/scene.ply").is_file());
    assert!(root.join("run/tagged.ply").is_file() && root.join("run/tagged.json").is_file());
    let r = report(&path("run/removal"));
    assert_eq!(r["labels"], serde_json::json!([1]));
    assert_eq!(r["refine"]["iters"].as_u64().unwrap(), 10);
    let clean = cogeo::scene::ply::read_ply(&root.join("run/removal/scene.ply")).unwrap();
    assert_eq!(clean.len() as u64, r["gaussians"]["output"].as_u64().unwrap());
    std::fs::remove_dir_all(&root).ok();
}
