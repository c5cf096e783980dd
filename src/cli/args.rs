//! Argument groups and helpers shared by several subcommands: the device, the capture's
//! resolution, colors, progress bars, scene loading.

use anyhow::{Context, Result};
use clap::Args;
use cogeo::gpu::{DeviceChoice, Gpu};
use cogeo::scene::{ply, GaussianScene};
use indicatif::{ProgressBar, ProgressStyle};
use std::path::Path;

#[derive(Args, Clone)]
pub struct DeviceArgs {
    /// Vulkan device to use: index or case-insensitive name substring (see `cogeo devices`).
    /// Default: COGEO_DEVICE, else the first discrete GPU, then integrated, then CPU (lavapipe).
    #[arg(long, global = true)]
    pub device: Option<String>,
    /// Use at most this many MiB of device memory (for a GPU shared with other jobs); work that
    /// needs more stops with the sizes and the device named. Default: COGEO_MAX_DEVICE_MEMORY_MIB,
    /// else all of the device's local memory.
    #[arg(long, global = true, value_name = "MIB")]
    pub max_device_memory: Option<f64>,
}

/// Which images of a capture are used and at what resolution (train, tag, remove and run share it).
#[derive(Args, Clone)]
pub struct CaptureArgs {
    /// Image folder inside --data (e.g. images_2, images_4 for downscaled copies; intrinsics are
    /// scaled, masks are resized to its images).
    #[arg(long, default_value = cogeo::scene::dataset::DEFAULT_IMAGE_FOLDER)]
    pub images: String,
    /// Box-filter every image by N x N pixels on load (intrinsics follow; masks are resized to the
    /// result): train, tag and edit a capture at 1/N resolution without writing a copy. Use the same
    /// value for train, tag and remove.
    #[arg(long, default_value_t = 1, value_parser = clap::value_parser!(u32).range(1..=16))]
    pub downscale: u32,
}

impl DeviceArgs {
    /// These flags as they were given, for a step that runs another cogeo command line.
    pub fn command_line(&self) -> Vec<String> {
        let mut v = Vec::new();
        if let Some(d) = &self.device {
            v.extend(["--device".to_string(), d.clone()]);
        }
        if let Some(m) = self.max_device_memory {
            v.extend(["--max-device-memory".to_string(), m.to_string()]);
        }
        v
    }
}

pub use cogeo::flag_values::parse_rgb;

/// Seconds between the plain lines of one long stage without a terminal (`StageProgress`).
const PLAIN_EVERY_SECONDS: f64 = 10.0;

/// Progress through a run of named stages (`remove`'s, `synth --composite-into`'s): one bar showing
/// each stage's name and its items done. Without a terminal (a pipe, a log file, a batch job) the
/// bar draws nothing, so a plain line is printed instead when a stage starts and about every
/// `PLAIN_EVERY_SECONDS` within one (a removal on a large capture spends minutes in one stage).
pub struct StageProgress {
    bar: ProgressBar,
    /// The command's name, each plain line's first word; None on a terminal.
    plain: Option<&'static str>,
    start: std::time::Instant,
    /// The stage of the last plain line and when it was printed (a cell: `synth`'s callback is a
    /// `Fn`).
    last: std::cell::RefCell<Option<(String, f64)>>,
}

impl StageProgress {
    pub fn new(command: &'static str) -> StageProgress {
        use std::io::IsTerminal;
        let bar = ProgressBar::new(0);
        bar.set_style(
            ProgressStyle::with_template("{msg:>9} [{bar:30}] {pos}/{len} {elapsed_precise}")
                .unwrap()
                .progress_chars("=> "),
        );
        let plain = (!std::io::stderr().is_terminal()).then_some(command);
        StageProgress { bar, plain, start: std::time::Instant::now(), last: Default::default() }
    }

    /// `done` of `total` items of `stage`.
    pub fn set(&self, stage: &str, done: usize, total: usize) {
        self.bar.set_message(stage.to_string());
        self.bar.set_length(total as u64);
        self.bar.set_position(done as u64);
        let Some(command) = self.plain else { return };
        let now = self.start.elapsed().as_secs_f64();
        let mut last = self.last.borrow_mut();
        let due = match &*last {
            Some((shown, at)) => shown != stage || now - at >= PLAIN_EVERY_SECONDS,
            None => true,
        };
        if due {
            eprintln!("{command}: {stage} {done}/{total} at {now:.1} s");
            *last = Some((stage.to_string(), now));
        }
    }

    pub fn finish(self) {
        self.bar.finish_and_clear();
    }
}

pub fn progress(len: usize, what: &str) -> ProgressBar {
    let bar = ProgressBar::new(len as u64);
    bar.set_style(
        ProgressStyle::with_template("{msg:>10} [{bar:40}] {pos}/{len} {elapsed_precise} eta {eta}")
            .unwrap()
            .progress_chars("=> "),
    );
    bar.set_message(what.to_string());
    bar
}

pub fn open_gpu(device: &DeviceArgs) -> Result<Gpu> {
    let mut choice = DeviceChoice::from_env(device.device.clone());
    choice.memory_limit_mib = device.max_device_memory.or(choice.memory_limit_mib);
    Gpu::new(&choice)
}

/// Creates an output folder early (so a folder that cannot be made fails before the work), and
/// removes it again if the command ends while it is still empty (a failure before any output), so
/// that a failed run leaves no folder behind. Keep the guard alive for the whole command.
pub struct OutputFolder {
    path: Option<std::path::PathBuf>,
}

impl OutputFolder {
    pub fn create(path: &Path) -> Result<OutputFolder> {
        let created = !path.exists();
        std::fs::create_dir_all(path).with_context(|| format!("{}: cannot create output folder", path.display()))?;
        Ok(OutputFolder { path: created.then(|| path.to_path_buf()) })
    }
}

impl Drop for OutputFolder {
    fn drop(&mut self) {
        if let Some(p) = &self.path {
            let _ = std::fs::remove_dir(p); // only succeeds while empty
        }
    }
}

pub fn load_scene(path: &Path) -> Result<GaussianScene> {
    let scene = ply::read_ply(path)?;
    scene.validate(&path.display().to_string())?;
    Ok(scene)
}
