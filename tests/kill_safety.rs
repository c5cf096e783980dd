//! Kill safety: `train`, `tag`, `remove` and `render`, killed with SIGKILL at several points of
//! their run (into a fresh output folder and over a previous complete output), leave every output
//! file complete and valid or absent, never touch their inputs, and a run after the kill succeeds
//! and leaves no temporary files behind. Validation layer on (COGEO_VALIDATE=1, as the suite runs).

mod common;

use common::run_cogeo;
use std::path::{Path, PathBuf};
use std::process::Command;
use std::sync::OnceLock;
use std::time::{Duration, Instant};

const EXE: &str = env!("CARGO_BIN_EXE_cogeo");

/// A tiny capture, a scene trained on it and the scene tagged: the inputs of the four commands.
struct Fixture {
    root: PathBuf,
}

impl Fixture {
    fn path(&self, p: &str) -> String {
        self.root.join(p).to_string_lossy().into_owned()
    }
}

fn fixture() -> &'static Fixture {
    static FIXTURE: OnceLock<Fixture> = OnceLock::new();
    FIXTURE.get_or_init(|| {
        let root = common::scratch_dir("kill_safety");
        let f = Fixture { root };
        let (data, train, tagged) = (f.path("data"), f.path("trained"), f.path("tagged.ply"));
        let synth = ["synth", "--out", &data, "--width", "32", "--height", "24", "--views", "8", "--objects", "2"];
        run_cogeo(EXE, &synth);
        run_cogeo(EXE, &["train", "--data", &data, "--out", &train, "--iters", "60", "--sh-degree", "0"]);
        let scene = f.path("trained/scene.ply");
        let tag = ["tag", "--scene", &scene, "--data", &data, "--masks", "object_mask", "--method", "vote"];
        run_cogeo(EXE, &[&tag[..], &["--out", &tagged]].concat());
        f
    })
}

/// Checks every file under `dir` by its kind; returns the temporary files of killed writers.
fn check_outputs(dir: &Path, context: &str) -> Vec<PathBuf> {
    let mut temps = Vec::new();
    if !dir.exists() {
        return temps;
    }
    for (path, bytes) in common::snapshot(dir) {
        let name = path.file_name().unwrap().to_string_lossy().into_owned();
        let what = format!("{context}: {}", path.display());
        if name.starts_with('.') && name.ends_with(".tmp") {
            temps.push(path);
            continue;
        }
        match path.extension().and_then(|e| e.to_str()).unwrap_or("") {
            "ply" => {
                let scene =
                    cogeo::scene::ply::read_ply_from(&mut &bytes[..], &what).unwrap_or_else(|e| panic!("{e:#}"));
                scene.validate(&what).unwrap_or_else(|e| panic!("{e:#}"));
            }
            "png" => {
                cogeo::io::decode_image(&bytes, &what).unwrap_or_else(|e| panic!("{e:#}"));
            }
            "json" => {
                serde_json::from_slice::<serde_json::Value>(&bytes).unwrap_or_else(|e| panic!("{what}: {e}"));
            }
            "exr" => {
                cogeo::io::read_exr_channel(&path, None).unwrap_or_else(|e| panic!("{what}: {e:#}"));
            }
            "bin" => {
                // moments.bin: the checkpoint folder it is in must load as a whole
                let out = path.parent().unwrap().parent().unwrap();
                cogeo::train::checkpoint::load(out).unwrap_or_else(|e| panic!("{what}: {e:#}"));
            }
            _ => panic!("{what}: an output this test does not know how to check"),
        }
    }
    temps
}

/// Runs `args` to completion and returns how long it took.
fn timed_run(args: &[&str]) -> Duration {
    let start = Instant::now();
    run_cogeo(EXE, args);
    start.elapsed()
}

/// Starts `args` and kills it with SIGKILL after `after`, unless it finishes first: `None` when
/// the kill interrupted the run, else how long the run took.
fn kill_after(args: &[&str], after: Duration) -> Option<Duration> {
    let start = Instant::now();
    let mut child = Command::new(EXE)
        .env("COGEO_VALIDATE", std::env::var("COGEO_VALIDATE").unwrap_or_else(|_| "1".into()))
        .args(args)
        .stdout(std::process::Stdio::null())
        .stderr(std::process::Stdio::null())
        .spawn()
        .unwrap();
    while start.elapsed() < after {
        if let Some(status) = child.try_wait().unwrap() {
            assert!(status.success(), "{args:?} failed ({status}) before it was killed");
            return Some(start.elapsed());
        }
        std::thread::sleep(Duration::from_millis(2));
    }
    let _ = child.kill(); // SIGKILL; the run may have finished since the last look
    use std::os::unix::process::ExitStatusExt;
    let status = child.wait().unwrap();
    (status.signal() != Some(9)).then(|| start.elapsed())
}

/// The kill protocol for one command writing into `out` (a folder, or a file and its sidecar).
fn kill_repeatedly(name: &str, args: &[&str], outputs: &[PathBuf], inputs: &[PathBuf]) {
    let before: Vec<_> = inputs.iter().map(|p| common::snapshot(p)).collect();
    let check_all = |context: &str| -> usize { outputs.iter().map(|o| check_outputs(o, context).len()).sum() };
    // a fresh output folder, killed early and late; then over a complete previous output. The
    // faster of two runs sets the kill times: with the other tests loading the machine a single
    // slow run put later kills after the end of faster runs
    let full = timed_run(args).min(timed_run(args));
    for o in outputs {
        let _ = std::fs::remove_dir_all(o);
    }
    let mut rng = cogeo::rng::Rng::new(name.len() as u64 * 7919);
    let (mut full, mut interrupted, mut temps) = (full, 0, 0);
    for (k, fraction) in [0.25, 0.6, 0.1, 0.4, 0.7, 0.85].into_iter().enumerate() {
        if k == 2 {
            timed_run(args); // from here on, each kill interrupts an overwrite
        }
        // a run that finished before its kill (a machine less loaded than when `full` was
        // timed: a lent GPU machine ran the removal in a fraction of it) sets a shorter `full`
        // and is killed again, at most twice
        for _ in 0..3 {
            let jitter = rng.range(0.9, 1.1);
            let finished = kill_after(args, full.mul_f64(fraction * jitter));
            temps += check_all(&format!("{name}, killed at {:.0} % of its run", fraction * 100.0));
            match finished {
                None => {
                    interrupted += 1;
                    break;
                }
                Some(took) => full = full.min(took),
            }
        }
    }
    eprintln!("{name}: {interrupted} of 6 kills interrupted the run; {temps} temporary files seen after them");
    assert!(interrupted >= 3, "{name}: only {interrupted} of 6 kills landed inside the run");
    for (input, snap) in inputs.iter().zip(&before) {
        assert!(common::snapshot(input) == *snap, "{name} changed its input {}", input.display());
    }
    timed_run(args);
    let temps = check_all(&format!("{name}, run after the kills"));
    assert_eq!(temps, 0, "{name}: temporary files of killed runs are still there after a complete run");
}

#[test]
fn train_killed_at_random_points() {
    let f = fixture();
    let out = f.path("kill_train");
    let args = ["train", "--data", &f.path("data"), "--out", &out, "--iters", "60", "--sh-degree", "0"];
    let args = [&args[..], &["--checkpoint-every", "20"]].concat();
    kill_repeatedly("train", &args, &[PathBuf::from(&out)], &[f.root.join("data")]);
}

#[test]
fn tag_killed_at_random_points() {
    let f = fixture();
    let dir = f.root.join("kill_tag");
    let out = dir.join("tagged.ply").to_string_lossy().into_owned();
    let scene = f.path("trained/scene.ply");
    let args = ["tag", "--scene", &scene, "--data", &f.path("data"), "--masks", "object_mask", "--out", &out];
    let args = [&args[..], &["--iters", "30"]].concat();
    kill_repeatedly("tag", &args, &[dir], &[f.root.join("data"), f.root.join("trained")]);
}

#[test]
fn remove_killed_at_random_points() {
    let f = fixture();
    let out = f.path("kill_remove");
    let tagged = f.path("tagged.ply");
    let args = ["remove", "--scene", &tagged, "--data", &f.path("data"), "--labels", "1", "--out", &out];
    let args = [&args[..], &["--refine-iters", "10"]].concat();
    let inputs = [f.root.join("data"), f.root.join("tagged.ply"), f.root.join("tagged.json")];
    kill_repeatedly("remove", &args, &[PathBuf::from(&out)], &inputs);
}

#[test]
fn render_killed_at_random_points() {
    let f = fixture();
    let out = f.path("kill_render");
    let tagged = f.path("tagged.ply");
    let colmap = f.path("data/sparse/0");
    // upscaled outputs, so that writing is a good part of the run and kills land inside writes
    let args = ["render", "--scene", &tagged, "--colmap", &colmap, "--out", &out, "--depth", "--alpha", "--labels"];
    let args = [&args[..], &["--width", "320"]].concat();
    kill_repeatedly("render", &args, &[PathBuf::from(&out)], &[f.root.join("data"), f.root.join("tagged.ply")]);
}
