//! `cogeo batch`: many scenes from one manifest, as one task per scene of a scheduler's job array
//! (a Slurm `--array`, a Kubernetes Indexed Job). `plan` validates every entry, `run` does one entry
//! end to end (train, tag, remove, eval) and can be run again at any point, `report` gathers all.
//!
//! A step is done when its marker `<out>/.batch/<step>.json` exists; the marker is written last,
//! atomically, so a task killed inside a step runs that step again (training from its last
//! checkpoint, `--resume`) and skips the steps before it. Exit status: 0 done, 65 permanent
//! failure (the entry or its inputs are wrong: retrying cannot help), 75 retryable failure (a step
//! failed: device lost, out of memory on this node, disk full, killed).

use super::manifest::{Manifest, Step};
use anyhow::{anyhow, bail, Context, Result};
use clap::{Args, Subcommand};
use serde_json::{json, Value};
use std::path::{Path, PathBuf};
use std::time::Instant;

#[derive(Args)]
pub struct BatchArgs {
    #[command(subcommand)]
    pub command: BatchCommand,
}

#[derive(Subcommand)]
pub enum BatchCommand {
    /// Validate every entry of a manifest (paths, labels, models, each step's options) and print
    /// the number of tasks; errors name the entry.
    Plan(PlanArgs),
    /// Run entry --index of a manifest end to end into `<output_root>/<name>/`, skipping finished
    /// steps and resuming training from its checkpoint. Exit status: 0 done, 65 permanent failure
    /// (bad input: do not retry), 75 retryable failure (requeue).
    Run(RunArgs),
    /// Gather every entry's metrics, timings and status into `<output_root>/report.json` and
    /// `report.md` (printed too).
    Report(ReportArgs),
}

#[derive(Args)]
pub struct PlanArgs {
    /// The manifest (JSON; schema in the README, "Processing many scenes").
    pub manifest: PathBuf,
    /// Print only the number of tasks (for `sbatch --array=0-$((N-1))`).
    #[arg(long)]
    pub count: bool,
}

#[derive(Args)]
pub struct RunArgs {
    /// The manifest.
    pub manifest: PathBuf,
    /// Entry to run, from 0. Default: SLURM_ARRAY_TASK_ID (Slurm job array), else
    /// JOB_COMPLETION_INDEX (Kubernetes Indexed Job).
    #[arg(long)]
    pub index: Option<usize>,
}

#[derive(Args)]
pub struct ReportArgs {
    /// The manifest.
    pub manifest: PathBuf,
}

/// How a failed `batch run` tells the scheduler what to do; the process exits with its code.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Exit {
    /// 65 (EX_DATAERR): the entry or its inputs are wrong; a retry fails the same way.
    Permanent,
    /// 75 (EX_TEMPFAIL): a step failed; a retry (a requeue) may succeed and resumes.
    Retryable,
}

impl Exit {
    pub fn code(self) -> i32 {
        match self {
            Exit::Permanent => 65,
            Exit::Retryable => 75,
        }
    }
}

impl std::fmt::Display for Exit {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Exit::Permanent => {
                write!(f, "permanent failure, exit 65 (fix the manifest or the inputs; a retry cannot help)")
            }
            Exit::Retryable => write!(f, "retryable failure, exit 75 (a rerun resumes)"),
        }
    }
}

pub fn run(a: BatchArgs, run_command: &dyn Fn(&[String]) -> Result<()>) -> Result<()> {
    match a.command {
        BatchCommand::Plan(p) => plan(&p),
        BatchCommand::Run(r) => run_entry(&r, run_command).map_err(|e| match e.downcast_ref::<Exit>() {
            Some(_) => e,
            None => e.context(Exit::Retryable),
        }),
        BatchCommand::Report(r) => report(&Manifest::load(&r.manifest)?),
    }
}

fn plan(p: &PlanArgs) -> Result<()> {
    let manifest = Manifest::load(&p.manifest)?;
    let mut problems = Vec::new();
    for (i, entry) in manifest.entries.iter().enumerate() {
        if let Err(e) = entry.validate(&manifest) {
            problems.push(format!("entry {i} ({:?}): {e:#}", entry.name));
        }
    }
    if !problems.is_empty() {
        for p in &problems[1..] {
            eprintln!("error: {p}");
        }
        bail!("{} of {} entries are invalid; first: {}", problems.len(), manifest.entries.len(), problems[0]);
    }
    if p.count {
        println!("{}", manifest.entries.len());
        return Ok(());
    }
    println!(
        "{}: {} task(s), outputs under {}",
        p.manifest.display(),
        manifest.entries.len(),
        manifest.output_root.display()
    );
    for (i, e) in manifest.entries.iter().enumerate() {
        let steps: Vec<&str> = e.steps().iter().map(|s| s.name()).collect();
        println!("  {i}: {} ({})", e.name, steps.join(", "));
    }
    println!(
        "Slurm: sbatch --array=0-{} deploy/slurm/cogeo-array.sbatch {}",
        manifest.entries.len() - 1,
        p.manifest.display()
    );
    Ok(())
}

/// The entry index: --index, else the scheduler's variable.
fn task_index(flag: Option<usize>) -> Result<usize> {
    if let Some(i) = flag {
        return Ok(i);
    }
    for var in ["SLURM_ARRAY_TASK_ID", "JOB_COMPLETION_INDEX"] {
        if let Ok(v) = std::env::var(var) {
            return v.trim().parse().map_err(|_| anyhow!("{var}={v:?} is not an entry index"));
        }
    }
    bail!("no entry index: give --index, or run inside a Slurm job array (SLURM_ARRAY_TASK_ID) or a Kubernetes Indexed Job (JOB_COMPLETION_INDEX)")
}

fn marker(out: &Path, step: Step) -> PathBuf {
    out.join(".batch").join(format!("{}.json", step.name()))
}

fn run_entry(r: &RunArgs, run_command: &dyn Fn(&[String]) -> Result<()>) -> Result<()> {
    let permanent = |e: anyhow::Error| e.context(Exit::Permanent);
    let manifest = Manifest::load(&r.manifest).map_err(permanent)?;
    let index = task_index(r.index).map_err(permanent)?;
    let entry = manifest.entries.get(index).ok_or_else(|| {
        permanent(anyhow!(
            "{}: entry {index} does not exist ({} entries)",
            r.manifest.display(),
            manifest.entries.len()
        ))
    })?;
    entry.validate(&manifest).with_context(|| format!("entry {index} ({:?})", entry.name)).map_err(permanent)?;
    let out = entry.out_dir(&manifest);
    std::fs::create_dir_all(out.join(".batch")).with_context(|| format!("{}: cannot create", out.display()))?;
    let restart = std::env::var("SLURM_RESTART_COUNT").ok().filter(|v| v != "0");
    eprintln!(
        "batch: entry {index} ({}) into {}{}",
        entry.name,
        out.display(),
        restart.map(|n| format!(" (restart {n})")).unwrap_or_default()
    );
    for step in entry.steps() {
        let done = marker(&out, step);
        if done.exists() {
            eprintln!("batch: skip {} (done: {})", step.name(), done.display());
            continue;
        }
        let args = entry.command_line(&manifest, step)?;
        eprintln!("batch: run {}: cogeo {}", step.name(), args.join(" "));
        let start = Instant::now();
        run_command(&args).with_context(|| format!("entry {index} ({:?}), step {}", entry.name, step.name()))?;
        let record = json!({
            "step": step.name(), "seconds": start.elapsed().as_secs_f64(),
            "peak_rss_mib": cogeo::io::peak_rss_mib(), "command": args,
            "finished_unix": std::time::SystemTime::now().duration_since(std::time::UNIX_EPOCH).map(|d| d.as_secs()).unwrap_or(0),
        });
        cogeo::io::write_atomic(&done, |w| serde_json::to_writer_pretty(&mut *w, &record).map_err(Into::into))?;
    }
    eprintln!("batch: entry {index} ({}) done", entry.name);
    Ok(())
}

fn read_json(path: &Path) -> Option<Value> {
    std::fs::read(path).ok().and_then(|b| serde_json::from_slice(&b).ok())
}

fn report(manifest: &Manifest) -> Result<()> {
    let mut rows = Vec::new();
    for e in &manifest.entries {
        let out = e.out_dir(manifest);
        let steps = e.steps();
        let markers: Vec<Option<Value>> = steps.iter().map(|&s| read_json(&marker(&out, s))).collect();
        let finished = markers.iter().filter(|m| m.is_some()).count();
        let status = match finished {
            n if n == steps.len() => "done".to_string(),
            0 => "not started".to_string(),
            n => format!("{n} of {} steps", steps.len()),
        };
        let train = read_json(&out.join("train/metrics.json")).unwrap_or(Value::Null);
        let removal = read_json(&out.join("removal/report.json")).unwrap_or(Value::Null);
        let eval = read_json(&out.join("eval.json")).unwrap_or(Value::Null);
        let seconds: serde_json::Map<String, Value> = steps
            .iter()
            .zip(&markers)
            .filter_map(|(s, m)| m.as_ref().map(|m| (s.name().to_string(), m["seconds"].clone())))
            .collect();
        let peak = markers
            .iter()
            .flatten()
            .filter_map(|m| m["peak_rss_mib"].as_f64())
            .fold(None, |a: Option<f64>, b| Some(a.map_or(b, |a| a.max(b))));
        rows.push(json!({
            "scene": e.name, "output": out, "status": status,
            "gaussians": train["gaussians"], "iterations": train["iterations"],
            "iterations_per_second": train["iterations_per_second"],
            "removed": removal["gaussians"]["removed"],
            "masked_psnr": eval["mask"]["psnr"], "masked_lpips": eval["lpips"]["mask"],
            "seconds": seconds, "peak_rss_mib": peak,
        }));
    }
    let num = |v: &Value, digits: usize| v.as_f64().map_or("-".to_string(), |x| format!("{x:.digits$}"));
    let mut md = String::from(
        "| scene | status | Gaussians | iterations | it/s | removed | masked PSNR | masked LPIPS | train s | tag s | remove s | eval s | peak RSS MiB |\n\
         |---|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|\n",
    );
    for r in &rows {
        let s = |k: &str| num(&r["seconds"][k], 1);
        md += &format!(
            "| {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} |\n",
            r["scene"].as_str().unwrap_or("?"),
            r["status"].as_str().unwrap_or("?"),
            num(&r["gaussians"], 0),
            num(&r["iterations"], 0),
            num(&r["iterations_per_second"], 2),
            num(&r["removed"], 0),
            num(&r["masked_psnr"], 2),
            num(&r["masked_lpips"], 3),
            s("train"),
            s("tag"),
            s("remove"),
            s("eval"),
            num(&r["peak_rss_mib"], 0)
        );
    }
    let root = &manifest.output_root;
    std::fs::create_dir_all(root).with_context(|| format!("{}: cannot create", root.display()))?;
    let batch = cogeo::io::OutputBatch::begin();
    let doc = json!({"manifest": manifest.path, "entries": rows});
    cogeo::io::write_atomic(&root.join("report.json"), |w| {
        serde_json::to_writer_pretty(&mut *w, &doc).map_err(Into::into)
    })?;
    cogeo::io::write_atomic(&root.join("report.md"), |w| {
        use std::io::Write;
        w.write_all(md.as_bytes()).map_err(Into::into)
    })?;
    batch.commit()?;
    print!("{md}");
    eprintln!("wrote {} and report.md", root.join("report.json").display());
    Ok(())
}
