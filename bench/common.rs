//! Shared pieces of the benchmarks: argument handling, synthetic scenes, result files.
#![allow(dead_code)]

use cogeo::gpu::{DeviceChoice, Gpu};
use cogeo::rng::Rng;
use cogeo::scene::GaussianScene;
use std::path::PathBuf;

/// The stages of `cogeo remove`'s report (`seconds`), in pipeline order: the stage tables of the
/// removal and removal_speed benches. A binary older than a stage reads no time for it (`hull` is
/// from 2026-11-29).
pub const REMOVAL_STAGES: [&str; 9] =
    ["select", "masks", "hull", "complete", "photo_depth", "transfer", "fuse", "refine", "render"];

/// Arguments after `cargo bench --bench NAME --`; cargo's own `--bench` flag is ignored.
pub fn args() -> Vec<String> {
    std::env::args().skip(1).filter(|a| a != "--bench").collect()
}

/// Value of `--name value` among the arguments.
pub fn arg(args: &[String], name: &str) -> Option<String> {
    args.iter().position(|a| a == name).and_then(|i| args.get(i + 1).cloned())
}

/// `--remove-args "--refine-coverage-weight 1 ..."` among `args`: flags a removal bench adds to
/// every `cogeo remove` it runs, split at whitespace (none without the option).
pub fn remove_args(args: &[String]) -> Vec<String> {
    arg(args, "--remove-args").map_or(vec![], |f| f.split_whitespace().map(str::to_string).collect())
}

/// Comma-separated counts of `--name` (e.g. --sizes 100000,1000000), or `default`.
pub fn counts(args: &[String], name: &str, default: &str) -> Vec<usize> {
    arg(args, name)
        .unwrap_or_else(|| default.into())
        .split(',')
        .map(|s| s.parse().unwrap_or_else(|_| panic!("{name}: comma-separated counts, got {s:?}")))
        .collect()
}

/// Comma-separated WxH resolutions of `--name`, or `default`.
pub fn resolutions(args: &[String], name: &str, default: &str) -> Vec<(u32, u32)> {
    arg(args, name)
        .unwrap_or_else(|| default.into())
        .split(',')
        .map(|r| {
            let (w, h) = r.split_once('x').unwrap_or_else(|| panic!("{name}: WxH, got {r:?}"));
            (w.parse().unwrap(), h.parse().unwrap())
        })
        .collect()
}

pub fn gpu() -> Gpu {
    Gpu::new(&DeviceChoice::from_env(None)).expect("cannot create the Vulkan context")
}

/// `n` random Gaussians of SH degree `degree` filling a 4x4x4 box, sized so that neighbours overlap
/// about as much as in trained scenes (sigma ~ 0.6 x mean spacing).
pub fn synthetic_scene(n: usize, degree: u32, seed: u64) -> GaussianScene {
    let mut rng = Rng::new(seed);
    let k = ((degree + 1) * (degree + 1)) as usize;
    let spacing = 4.0 / (n as f64).cbrt();
    let mut s = GaussianScene { sh_degree: degree, ..Default::default() };
    s.means.reserve(n);
    s.sh.reserve(n * k * 3);
    for _ in 0..n {
        s.means.push([rng.range(-2.0, 2.0) as f32, rng.range(-2.0, 2.0) as f32, rng.range(-2.0, 2.0) as f32]);
        s.normals.push([0.0; 3]);
        let base = (0.6 * spacing).ln();
        s.log_scales.push([0, 1, 2].map(|_| (base + 0.4 * rng.normal()) as f32));
        s.quats.push([0, 1, 2, 3].map(|_| rng.normal() as f32));
        s.opacity_logits.push((1.5 * rng.normal()) as f32);
        for b in 0..k {
            for _ in 0..3 {
                s.sh.push((if b == 0 { 1.0 } else { 0.2 } * rng.normal()) as f32);
            }
        }
    }
    s
}

/// Whether `args` make a trial run (`--no-results`), which must leave the committed results as
/// they are.
pub fn trial_run(args: &[String]) -> bool {
    args.iter().any(|a| a == "--no-results")
}

/// Where a bench writes `name` (JSON, tables, images): bench/results, or on a trial run
/// (`trial_run`) a folder under the system's temporary directory.
pub fn results_path(name: &str) -> PathBuf {
    let folder = if trial_run(&args()) {
        let trial = std::env::temp_dir().join("cogeo-bench-trial-results");
        std::fs::create_dir_all(&trial).unwrap_or_else(|e| panic!("cannot create {}: {e}", trial.display()));
        trial
    } else {
        PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("bench").join("results")
    };
    folder.join(name)
}

/// File-name-safe short name of the device ("llvmpipe", "nvidia-h100", ...).
pub fn device_slug(gpu: &Gpu) -> String {
    let name = gpu.info().name.to_lowercase();
    let first: String = name
        .split(|c: char| !c.is_ascii_alphanumeric())
        .filter(|w| !w.is_empty())
        .take(3)
        .collect::<Vec<_>>()
        .join("-");
    first
}

pub fn write_json(path: &std::path::Path, value: &serde_json::Value) {
    let text = serde_json::to_string_pretty(value).unwrap();
    cogeo::io::write_atomic(path, |w| {
        use std::io::Write;
        w.write_all(text.as_bytes()).map_err(Into::into)
    })
    .unwrap();
    println!("wrote {}", path.display());
}

/// The median of `v` (of an even count, the mean of the middle two).
pub fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(|a, b| a.partial_cmp(b).unwrap());
    let n = v.len();
    if n.is_multiple_of(2) {
        0.5 * (v[n / 2 - 1] + v[n / 2])
    } else {
        v[n / 2]
    }
}

/// Runs the `cogeo` binary of this build with `args`, panics with its stderr when it fails, and
/// returns the wall time in seconds (also printed with the command line).
pub fn cogeo(args: &[String]) -> f64 {
    run_binary(std::path::Path::new(env!("CARGO_BIN_EXE_cogeo")), args)
}

/// `cogeo` for any cogeo binary `exe` (an older build to compare with).
pub fn run_binary(exe: &std::path::Path, args: &[String]) -> f64 {
    let t = std::time::Instant::now();
    let out = std::process::Command::new(exe)
        .args(args)
        .output()
        .unwrap_or_else(|e| panic!("cannot run {}: {e}", exe.display()));
    if !out.status.success() {
        panic!("{} {} failed:\n{}", exe.display(), args.join(" "), String::from_utf8_lossy(&out.stderr));
    }
    let seconds = t.elapsed().as_secs_f64();
    eprintln!("  {seconds:>7.1} s  {} {}", exe.display(), args.join(" "));
    seconds
}

/// The folder under target/bench-cache where benches keep what they made for later runs.
pub fn bench_cache() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("target/bench-cache")
}

/// The shared real capture `name` (../shared/data/name).
pub fn shared_capture(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../shared/data").join(name)
}

/// Fills the folder `dir` with `make`, which writes into the folder it is given: a sibling
/// `<dir>.partial`, moved to `dir` only once `make` returns, so an interrupted run leaves no
/// half-made folder for a later run to trust.
pub fn make_folder(dir: &std::path::Path, make: impl FnOnce(&std::path::Path)) {
    // the whole name and a suffix: `with_extension` would cut a name such as cup-images-d1.5-i800
    let mut partial = dir.as_os_str().to_owned();
    partial.push(".partial");
    let partial = std::path::PathBuf::from(partial);
    std::fs::remove_dir_all(&partial).ok();
    std::fs::create_dir_all(&partial).unwrap_or_else(|e| panic!("cannot create {}: {e}", partial.display()));
    make(&partial);
    std::fs::remove_dir_all(dir).ok();
    std::fs::rename(&partial, dir)
        .unwrap_or_else(|e| panic!("cannot move {} to {}: {e}", partial.display(), dir.display()));
}

pub fn read_json(p: &std::path::Path) -> serde_json::Value {
    serde_json::from_str(&std::fs::read_to_string(p).unwrap_or_else(|e| panic!("{}: {e}", p.display())))
        .unwrap_or_else(|e| panic!("{}: {e}", p.display()))
}

/// Owned copies of string literals, for argument lists.
pub fn s(v: &[&str]) -> Vec<String> {
    v.iter().map(|x| x.to_string()).collect()
}

/// The device's copy bandwidth (gpu::bandwidth), measured on 256 MiB and printed: the roof of the
/// benches' roofline columns.
pub fn copy_bandwidth(gpu: &Gpu) -> cogeo::gpu::bandwidth::CopyBandwidth {
    let bw = cogeo::gpu::bandwidth::measure(gpu, 256 << 20, 3).expect("cannot measure the copy bandwidth");
    println!(
        "copy bandwidth (read + write): {:.1} GB/s compute copy (the roof below), {:.1} GB/s transfer copy",
        bw.shader_gbps, bw.transfer_gbps,
    );
    bw
}

/// Per-pass GPU times over repeated runs, with the bytes each pass states it moves.
#[derive(Default)]
pub struct PassStats {
    order: Vec<String>,
    ms: std::collections::BTreeMap<String, Vec<f64>>,
    bytes: std::collections::BTreeMap<String, u64>,
}

impl PassStats {
    pub fn add(&mut self, timings: &[cogeo::gpu::PassTiming]) {
        for p in timings {
            if !self.order.contains(&p.pass) {
                self.order.push(p.pass.clone());
            }
            self.ms.entry(p.pass.clone()).or_default().push(p.ms);
            self.bytes.insert(p.pass.clone(), p.bytes);
        }
    }

    /// Each pass in first-seen order with its median time and its bytes.
    pub fn medians(&self) -> Vec<cogeo::gpu::PassTiming> {
        self.order
            .iter()
            .map(|p| cogeo::gpu::PassTiming { pass: p.clone(), ms: median(self.ms[p].clone()), bytes: self.bytes[p] })
            .collect()
    }

    /// Prints one line per pass: time, and where the pass states its bytes, the MB it moves, its
    /// GB/s and the share of the roof (the copy bandwidth) that is.
    pub fn print(&self, indent: &str, roof_gbps: f64) {
        for t in self.medians() {
            let roofline = t
                .gbps()
                .map(|gbps| {
                    let mb = t.bytes as f64 / 1e6;
                    format!("  {mb:>9.1} MB {gbps:>7.2} GB/s {:>5.1} % of copy", 100.0 * gbps / roof_gbps)
                })
                .unwrap_or_default();
            println!("{indent}{:<20} {:>10.2} ms{roofline}", t.pass, t.ms);
        }
    }

    /// The passes as JSON rows: pass, ms, and where stated bytes, GB/s and share of the roof.
    pub fn json(&self, roof_gbps: f64) -> Vec<serde_json::Value> {
        self.medians()
            .into_iter()
            .map(|t| {
                let gbps = t.gbps();
                serde_json::json!({"pass": t.pass, "ms": t.ms, "bytes": (t.bytes > 0).then_some(t.bytes), "gbps": gbps,
                                   "share_of_copy": gbps.map(|g| g / roof_gbps)})
            })
            .collect()
    }
}

/// A bench's markdown table: each line printed as it is made, and kept for `update_results`.
#[derive(Default)]
pub struct Table {
    pub md: String,
}

impl Table {
    /// A table headed by the command line that made it (with `what`, e.g. "3 frames, ms"), the
    /// device (`device`, or none for a CPU-only bench) and the date, then its `columns` row
    /// ("| a | b |") and `align` row ("|---|---:|").
    pub fn new(bench: &str, args: &[String], what: &str, device: Option<&str>, columns: &str, align: &str) -> Table {
        let mut t = Table::default();
        let what = if what.is_empty() { String::new() } else { format!(", {what}") };
        let device = device.map(|d| format!("{d}, ")).unwrap_or_default();
        println!();
        t.line(format!("{}{what}; {device}{}.\n", command_line(bench, args), today()));
        t.line(columns.into());
        t.line(align.into());
        t
    }

    pub fn line(&mut self, line: String) {
        println!("{line}");
        self.md.push_str(&line);
        self.md.push('\n');
    }
}

/// Replaces the text between `<!-- {section}:begin -->` and `<!-- {section}:end -->` in
/// bench/RESULTS.md with `md`, so the file holds each bench's latest table and no hand-copied
/// numbers. Skipped with `--no-results` among `args` (a trial run that should not replace them).
pub fn update_results(args: &[String], section: &str, md: &str) {
    if trial_run(args) || args.iter().any(|a| a == "--no-readme") {
        return;
    }
    let path = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("bench/RESULTS.md");
    let text = std::fs::read_to_string(&path).unwrap();
    let (begin, end) = (format!("<!-- {section}:begin -->"), format!("<!-- {section}:end -->"));
    let (Some(b), Some(e)) = (text.find(&begin), text.find(&end)) else {
        println!("bench/RESULTS.md has no {section} markers; left as is");
        return;
    };
    let new = format!("{}{begin}\n{}\n{}", &text[..b], md.trim_end(), &text[e..]);
    cogeo::io::write_atomic(&path, |w| {
        use std::io::Write;
        w.write_all(new.as_bytes()).map_err(Into::into)
    })
    .unwrap();
    println!("updated the {section} table in {}", path.display());
}

/// The command line a bench ran with, for the heading of its table.
pub fn command_line(bench: &str, args: &[String]) -> String {
    if args.is_empty() {
        format!("`cargo bench --bench {bench}`")
    } else {
        format!("`cargo bench --bench {bench} -- {}`", args.join(" "))
    }
}

/// Today's date (UTC) as YYYY-MM-DD, for the heading of a bench's table.
pub fn today() -> String {
    let days = std::time::SystemTime::now().duration_since(std::time::UNIX_EPOCH).unwrap().as_secs() / 86_400;
    // civil-from-days (Howard Hinnant's algorithm)
    let z = days as i64 + 719_468;
    let era = z.div_euclid(146_097);
    let doe = z - era * 146_097;
    let yoe = (doe - doe / 1460 + doe / 36_524 - doe / 146_096) / 365;
    let doy = doe - (365 * yoe + yoe / 4 - yoe / 100);
    let mp = (5 * doy + 2) / 153;
    let d = doy - (153 * mp + 2) / 5 + 1;
    let m = if mp < 10 { mp + 3 } else { mp - 9 };
    let y = yoe + era * 400 + (m <= 2) as i64;
    format!("{y:04}-{m:02}-{d:02}")
}
