//! Test helpers: a GPU context with the Khronos validation layer on (every test fails on any
//! validation message), and seeded random scenes with the hard cases the conventions name.
#![allow(dead_code)]

pub mod onnx;
pub mod wall;

use cogeo::gpu::{DeviceChoice, Gpu};
use cogeo::rng::Rng;
use cogeo::scene::{logit, Camera, GaussianScene};
use std::path::{Path, PathBuf};

/// A GPU context that asserts, when dropped at the end of a passing test, that the validation layer
/// reported nothing.
pub struct TestGpu(pub Gpu);

impl std::ops::Deref for TestGpu {
    type Target = Gpu;
    fn deref(&self) -> &Gpu {
        &self.0
    }
}

impl Drop for TestGpu {
    fn drop(&mut self) {
        if std::thread::panicking() {
            return;
        }
        let messages = self.0.validation_messages();
        assert!(messages.is_empty(), "Vulkan validation messages:\n{}", messages.join("\n"));
    }
}

/// A fixed, emptied folder `name` under the target's temporary directory: one per test name, not
/// one per process in /tmp (those piled up run after run).
pub fn scratch_dir(name: &str) -> PathBuf {
    let d = Path::new(env!("CARGO_TARGET_TMPDIR")).join(name);
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// Validation is on unless COGEO_VALIDATE=0 is set explicitly.
pub fn gpu() -> TestGpu {
    // One context per test process is never dropped, so that the driver always holds a device.
    // Tests create and drop contexts on up to 8 threads; on a lent H200 a test thread that ended
    // after the others had dropped theirs crashed in its thread-exit destructors, in driver code
    // unloaded meanwhile (`cogeo::gpu` keeps the loader and an instance for the same reason).
    let choice =
        |validate| DeviceChoice { selector: std::env::var("COGEO_DEVICE").ok(), validate, memory_limit_mib: None };
    static ANCHOR: std::sync::Once = std::sync::Once::new();
    ANCHOR.call_once(|| {
        if let Ok(anchor) = Gpu::new(&choice(false)) {
            std::mem::forget(anchor);
        }
    });
    let validate = std::env::var("COGEO_VALIDATE").map(|v| v != "0").unwrap_or(true);
    let gpu = Gpu::new(&choice(validate)).expect("cannot create the Vulkan context (is lavapipe installed?)");
    if validate {
        assert!(gpu.validating());
    }
    TestGpu(gpu)
}

/// `../shared/<rel>` beside the checkout (real captures, splats, networks), or None when it is
/// not there and the test should skip. The harness counts a skipped test as passed, so a skip is
/// also appended to the file `COGEO_SKIPPED_LOG` names (`scripts/test.sh` lists them at the end),
/// and with `COGEO_REQUIRE_SHARED=1` (the GPU checks, when all the data travelled) it fails.
pub fn shared(rel: &str) -> Option<PathBuf> {
    let p = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../shared").join(rel);
    if p.exists() {
        return Some(p);
    }
    // the test binary's name without cargo's hash, and the test's (the harness names its thread so)
    let exe = std::env::current_exe().ok().and_then(|e| e.file_stem().map(|s| s.to_string_lossy().into_owned()));
    let exe = exe.unwrap_or_default();
    let binary = exe.rsplit_once('-').map_or(exe.as_str(), |(name, _)| name);
    let test = format!("{binary} {}", std::thread::current().name().unwrap_or("?"));
    let required = std::env::var("COGEO_REQUIRE_SHARED").is_ok_and(|v| v == "1");
    assert!(!required, "{test}: ../shared/{rel} is missing (COGEO_REQUIRE_SHARED=1)");
    eprintln!("{test}: ../shared/{rel} not present; skipping");
    if let Some(log) = std::env::var_os("COGEO_SKIPPED_LOG") {
        use std::io::Write;
        let file = std::fs::OpenOptions::new().create(true).append(true).open(log);
        file.and_then(|mut f| writeln!(f, "{test}: ../shared/{rel} not present"))
            .expect("cannot write COGEO_SKIPPED_LOG");
    }
    None
}

/// `shared("data/<rel>")`: a real capture or splat.
pub fn shared_data(rel: &str) -> Option<PathBuf> {
    shared(&format!("data/{rel}"))
}

/// What kinds of Gaussians a random scene mixes in.
#[derive(Clone, Copy)]
pub struct SceneMix {
    pub normal: usize,
    pub tiny: usize,
    pub huge: usize,
    pub behind: usize,
    pub faint: usize,
    pub opaque: usize,
}

impl Default for SceneMix {
    fn default() -> Self {
        SceneMix { normal: 160, tiny: 40, huge: 6, behind: 20, faint: 40, opaque: 30 }
    }
}

/// A camera at (0, 0, -4) looking at the origin (+z forward, +y down).
pub fn test_camera(width: u32, height: u32) -> Camera {
    Camera::look_at("cam", width, height, 60.0, [0.3, -0.2, -4.0], [0.0, 0.0, 0.0], [0.0, -1.0, 0.0])
}

/// A seeded random scene around the origin, visible from `test_camera`.
pub fn random_scene(seed: u64, sh_degree: u32, mix: SceneMix) -> GaussianScene {
    let mut rng = Rng::new(seed);
    let mut scene = GaussianScene { sh_degree, ..Default::default() };
    let k = scene.sh_coeffs();
    let mut add = |rng: &mut Rng, pos: [f64; 3], log_scale: [f64; 3], opacity_logit: f32| {
        let quat = [rng.normal() as f32, rng.normal() as f32, rng.normal() as f32, rng.normal() as f32];
        let sh: Vec<f32> = (0..3 * k).map(|i| (if i < 3 { 1.2 } else { 0.3 } * rng.normal()) as f32).collect();
        scene.push(pos.map(|v| v as f32), log_scale.map(|v| v as f32), quat, opacity_logit, &sh);
    };
    let spread = |rng: &mut Rng| [rng.range(-2.0, 2.0), rng.range(-1.5, 1.5), rng.range(-1.5, 2.0)];
    for _ in 0..mix.normal {
        let p = spread(&mut rng);
        let s = [rng.range(-3.5, -1.2), rng.range(-3.5, -1.2), rng.range(-3.5, -1.2)];
        let o = rng.range(-2.0, 3.0) as f32;
        add(&mut rng, p, s, o);
    }
    for _ in 0..mix.tiny {
        let p = spread(&mut rng);
        let s = [rng.range(-9.0, -6.0), rng.range(-9.0, -6.0), rng.range(-9.0, -6.0)];
        let o = rng.range(0.0, 4.0) as f32;
        add(&mut rng, p, s, o);
    }
    for _ in 0..mix.huge {
        // large but with anisotropy below 10, so float32 stays well conditioned
        let p = spread(&mut rng);
        let base = rng.range(0.0, 1.0);
        let s = [base + rng.range(-1.0, 1.0), base + rng.range(-1.0, 1.0), base + rng.range(-1.0, 1.0)];
        let o = rng.range(-4.0, -1.0) as f32;
        add(&mut rng, p, s, o);
    }
    for _ in 0..mix.behind {
        let p = [rng.range(-2.0, 2.0), rng.range(-2.0, 2.0), rng.range(-8.0, -4.05)];
        let s = [rng.range(-2.0, 0.0), rng.range(-2.0, 0.0), rng.range(-2.0, 0.0)];
        add(&mut rng, p, s, 2.0);
    }
    for _ in 0..mix.faint {
        // opacity within a few percent of 1/255, on both sides
        let p = spread(&mut rng);
        let s = [rng.range(-2.5, -1.0), rng.range(-2.5, -1.0), rng.range(-2.5, -1.0)];
        let o = logit(rng.range(0.9, 1.1) / 255.0);
        add(&mut rng, p, s, o);
    }
    for _ in 0..mix.opaque {
        let p = spread(&mut rng);
        let s = [rng.range(-3.0, -1.5), rng.range(-3.0, -1.5), rng.range(-3.0, -1.5)];
        let o = logit(1.0 - rng.range(1e-5, 1e-3));
        add(&mut rng, p, s, o);
    }
    scene
}

/// A random N x D feature matrix.
pub fn random_features(seed: u64, n: usize, d: usize) -> Vec<f32> {
    let mut rng = Rng::new(seed);
    (0..n * d).map(|_| rng.normal() as f32).collect()
}

/// Runs the cogeo binary `exe` (the test's `env!("CARGO_BIN_EXE_cogeo")`) with `args`, validation on
/// unless COGEO_VALIDATE=0; asserts success and no validation messages, and returns its stderr.
pub fn run_cogeo(exe: &str, args: &[&str]) -> String {
    let output = std::process::Command::new(exe)
        .env("COGEO_VALIDATE", std::env::var("COGEO_VALIDATE").unwrap_or_else(|_| "1".into()))
        .args(args)
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&output.stderr).to_string();
    assert!(output.status.success(), "{args:?} failed:\n{stderr}");
    assert!(!stderr.contains("vulkan validation:"), "validation messages:\n{stderr}");
    stderr
}

/// Central differences of `f` at `x` for every coordinate in `which`.
pub fn finite_differences(x: &mut [f64], which: std::ops::Range<usize>, h: f64, f: impl Fn(&[f64]) -> f64) -> Vec<f64> {
    which
        .map(|i| {
            let v = x[i];
            x[i] = v + h;
            let up = f(x);
            x[i] = v - h;
            let down = f(x);
            x[i] = v;
            (up - down) / (2.0 * h)
        })
        .collect()
}

/// Every file under `dir` (or `dir` itself, a file) with its bytes, sorted by path: to prove files
/// unchanged.
pub fn snapshot(dir: &Path) -> Vec<(PathBuf, Vec<u8>)> {
    if dir.is_file() {
        return vec![(dir.to_path_buf(), std::fs::read(dir).unwrap())];
    }
    let mut out = Vec::new();
    let mut stack = vec![dir.to_path_buf()];
    while let Some(d) = stack.pop() {
        for e in std::fs::read_dir(&d).unwrap().flatten() {
            let p = e.path();
            if p.is_dir() {
                stack.push(p);
            } else {
                out.push((p.clone(), std::fs::read(&p).unwrap()));
            }
        }
    }
    out.sort();
    out
}
