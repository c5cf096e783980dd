//! Structure-aware fuzzing of every parser a user feeds, on stable Rust:
//! `cargo bench --bench fuzz -- --execs 1000000 [--families ply,colmap-bin] [--jobs 2]
//! [--bound-ms 2000] [--salt 1] [--out bench/results/fuzz.json]`.
//!
//! Each family runs in a child process (this binary with `--worker`), so an abort or a stack
//! overflow costs one input, not the run. Per input the child checks: no panic (caught and
//! reported), no hang (a watchdog thread ends the child when one input runs past --bound-ms), and no
//! single allocation above 16 MiB + 4096 x the input's size (a tracking global allocator; requests
//! above 1 GiB are refused, which aborts the child). The child writes the index of the input it is
//! on to a file before running it, and inputs are a pure function of (family, index, salt), so the
//! parent regenerates any input that killed a child. Panics and over-allocations are minimized
//! (chunks dropped while the finding persists) and written to target/fuzz-findings/; copy them to
//! tests/fuzz_cases/ to keep them as regression tests.

#[path = "common.rs"]
mod common;
#[path = "fuzz_seeds.rs"]
mod fuzz_seeds;
#[path = "fuzz_targets.rs"]
mod fuzz_targets;

use fuzz_targets::{allocation_bound, run_one, Family, Outcome, Seeds, FAMILIES};
use std::collections::HashMap;
use std::io::{BufRead, BufReader};
use std::os::unix::fs::FileExt;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, AtomicUsize, Ordering};
use std::time::Instant;

/// An error message with its numbers and quoted values blanked, so messages group by kind.
fn message_class(message: &str) -> String {
    let mut out = String::new();
    let mut quoted = false;
    for c in message.chars() {
        match c {
            '"' => {
                quoted = !quoted;
                if quoted {
                    out.push_str("\"_\"");
                }
            }
            _ if quoted => {}
            '0'..='9' => {
                if !out.ends_with('#') {
                    out.push('#')
                }
            }
            _ => out.push(c),
        }
    }
    out.chars().take(90).collect()
}

fn worker(args: &[String]) {
    let family = Family::from_name(&common::arg(args, "--worker").unwrap()).expect("family");
    let num = |name: &str| common::arg(args, name).unwrap().parse::<u64>().unwrap();
    let (from, to, salt, bound_ms) = (num("--from"), num("--to"), num("--salt"), num("--bound-ms"));
    let progress = std::fs::OpenOptions::new().write(true).open(common::arg(args, "--progress").unwrap()).unwrap();
    std::panic::set_hook(Box::new(|_| {}));
    let seeds = Seeds::new();
    let family_seeds = seeds.of(family);
    // watchdog: the start time (ms since `epoch`, +1) of the input being parsed, 0 when idle
    let epoch = Instant::now();
    static STARTED: AtomicU64 = AtomicU64::new(0);
    std::thread::spawn(move || loop {
        std::thread::sleep(std::time::Duration::from_millis(50));
        let started = STARTED.load(Ordering::Relaxed);
        if started != 0 && epoch.elapsed().as_millis() as u64 + 1 - started > bound_ms {
            eprintln!("hang: one input ran past {bound_ms} ms");
            std::process::exit(3);
        }
    });
    let (mut accepted, mut rejected) = (0u64, 0u64);
    let mut classes: HashMap<String, u64> = HashMap::new();
    for i in from..to {
        progress.write_at(&i.to_le_bytes(), 0).unwrap();
        let input = fuzz_targets::input(family, &family_seeds, i, salt);
        STARTED.store(epoch.elapsed().as_millis() as u64 + 1, Ordering::Relaxed);
        let (outcome, peak) = run_one(family, &input, &seeds);
        STARTED.store(0, Ordering::Relaxed);
        match outcome {
            Outcome::Accepted => accepted += 1,
            Outcome::Rejected(m) => {
                rejected += 1;
                *classes.entry(message_class(&m)).or_default() += 1;
            }
            Outcome::Panic(m) => println!("FINDING\tpanic\t{i}\t{}", m.replace(['\n', '\t'], " ")),
        }
        if peak > allocation_bound(input.len()) {
            println!("FINDING\tallocation\t{i}\t{peak} bytes in one allocation for a {}-byte input", input.len());
        }
        // cumulative counts now and then, so a child that dies later still reports them
        if (i - from) % 50_000 == 49_999 || i + 1 == to {
            let stats = serde_json::json!({"accepted": accepted, "rejected": rejected, "classes": classes});
            println!("STATS\t{stats}");
        }
    }
}

struct Finding {
    kind: String,
    index: u64,
    detail: String,
    file: PathBuf,
}

/// Drops chunks of `input` while `still` holds, halving the chunk size down to one byte.
fn minimize(mut input: Vec<u8>, still: impl Fn(&[u8]) -> bool) -> Vec<u8> {
    let mut chunk = input.len().div_ceil(2).max(1);
    loop {
        let mut at = 0;
        while at < input.len() {
            let mut trial = input.clone();
            trial.drain(at..(at + chunk).min(input.len()));
            if still(&trial) {
                input = trial;
            } else {
                at += chunk;
            }
        }
        if chunk == 1 {
            return input;
        }
        chunk = chunk.div_ceil(2);
    }
}

/// `--replay FAMILY FILE`: runs one input and tells the parent what it did through the exit
/// status (0 handled, 10 panic, 11 over-allocation; an abort ends it by a signal).
fn replay(args: &[String]) {
    let family = Family::from_name(&common::arg(args, "--replay").unwrap()).expect("family");
    let input = std::fs::read(common::arg(args, "--file").unwrap()).unwrap();
    std::panic::set_hook(Box::new(|_| {}));
    let seeds = Seeds::new();
    let (outcome, peak) = run_one(family, &input, &seeds);
    if matches!(outcome, Outcome::Panic(_)) {
        std::process::exit(10);
    }
    std::process::exit(if peak > allocation_bound(input.len()) { 11 } else { 0 });
}

/// Regenerates the input behind a finding, minimizes it (each trial in a child process, since a
/// trial may abort) and writes it to `dir`. Hangs are kept as found.
fn save_finding(family: Family, kind: &str, index: u64, salt: u64, seeds: &Seeds, dir: &Path) -> PathBuf {
    let input = fuzz_targets::input(family, &seeds.of(family), index, salt);
    std::fs::create_dir_all(dir).unwrap();
    let trial_file = dir.join(format!(".trial-{}-{}", family.name(), std::process::id()));
    let reproduces = |data: &[u8]| {
        std::fs::write(&trial_file, data).unwrap();
        let status = std::process::Command::new(std::env::current_exe().unwrap())
            .args(["--replay", family.name(), "--file"])
            .arg(&trial_file)
            .stderr(std::process::Stdio::null())
            .status()
            .unwrap();
        match kind {
            "panic" => status.code() == Some(10),
            "allocation" => status.code() == Some(11) || status.code().is_none(),
            "crash" => status.code().is_none(),
            _ => false,
        }
    };
    let input = if kind != "hang" && reproduces(&input) { minimize(input, reproduces) } else { input };
    let _ = std::fs::remove_file(&trial_file);
    let file = dir.join(format!("{}-{kind}-{index}.bin", family.name()));
    std::fs::write(&file, &input).unwrap();
    file
}

/// Runs one family's inputs [0, execs) in child processes, restarting after an input that killed one.
fn drive(family: Family, execs: u64, salt: u64, bound_ms: u64, seeds: &Seeds) -> serde_json::Value {
    let exe = std::env::current_exe().unwrap();
    let findings_dir = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("target/fuzz-findings");
    let progress = std::env::temp_dir().join(format!("cogeo-fuzz-{}-{}", family.name(), std::process::id()));
    let started = Instant::now();
    let mut findings: Vec<Finding> = Vec::new();
    let mut stats: Vec<serde_json::Value> = Vec::new();
    let mut from = 0;
    let mut children = 0;
    while from < execs {
        std::fs::write(&progress, from.to_le_bytes()).unwrap();
        let mut child = std::process::Command::new(&exe)
            .args(["--worker", family.name(), "--from", &from.to_string(), "--to", &execs.to_string()])
            .args(["--salt", &salt.to_string(), "--bound-ms", &bound_ms.to_string()])
            .arg("--progress")
            .arg(&progress)
            .stdout(std::process::Stdio::piped())
            .stderr(std::process::Stdio::null())
            .spawn()
            .unwrap();
        children += 1;
        let mut last_stats = None;
        for line in BufReader::new(child.stdout.take().unwrap()).lines() {
            let line = line.unwrap();
            let parts: Vec<&str> = line.splitn(4, '\t').collect();
            match parts.as_slice() {
                ["FINDING", kind, index, detail] => {
                    let index: u64 = index.parse().unwrap();
                    let file = save_finding(family, kind, index, salt, seeds, &findings_dir);
                    eprintln!("  {}: {kind} at input {index}: {detail} ({})", family.name(), file.display());
                    findings.push(Finding { kind: kind.to_string(), index, detail: detail.to_string(), file });
                }
                ["STATS", json] => last_stats = Some(serde_json::from_str::<serde_json::Value>(json).unwrap()),
                _ => {}
            }
        }
        let status = child.wait().unwrap();
        stats.extend(last_stats);
        if status.success() {
            break;
        }
        // the input this child was on killed it (or hung): keep it, go on after it
        let index = u64::from_le_bytes(std::fs::read(&progress).unwrap()[..8].try_into().unwrap());
        let kind = if status.code() == Some(3) { "hang" } else { "crash" };
        let file = save_finding(family, kind, index, salt, seeds, &findings_dir);
        eprintln!("  {}: {kind} at input {index} ({status}; {})", family.name(), file.display());
        findings.push(Finding { kind: kind.into(), index, detail: status.to_string(), file });
        from = index + 1;
    }
    let _ = std::fs::remove_file(&progress);
    let seconds = started.elapsed().as_secs_f64();
    let count = |k: &str| findings.iter().filter(|f| f.kind == k).count();
    let sum = |key: &str| stats.iter().map(|s| s[key].as_u64().unwrap_or(0)).sum::<u64>();
    let mut classes: HashMap<String, u64> = HashMap::new();
    for s in &stats {
        for (class, n) in s["classes"].as_object().into_iter().flatten() {
            *classes.entry(class.clone()).or_default() += n.as_u64().unwrap_or(0);
        }
    }
    let mut top: Vec<(String, u64)> = classes.into_iter().collect();
    top.sort_by(|a, b| b.1.cmp(&a.1).then(a.0.cmp(&b.0)));
    serde_json::json!({
        "family": family.name(), "execs": execs, "seconds": seconds, "execs_per_s": execs as f64 / seconds,
        "seeds": seeds.of(family).len(), "children": children,
        "accepted": sum("accepted"), "rejected": sum("rejected"),
        "panics": count("panic"), "hangs": count("hang"), "crashes": count("crash"), "over_allocations": count("allocation"),
        "findings": findings.iter().map(|f| serde_json::json!({"kind": f.kind, "index": f.index, "detail": f.detail,
            "file": f.file.display().to_string()})).collect::<Vec<_>>(),
        "error_kinds": top.len(),
        "top_errors": top.iter().take(15).map(|(c, n)| serde_json::json!([c, n])).collect::<Vec<_>>(),
    })
}

fn main() {
    let args = common::args();
    if common::arg(&args, "--worker").is_some() {
        return worker(&args);
    }
    if common::arg(&args, "--replay").is_some() {
        return replay(&args);
    }
    let execs: u64 = common::arg(&args, "--execs").map_or(100_000, |v| v.parse().expect("--execs N"));
    let salt: u64 = common::arg(&args, "--salt").map_or(1, |v| v.parse().expect("--salt N"));
    let bound_ms: u64 = common::arg(&args, "--bound-ms").map_or(2000, |v| v.parse().expect("--bound-ms N"));
    let jobs: usize = common::arg(&args, "--jobs").map_or(2, |v| v.parse().expect("--jobs N"));
    let families: Vec<Family> = match common::arg(&args, "--families") {
        Some(list) => {
            list.split(',').map(|n| Family::from_name(n).unwrap_or_else(|| panic!("unknown family {n}"))).collect()
        }
        None => FAMILIES.to_vec(),
    };
    let out = common::arg(&args, "--out").map(PathBuf::from).unwrap_or_else(|| common::results_path("fuzz.json"));
    eprintln!(
        "fuzzing {} families, {execs} inputs each, {jobs} at a time (salt {salt}, bound {bound_ms} ms)",
        families.len()
    );
    let seeds = Seeds::new();
    let next = AtomicUsize::new(0);
    let results = std::sync::Mutex::new(Vec::new());
    std::thread::scope(|s| {
        for _ in 0..jobs.max(1) {
            s.spawn(|| loop {
                let k = next.fetch_add(1, Ordering::Relaxed);
                let Some(&family) = families.get(k) else { break };
                let r = drive(family, execs, salt, bound_ms, &seeds);
                eprintln!("{}: {} inputs in {:.0} s", family.name(), execs, r["seconds"].as_f64().unwrap());
                results.lock().unwrap().push(r);
            });
        }
    });
    let mut results = results.into_inner().unwrap();
    results.sort_by_key(|r| families.iter().position(|f| f.name() == r["family"].as_str().unwrap()));
    let mut table = common::Table::new(
        "fuzz",
        &args,
        "",
        None,
        "| family | seeds | inputs | inputs/s | accepted | rejected | error kinds | panics | hangs | crashes | over-allocations |",
        "|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|",
    );
    for r in &results {
        table.line(format!(
            "| {} | {} | {} | {:.0} | {} | {} | {} | {} | {} | {} | {} |",
            r["family"].as_str().unwrap(),
            r["seeds"],
            r["execs"],
            r["execs_per_s"].as_f64().unwrap(),
            r["accepted"],
            r["rejected"],
            r["error_kinds"],
            r["panics"],
            r["hangs"],
            r["crashes"],
            r["over_allocations"]
        ));
    }
    common::update_results(&args, "fuzz", &table.md);
    let json = serde_json::json!({"execs_per_family": execs, "salt": salt, "bound_ms": bound_ms,
        "allocation_bound": "16 MiB + 4096 x input bytes per allocation", "families": results});
    std::fs::write(&out, serde_json::to_string_pretty(&json).unwrap() + "\n").unwrap();
    eprintln!("wrote {}", out.display());
}
