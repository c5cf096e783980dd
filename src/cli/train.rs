//! `cogeo train`: a Gaussian scene from a COLMAP capture, with checkpoints and resume.

use super::args::{open_gpu, CaptureArgs, DeviceArgs};
use anyhow::{bail, Context, Result};
use clap::Args;
use cogeo::scene::ply;
use indicatif::{ProgressBar, ProgressStyle};
use std::io::IsTerminal;
use std::path::PathBuf;

#[derive(Args)]
pub struct TrainArgs {
    /// Dataset folder: COLMAP model (here or in sparse/0) or nerfstudio / instant-ngp transforms.json,
    /// and an image folder.
    #[arg(long)]
    pub data: PathBuf,
    /// Output folder: scene.ply, metrics.json, checkpoint/ and, with --exposure, exposure.json
    /// (created if missing).
    #[arg(long)]
    pub out: PathBuf,
    #[command(flatten)]
    pub capture: CaptureArgs,
    /// Continue from the last checkpoint in --out (starts fresh when there is none).
    #[arg(long)]
    pub resume: bool,
    /// Write a checkpoint every this many iterations (0 = only at the end).
    #[arg(long, default_value_t = 1000)]
    pub checkpoint_every: u32,
    /// Densify until this iteration (INRIA: 15000; by default half the iterations for short runs).
    #[arg(long)]
    pub densify_until: Option<u32>,
    #[command(flatten)]
    pub config: cogeo::train::trainer::TrainConfig,
    #[command(flatten)]
    pub device: DeviceArgs,
}

pub fn run(a: TrainArgs) -> Result<()> {
    use cogeo::scene::dataset;
    use cogeo::train::{checkpoint, trainer};
    let iters = a.config.iters;
    if iters == 0 {
        bail!("--iters must be positive");
    }
    if a.config.sh_degree > cogeo::scene::MAX_SH_DEGREE {
        bail!("--sh-degree must be 0..{}", cogeo::scene::MAX_SH_DEGREE);
    }
    let data = dataset::load(&a.data, &a.capture.images, a.capture.downscale)?;
    for w in &data.warnings {
        eprintln!("warning: {w}");
    }
    let gpu = open_gpu(&a.device)?;
    let mut cfg = a.config.clone();
    cfg.fit_schedule_to_iters();
    if let Some(until) = a.densify_until {
        cfg.densify_until = until;
    }
    let resumed = if a.resume { checkpoint::load(&a.out)? } else { None };
    if a.resume && resumed.is_none() {
        eprintln!("no checkpoint in {}; starting from the sparse points", a.out.display());
    }
    let scene = match &resumed {
        Some(c) => c.scene.clone(),
        None => trainer::init_from_points(&data.points, a.config.sh_degree)?,
    };
    let mut t = trainer::Trainer::new(&gpu, &data, &scene, cfg)?;
    // the folder appears once the inputs are read and the device memory is taken
    std::fs::create_dir_all(&a.out).with_context(|| format!("{}: cannot create output folder", a.out.display()))?;
    if let Some(c) = &resumed {
        t.set_step(c.step);
        t.load_moments(&c.moments)?;
        if let Some(e) = c.exposures.as_ref().filter(|_| a.config.exposure) {
            t.resume_exposures(e)?;
        }
        eprintln!("resumed at iteration {} with {} Gaussians", c.step, scene.len());
    }
    eprintln!(
        "training {} views ({} held out), {} Gaussians, extent {:.2}, on {}",
        data.train.len(),
        data.test.len(),
        t.num_gaussians(),
        data.extent,
        gpu.info().name
    );
    let bar = ProgressBar::new(iters as u64);
    bar.set_style(
        ProgressStyle::with_template("train [{bar:30}] {pos}/{len} {elapsed_precise} eta {eta} {msg}")
            .unwrap()
            .progress_chars("=> "),
    );
    bar.set_position(t.step as u64);
    let start = std::time::Instant::now();
    let first_step = t.step;
    let mut test_psnr = None;
    // Without a terminal (a pipe, a log file, CI) the bar draws nothing: print a plain line about
    // every 5 % of the run instead, on the steps that read the loss back anyway.
    let plain_every = (!std::io::stderr().is_terminal()).then(|| (iters / 20 / 50).max(1) * 50);
    while t.step < iters {
        let log = (t.step + 1) % 50 == 0;
        t.iterate(&data, log)?;
        if a.checkpoint_every > 0 && t.step % a.checkpoint_every == 0 && t.step < iters {
            checkpoint::save(&t, &a.out)?;
            test_psnr = Some(t.evaluate(&data.test)?.psnr);
        }
        if let Some((loss, l1)) = t.last_loss.filter(|_| log) {
            let psnr = test_psnr.map(|p| format!(" test PSNR {p:.2}")).unwrap_or_default();
            let msg = format!("loss {loss:.4} L1 {l1:.4}{psnr} | {} Gaussians", t.num_gaussians());
            if plain_every.is_some_and(|n| t.step % n == 0) {
                eprintln!("train {}/{} {:.0} s {msg}", t.step, iters, start.elapsed().as_secs_f64());
            }
            bar.set_message(msg);
        }
        bar.set_position(t.step as u64);
    }
    bar.finish();
    let seconds = start.elapsed().as_secs_f64();
    t.settle_exposure_gauge()?;
    let scene = t.download_scene()?;
    checkpoint::save(&t, &a.out)?;
    let test = t.evaluate(&data.test)?;
    let train = t.evaluate(&data.train)?;
    let report = serde_json::json!({
        "iterations": t.step,
        "gaussians": scene.len(),
        "seconds": seconds,
        "iterations_per_second": (t.step - first_step) as f64 / seconds.max(1e-9),
        "test": test,
        "train": train,
        "device": gpu.info().name,
    });
    let text = serde_json::to_string_pretty(&report)?;
    let batch = cogeo::io::OutputBatch::begin();
    ply::write_ply(&scene, &a.out.join("scene.ply"))?;
    if let Some(e) = t.exposure_file()? {
        e.write(&a.out.join("exposure.json"))?;
    }
    cogeo::io::write_atomic(&a.out.join("metrics.json"), |w| {
        use std::io::Write;
        w.write_all(text.as_bytes()).map_err(Into::into)
    })?;
    batch.commit()?;
    eprintln!(
        "done: {} Gaussians; test PSNR {:.2} dB SSIM {:.4} ({} views; {:.2} dB with each view's exposure fitted); train PSNR {:.2}; {:.1} it/s; wrote {}",
        scene.len(),
        test.psnr,
        test.ssim,
        test.views,
        test.psnr_exposure_fitted,
        train.psnr,
        (t.step - first_step) as f64 / seconds.max(1e-9),
        a.out.join("scene.ply").display()
    );
    Ok(())
}
