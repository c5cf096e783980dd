//! The `cogeo` command line: one module per subcommand, each holding its clap arguments and its
//! `run`; shared argument groups in `args`.

pub mod args;
pub mod batch;
pub mod demo;
pub mod devices;
pub mod eval;
pub mod manifest;
pub mod remove;
pub mod render;
pub mod run;
pub mod synth;
pub mod tag;
pub mod train;

use anyhow::{anyhow, Result};
use clap::{Parser, Subcommand};

#[derive(Parser)]
#[command(
    name = "cogeo",
    version,
    about = "Vulkan-native 3D Gaussian Splatting: render, train, tag and remove objects"
)]
pub struct Cli {
    #[command(subcommand)]
    pub command: Command,
}

#[derive(Subcommand)]
pub enum Command {
    /// List Vulkan devices with the limits cogeo cares about.
    Devices,
    /// Render a Gaussian scene (INRIA PLY) from a set of cameras to PNG (and EXR depth).
    Render(render::RenderArgs),
    /// The main job on built-in data: generate a synthetic multi-object scene, train, tag, remove
    /// 2+ objects, evaluate against the exact ground truth; writes image strips, a contact sheet,
    /// metrics.json and report.md.
    Demo(demo::DemoArgs),
    /// Generate a procedural dataset with exact ground truth for training and removal.
    Synth(synth::SynthArgs),
    /// Train a Gaussian scene from a COLMAP capture (sparse model + images).
    Train(train::TrainArgs),
    /// Give every Gaussian an object label from per-view masks (identity features, voting, or the
    /// 2D-projection baseline); writes the tagged PLY and a JSON sidecar.
    Tag(tag::TagArgs),
    /// Remove the objects of chosen labels from a tagged scene and complete the background behind
    /// them (hole masks, inpainting, depth completion, fusion, pruning, refinement).
    Remove(remove::RemoveArgs),
    /// The whole path from a capture: train, tag, remove, in one command.
    Run(run::RunArgs),
    /// Score renders against ground-truth images inside masks (PSNR/SSIM on the mask, its bounding
    /// box and the full image; with a synth dataset also never-seen / seen-elsewhere subsets,
    /// leftover, depth error and floaters; LPIPS and FID through user-supplied ONNX models).
    Eval(eval::EvalArgs),
    /// Many scenes from one manifest, one scheduler task per scene (Slurm job array, Kubernetes
    /// Indexed Job): `plan` validates, `run --index I` does entry I end to end and resumes after a
    /// kill, `report` gathers metrics and timings.
    Batch(batch::BatchArgs),
}

/// Runs a cogeo subcommand from its command line, as a user would type it.
pub fn run_command(args: &[String]) -> Result<()> {
    let cli = Cli::try_parse_from(std::iter::once("cogeo".to_string()).chain(args.iter().cloned()))
        .map_err(|e| anyhow!("internal command line {args:?}: {e}"))?;
    dispatch(cli.command)
}

pub fn dispatch(command: Command) -> Result<()> {
    match command {
        Command::Devices => devices::run(),
        Command::Render(a) => render::run(a),
        Command::Demo(a) => demo::run(a, &run_command),
        Command::Synth(a) => synth::run(a),
        Command::Train(a) => train::run(a),
        Command::Tag(a) => tag::run(a),
        Command::Remove(a) => remove::run(a),
        Command::Run(a) => run::run(a),
        Command::Eval(a) => eval::run(a),
        Command::Batch(a) => batch::run(a, &run_command),
    }
}

#[cfg(test)]
mod tests {
    use clap::CommandFactory;

    /// Flags flattened in from the library's config structs must not share an id with another
    /// flag of the same command: clap would merge them silently in a release build.
    #[test]
    fn every_subcommand_has_distinct_flag_ids_and_longs() {
        let cli = super::Cli::command();
        for sub in cli.get_subcommands() {
            let mut ids: Vec<&str> = sub.get_arguments().map(|a| a.get_id().as_str()).collect();
            let mut longs: Vec<&str> = sub.get_arguments().filter_map(|a| a.get_long()).collect();
            for v in [&mut ids, &mut longs] {
                let n = v.len();
                v.sort();
                v.dedup();
                assert_eq!(v.len(), n, "`cogeo {}` has a flag id or name twice: {v:?}", sub.get_name());
            }
        }
        cli.debug_assert();
    }

    /// `run` and `demo` hand the device flags on to their steps as they were given.
    #[test]
    fn device_flags_pass_on_as_given() {
        use clap::Parser;
        let device = |extra: &[&str]| {
            let args = [&["cogeo", "train", "--data", "d", "--out", "o"], extra].concat();
            match super::Cli::try_parse_from(args).unwrap().command {
                super::Command::Train(t) => t.device.command_line(),
                _ => unreachable!(),
            }
        };
        let given = ["--device", "llvmpipe", "--max-device-memory", "512.5"];
        assert_eq!(device(&given), given);
        assert!(device(&[]).is_empty());
    }
}
