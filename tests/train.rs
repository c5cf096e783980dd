//! End-to-end training on a small `cogeo synth` scene through the CLI, killed mid-run (SIGKILL) and
//! resumed from its checkpoint: the run must finish, leave no partial files, and reach a measured
//! test-view PSNR.

use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::{Duration, Instant};

fn tempdir(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("cogeo-train-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    d
}

fn cogeo() -> Command {
    let mut c = Command::new(env!("CARGO_BIN_EXE_cogeo"));
    c.env("COGEO_VALIDATE", std::env::var("COGEO_VALIDATE").unwrap_or_else(|_| "1".into()));
    c
}

fn checkpoint_step(out: &Path) -> Option<u64> {
    let text = std::fs::read_to_string(out.join("checkpoint/state.json")).ok()?;
    let v: serde_json::Value = serde_json::from_str(&text).ok()?;
    v["step"].as_u64()
}

/// Every file under `dir` that is a leftover temporary (a write that did not complete).
fn temporaries(dir: &Path) -> Vec<PathBuf> {
    let mut out = Vec::new();
    for e in std::fs::read_dir(dir).unwrap().flatten() {
        let p = e.path();
        if p.is_dir() {
            if p.file_name().unwrap() != "checkpoint.tmp" {
                out.extend(temporaries(&p));
            }
        } else if p.to_string_lossy().ends_with(".tmp") {
            out.push(p);
        }
    }
    out
}

#[test]
fn train_synth_scene_survives_a_kill_and_reaches_psnr() {
    let data = tempdir("data");
    let out = tempdir("out");
    let status = cogeo()
        .args(["synth", "--out", data.to_str().unwrap(), "--width", "64", "--height", "48", "--views", "16"])
        .args(["--objects", "1", "--seed", "3", "--points-per-view", "150"])
        .status()
        .unwrap();
    assert!(status.success());
    for f in [
        "sparse/0/cameras.txt",
        "sparse/0/images.txt",
        "sparse/0/points3D.txt",
        "images/view_000.png",
        "object_mask/view_005.png",
        "gt_background/view_005.png",
        "depth/view_005.exr",
        "unseen_mask/view_005.png",
        "synth.json",
    ] {
        assert!(data.join(f).exists(), "synth did not write {f}");
    }

    let train_args = |resume: bool| {
        let mut args = vec!["train", "--data", data.to_str().unwrap(), "--out", out.to_str().unwrap()];
        args.extend(["--iters", "1000", "--checkpoint-every", "150", "--max-gaussians", "8000", "--sh-degree", "1"]);
        if resume {
            args.push("--resume");
        }
        args.into_iter().map(String::from).collect::<Vec<_>>()
    };
    let mut child = cogeo().args(train_args(false)).stderr(std::process::Stdio::null()).spawn().unwrap();
    let start = Instant::now();
    let killed_at = loop {
        if let Some(step) = checkpoint_step(&out).filter(|&s| s >= 300) {
            break step;
        }
        assert!(child.try_wait().unwrap().is_none(), "training ended before it could be killed");
        assert!(start.elapsed() < Duration::from_secs(900), "no checkpoint after 15 minutes");
        std::thread::sleep(Duration::from_millis(200));
    };
    child.kill().unwrap(); // SIGKILL: no chance to clean up
    child.wait().unwrap();
    assert!(!out.join("scene.ply").exists(), "the final scene must not exist before the run finished");
    assert!(temporaries(&out).is_empty(), "partial files visible after the kill: {:?}", temporaries(&out));

    let output = cogeo().args(train_args(true)).output().unwrap();
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert!(output.status.success(), "resume failed:\n{stderr}");
    assert!(stderr.contains("resumed at iteration"), "did not resume:\n{stderr}");
    assert!(!stderr.contains("vulkan validation:"), "validation messages:\n{stderr}");
    assert!(temporaries(&out).is_empty());

    let metrics: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("metrics.json")).unwrap()).unwrap();
    let psnr = metrics["test"]["psnr"].as_f64().unwrap();
    let ssim = metrics["test"]["ssim"].as_f64().unwrap();
    println!("killed after checkpoint {killed_at}; final test PSNR {psnr:.2} dB, SSIM {ssim:.3}; {}", metrics);
    assert_eq!(metrics["iterations"].as_u64(), Some(1000));
    // measured 20.4 dB / SSIM 0.722 on lavapipe for this seed and budget (killed at 300 and resumed);
    // the bar leaves a margin for the run-to-run noise of float-atomic ordering and the kill point
    assert!(psnr >= 18.5, "test PSNR {psnr:.2} dB");
    assert!(ssim >= 0.62, "test SSIM {ssim:.3}");
    let scene = cogeo::scene::ply::read_ply(&out.join("scene.ply")).unwrap();
    scene.validate("trained scene").unwrap();
}
