//! Resource faults: work that needs more device memory than the device (or `--max-device-memory`)
//! allows stops with one error naming the buffer, the sizes and the device, before any output
//! folder exists; a disk that fills up while outputs are written (a file-size limit, RLIMIT_FSIZE,
//! with SIGXFSZ ignored so that writes fail with EFBIG as on a full disk) gives an error naming the
//! file, and every previous output stays byte for byte, including the small files that fit before
//! the disk filled (remove's refinement is not bit-reproducible, so a rewrite would show). Validation
//! layer on.

mod common;

use common::run_cogeo;
use std::path::{Path, PathBuf};
use std::process::{Command, Output};
use std::sync::OnceLock;

const EXE: &str = env!("CARGO_BIN_EXE_cogeo");

fn root() -> &'static PathBuf {
    static ROOT: OnceLock<PathBuf> = OnceLock::new();
    ROOT.get_or_init(|| {
        let root = common::scratch_dir("faults");
        let p = |s: &str| root.join(s).to_string_lossy().into_owned();
        run_cogeo(
            EXE,
            &["synth", "--out", &p("data"), "--width", "32", "--height", "24", "--views", "8", "--objects", "2"],
        );
        run_cogeo(EXE, &["train", "--data", &p("data"), "--out", &p("trained"), "--iters", "40", "--sh-degree", "0"]);
        let tag = ["tag", "--scene", &p("trained/scene.ply"), "--data", &p("data"), "--masks", "object_mask"];
        run_cogeo(EXE, &[&tag[..], &["--method", "vote", "--out", &p("tagged.ply")]].concat());
        root
    })
}

fn path(p: &str) -> String {
    root().join(p).to_string_lossy().into_owned()
}

/// Runs cogeo through `sh` with `limit` (e.g. `ulimit -f 4`) applied first.
fn run_limited(limit: &str, args: &[&str]) -> Output {
    let quoted: Vec<String> = args.iter().map(|a| format!("'{a}'")).collect();
    Command::new("sh")
        .arg("-c")
        .arg(format!("trap '' XFSZ; {limit}; exec '{EXE}' {}", quoted.join(" ")))
        .env("COGEO_VALIDATE", std::env::var("COGEO_VALIDATE").unwrap_or_else(|_| "1".into()))
        .output()
        .unwrap()
}

/// One `error:` line with every `expect` in it, exit status 1.
fn assert_one_error(out: &Output, expect: &[&str], what: &str) -> String {
    let stderr = String::from_utf8_lossy(&out.stderr).into_owned();
    assert_eq!(out.status.code(), Some(1), "{what}: exit status {:?}\n{stderr}", out.status);
    let errors: Vec<&str> = stderr.lines().filter(|l| l.starts_with("error:")).collect();
    assert_eq!(errors.len(), 1, "{what}: expected one error line:\n{stderr}");
    for e in expect {
        assert!(errors[0].contains(e), "{what}: the error does not mention {e:?}: {}", errors[0]);
    }
    assert!(!stderr.contains("vulkan validation:"), "{what}: validation messages:\n{stderr}");
    errors[0].to_string()
}

#[test]
fn train_remove_and_render_past_the_device_memory_name_sizes_and_device() {
    let device = "MiB of device memory, of which cogeo may use 0.05 MiB (--max-device-memory)";
    let (data, tagged, model) = (path("data"), path("tagged.ply"), path("data/sparse/0"));
    let cases: [(&str, Vec<&str>); 3] = [
        ("train", vec!["train", "--data", &data, "--iters", "10"]),
        ("remove", vec!["remove", "--scene", &tagged, "--data", &data, "--labels", "1"]),
        ("render", vec!["render", "--scene", &tagged, "--colmap", &model]),
    ];
    for (name, args) in cases {
        let out_dir = path(&format!("oom_{name}"));
        let mut args = args;
        args.extend(["--out", &out_dir, "--max-device-memory", "0.05"]);
        let out = run_limited("true", &args);
        let error = assert_one_error(&out, &["out of GPU memory: buffer", "already in use", device], name);
        // the device is named as `cogeo devices` names it
        let gpu = cogeo::gpu::Gpu::new(&cogeo::gpu::DeviceChoice::from_env(None)).unwrap();
        assert!(error.contains(&gpu.info().name), "{name}: the device is not named: {error}");
        assert!(!Path::new(&out_dir).exists(), "{name}: created its output folder before failing");
    }
}

#[test]
fn a_full_disk_while_writing_keeps_the_previous_outputs() {
    // blocks of 512 bytes: every PLY is larger than 8, every 32x24 image than 1
    let (data, tagged, model) = (path("data"), path("tagged.ply"), path("data/sparse/0"));
    let cases: [(&str, &str, Vec<&str>); 3] = [
        ("train", "ulimit -f 8", vec!["train", "--data", &data, "--iters", "20", "--sh-degree", "0"]),
        (
            "remove",
            "ulimit -f 8",
            vec!["remove", "--scene", &tagged, "--data", &data, "--labels", "1", "--refine-iters", "5"],
        ),
        ("render", "ulimit -f 1", vec!["render", "--scene", &tagged, "--colmap", &model, "--depth"]),
    ];
    for (name, limit, args) in cases {
        let out_dir = path(&format!("disk_{name}"));
        let mut args = args;
        args.extend(["--out", &out_dir]);
        run_cogeo(EXE, &args);
        let before = common::snapshot(Path::new(&out_dir));
        let out = run_limited(limit, &args);
        assert_one_error(&out, &["File too large", &out_dir], name);
        let after = common::snapshot(Path::new(&out_dir));
        let names = |f: &[(PathBuf, Vec<u8>)]| f.iter().map(|(p, _)| p.clone()).collect::<Vec<_>>();
        assert_eq!(names(&after), names(&before), "{name}: files appeared or vanished (temporary files left?)");
        for ((p, a), (_, b)) in after.iter().zip(&before) {
            // outputs are renamed into place together at the end (io::OutputBatch): none changes
            assert!(a == b, "{name}: {} changed after the failed run", p.display());
        }
    }
}
