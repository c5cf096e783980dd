//! Training settings: the one home of their defaults, which are also `cogeo train`'s flags
//! (crate::config). INRIA's schedule is for 30,000 iterations; `fit_schedule_to_iters` shortens
//! it for short runs.

use crate::flag_values::parse_rgb;

#[derive(Clone, Debug, serde::Serialize, serde::Deserialize, clap::Args)]
#[serde(default)]
pub struct TrainConfig {
    /// Training iterations.
    #[arg(long, default_value_t = 30_000)]
    pub iters: u32,
    /// Highest SH degree (one more band every --sh-band-every iterations).
    #[arg(long, default_value_t = 3)]
    pub sh_degree: u32,
    /// Iterations between SH band increases: bands 1, 2, 3 (view-dependent color) start training
    /// at this many iterations, twice and three times as many (INRIA's 1000). A shorter run
    /// learns no view-dependent color at all: the cup composite's 800 iterations score 26.52 dB
    /// held out at 1000, 27.14 at 200 (bench/JOURNAL.md, 2026-11-30, 05:52).
    #[arg(long, default_value_t = 1000, value_parser = clap::value_parser!(u32).range(1..))]
    pub sh_band_every: u32,
    /// Disable densification (no clone / split / prune / opacity reset, no MCMC relocation).
    #[arg(id = "no-densify", long = "no-densify", action = clap::ArgAction::SetFalse)]
    pub densify: bool,
    /// First densification iteration (INRIA's).
    #[arg(skip = 500u32)]
    pub densify_from: u32,
    /// Last densification iteration (INRIA's).
    #[arg(skip = 15_000u32)]
    pub densify_until: u32,
    #[arg(skip = 100u32)]
    pub densify_interval: u32,
    /// Mean view-space positional gradient (NDC units) above which Gaussians are cloned or split.
    #[arg(skip = 2e-4)]
    pub grad_threshold: f32,
    /// INRIA's fixed interval: short runs end densification before any reset, which suits them
    /// (a reset needs thousands of iterations to recover).
    #[arg(skip = 3000u32)]
    pub opacity_reset_interval: u32,
    /// Gaussian budget: adc never grows past it; mcmc grows to it.
    #[arg(long, default_value_t = 3_000_000)]
    pub max_gaussians: usize,
    /// Densification strategy: adc = INRIA adaptive density control (clone / split / prune, opacity
    /// reset); mcmc = 3DGS-MCMC (relocate transparent Gaussians onto opaque ones, grow by 5 % every
    /// 100 iterations up to --max-gaussians, opacity/scale regularizers and position noise).
    #[arg(long, value_enum, default_value_t)]
    pub strategy: Strategy,
    /// Random seed (view order, splits).
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
    /// Background color r,g,b in [0, 1] behind the Gaussians.
    #[arg(long, default_value = crate::flag_values::DEFAULT_BACKGROUND, value_parser = parse_rgb)]
    pub background: [f32; 3],
    /// Multiplies the SH learning rates (1: INRIA's). The removal's short refinement raises it:
    /// Adam moves a coefficient by about its learning rate per step, so the INRIA rate needs
    /// hundreds of steps to recolor a Gaussian.
    #[arg(skip = 1.0)]
    pub color_lr_gain: f32,
    /// Multiplies the scale and rotation learning rates (1: INRIA's); the removal's refinement
    /// raises it for the same reason as `color_lr_gain`.
    #[arg(skip = 1.0)]
    pub shape_lr_gain: f32,
    /// Learn a per-view affine color map (per-channel gain and bias, or --exposure-model, train/exposure.rs) applied to the
    /// render before each training view's loss, for captures whose exposure or white balance
    /// changes from shot to shot (phones). At the end the maps' common part moves into the scene,
    /// which then shows the views' mean exposure; each view's own part never does. Written to
    /// exposure.json, for `cogeo remove --exposure`.
    #[arg(long)]
    pub exposure: bool,
    /// What each view's exposure map may change: gain-bias (per-channel gain and bias) or affine
    /// (a 3x3 color matrix and bias).
    #[arg(long, value_enum, default_value_t, requires = "exposure")]
    pub exposure_model: super::exposure::ExposureModel,
    /// Adam learning rate of the exposure maps at the start; it decays exponentially to a tenth
    /// by the last iteration.
    #[arg(long, default_value_t = 0.02, requires = "exposure")]
    pub exposure_lr: f32,
    /// Weight of the pull of every exposure map toward identity (|A - I|^2 + |b|^2 added to the
    /// loss), which keeps a view's map from absorbing what its photo shows of the scene.
    #[arg(long, default_value_t = 0.001, requires = "exposure")]
    pub exposure_reg: f32,
}

crate::default_from_flags!(TrainConfig);

impl TrainConfig {
    /// A run shorter than INRIA's densifies from a tenth of its iterations at the latest and
    /// until half of them at the latest.
    pub fn fit_schedule_to_iters(&mut self) {
        self.densify_from = self.densify_from.min(self.iters / 10);
        self.densify_until = self.densify_until.min(self.iters / 2);
    }
}

/// How the set of Gaussians changes during training.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize, serde::Deserialize, clap::ValueEnum)]
pub enum Strategy {
    /// INRIA adaptive density control: clone / split / prune and periodic opacity reset.
    #[default]
    Adc,
    /// 3DGS-MCMC: dead Gaussians relocated onto live ones, growth by 5 % up to the budget, opacity
    /// and scale regularizers, position noise (train/mcmc.rs).
    Mcmc,
}

/// Which parameter groups are frozen (no update).
#[derive(Clone, Copy, Debug, Default, serde::Serialize, serde::Deserialize)]
pub struct Frozen {
    pub means: bool,
    pub log_scales: bool,
    pub quats: bool,
    pub opacity: bool,
    pub sh: bool,
}

impl Frozen {
    /// Geometry (means, scales, rotations) frozen; color and opacity train.
    pub fn geometry() -> Frozen {
        Frozen { means: true, log_scales: true, quats: true, ..Default::default() }
    }
}

/// How one Gaussian may step (`Trainer::set_movable`); the values are the shader's
/// (project_backward_adam.comp).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[repr(u32)]
pub enum Motion {
    /// Neither its parameters nor its moments change.
    Held = 0,
    /// Every parameter steps.
    Free = 1,
    /// Every parameter steps but the SH bands above the first, which keep their values: its
    /// color is the same from every direction unless it had view dependence already.
    ViewIndependent = 2,
}
