//! The path from a capture to a scored removal, train -> tag -> remove -> eval, as the `cogeo`
//! command lines that run each step. `cogeo run`, `cogeo demo`, `cogeo batch` and the removal
//! bench all take their steps from here, so the order of the stages, the folders they hand on and
//! the short training recipe of synthetic scenes are written once. Each function returns a whole
//! command line (the subcommand first); callers append their own flags.

use std::path::Path;

fn path(p: &Path) -> String {
    p.to_string_lossy().into_owned()
}

fn strings(v: &[&str]) -> Vec<String> {
    v.iter().map(|x| x.to_string()).collect()
}

/// A capture as the steps read it: the dataset folder, and optionally its image folder and the
/// downscale factor (each command's own default when None).
#[derive(Clone, Debug)]
pub struct Capture<'a> {
    pub data: &'a Path,
    pub images: Option<&'a str>,
    pub downscale: Option<u32>,
}

impl<'a> Capture<'a> {
    /// The dataset folder with the commands' default image folder and resolution.
    pub fn at(data: &'a Path) -> Capture<'a> {
        Capture { data, images: None, downscale: None }
    }

    fn args(&self) -> Vec<String> {
        let mut v = vec!["--data".to_string(), path(self.data)];
        if let Some(images) = self.images {
            v.extend(["--images".to_string(), images.to_string()]);
        }
        if let Some(n) = self.downscale {
            v.extend(["--downscale".to_string(), n.to_string()]);
        }
        v
    }
}

/// How the objects are named: label maps (a mask folder), or text prompts.
#[derive(Clone, Copy, Debug)]
pub enum Objects<'a> {
    Masks(&'a str),
    Prompts(&'a [String]),
}

/// Which objects to remove: labels, or names from the tagging sidecar.
#[derive(Clone, Copy, Debug)]
pub enum Chosen<'a> {
    Labels(&'a str),
    Names(&'a [String]),
}

/// The folder layout of one removal run under `out`: `train/`, `tagged.ply`, `removal/`.
pub struct Layout<'a> {
    pub out: &'a Path,
}

impl Layout<'_> {
    pub fn train(&self) -> std::path::PathBuf {
        self.out.join("train")
    }
    /// The training views' exposure maps of `cogeo train --exposure`.
    pub fn exposure(&self) -> std::path::PathBuf {
        self.train().join("exposure.json")
    }
    pub fn trained_scene(&self) -> std::path::PathBuf {
        self.out.join("train/scene.ply")
    }
    pub fn tagged(&self) -> std::path::PathBuf {
        self.out.join("tagged.ply")
    }
    pub fn removal(&self) -> std::path::PathBuf {
        self.out.join("removal")
    }
}

/// `cogeo train` of `capture` into `out`.
pub fn train(capture: &Capture, out: &Path) -> Vec<String> {
    let mut v = vec!["train".to_string()];
    v.extend(capture.args());
    v.extend(["--out".to_string(), path(out)]);
    v
}

/// The training recipe of the synthetic rooms (the demo and the removal bench): `iters`
/// iterations, SH degree 1, no densification, no intermediate checkpoints. Their sparse points
/// already cover every surface, and the short runs end before densification would pay off.
pub fn synth_training(iters: u32, seed: u64) -> Vec<String> {
    let mut v = strings(&["--iters", &iters.to_string(), "--sh-degree", "1", "--checkpoint-every", "0"]);
    v.extend(strings(&["--seed", &seed.to_string(), "--no-densify"]));
    v
}

/// The training recipe of a real capture (the real bench's captures and their composites):
/// `iters` iterations with the defaults' densification up to 200k Gaussians and SH degree, one
/// more SH band every `capture_sh_band_every(iters)` iterations, no intermediate checkpoints;
/// `seed` when given. A composite trained with the synth rooms' recipe (SH degree 1, no
/// densification) from the capture's 9k structure-from-motion points could not grow into the
/// desk's grain.
pub fn capture_training(iters: &str, seed: Option<u64>) -> Vec<String> {
    let every = capture_sh_band_every(iters.parse().expect("the iterations are a number")).to_string();
    let mut v = strings(&["--iters", iters, "--max-gaussians", "200000", "--checkpoint-every", "0"]);
    v.extend(strings(&["--sh-band-every", &every]));
    if let Some(seed) = seed {
        v.extend(strings(&["--seed", &seed.to_string()]));
    }
    v
}

/// The SH band interval of `capture_training`: a quarter of the run, at most INRIA's 1000, so that
/// the last band trains for the last quarter. A user's capture trains 30,000 iterations and
/// learns view-dependent color; at INRIA's interval the bench's 800-iteration runs learnt none,
/// and a removal on them never met it (bench/JOURNAL.md, 2026-11-30, 05:52).
pub fn capture_sh_band_every(iters: u32) -> u32 {
    (iters / 4).clamp(1, crate::train::config::TrainConfig::default().sh_band_every)
}

/// `cogeo tag` of the trained `scene` by `objects` with `method` (the command's default when
/// None), into `out` (a .ply).
pub fn tag(scene: &Path, capture: &Capture, objects: Objects, method: Option<&str>, out: &Path) -> Vec<String> {
    let mut v = vec!["tag".to_string(), "--scene".to_string(), path(scene)];
    v.extend(capture.args());
    match objects {
        Objects::Masks(m) => v.extend(["--masks".to_string(), m.to_string()]),
        Objects::Prompts(p) => v.extend(["--prompt".to_string(), p.join(",")]),
    }
    if let Some(m) = method {
        v.extend(["--method".to_string(), m.to_string()]);
    }
    v.extend(["--out".to_string(), path(out)]);
    v
}

/// `cogeo remove` of the `chosen` objects from the tagged `scene`, into `out`.
pub fn remove(scene: &Path, capture: &Capture, chosen: Chosen, out: &Path) -> Vec<String> {
    let mut v = vec!["remove".to_string(), "--scene".to_string(), path(scene)];
    v.extend(capture.args());
    match chosen {
        Chosen::Labels(l) => v.extend(["--labels".to_string(), l.to_string()]),
        Chosen::Names(n) => v.extend(["--prompt".to_string(), n.join(",")]),
    }
    v.extend(["--out".to_string(), path(out)]);
    v
}

/// `cogeo eval` of a removal's held-out renders (`removal/test_after`) against the ground-truth
/// images `gt` inside `masks`, into `out` (a .json).
pub fn eval(removal: &Path, gt: &Path, masks: &Path, out: &Path) -> Vec<String> {
    let mut v = vec!["eval".to_string(), "--renders".to_string(), path(&removal.join("test_after"))];
    v.extend(["--gt".to_string(), path(gt), "--masks".to_string(), path(masks), "--out".to_string(), path(out)]);
    v
}
