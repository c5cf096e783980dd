//! The `cogeo batch` manifest: a JSON file listing scenes (schema in docs/usage.md, "Processing many
//! scenes"). Paths in it are relative to the manifest's folder. Each entry becomes the command
//! lines of its steps; per-entry options override the manifest's defaults flag by flag.

use anyhow::{anyhow, bail, Context, Result};
use clap::Parser;
use cogeo::pipeline::{self, Capture, Chosen, Layout, Objects};
use serde::Deserialize;
use std::path::{Path, PathBuf};

/// Extra options per command, as on the command line (`["--iters", "7000"]`).
#[derive(Deserialize, Default, Clone)]
#[serde(deny_unknown_fields)]
pub struct StepOptions {
    #[serde(default)]
    pub train: Vec<String>,
    #[serde(default)]
    pub tag: Vec<String>,
    #[serde(default)]
    pub remove: Vec<String>,
    #[serde(default)]
    pub eval: Vec<String>,
}

/// Held-out ground truth for `cogeo eval`: images of the held-out views without the objects and
/// the object masks of those views; `synth` marks a `cogeo synth` dataset (adds never-seen /
/// seen-elsewhere scores).
#[derive(Deserialize, Clone)]
#[serde(deny_unknown_fields)]
pub struct GroundTruth {
    pub images: PathBuf,
    pub masks: PathBuf,
    #[serde(default)]
    pub synth: bool,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Entry {
    /// Output folder name under output_root; letters, digits, '.', '_' and '-'.
    pub name: String,
    /// Capture: COLMAP model (here or in sparse/0) or transforms.json, and image folders.
    pub data: PathBuf,
    #[serde(default = "default_images")]
    pub images: String,
    #[serde(default = "one")]
    pub downscale: u32,
    /// Tagging from masks: a folder inside `data` (`tag --masks`) ...
    pub masks: Option<String>,
    /// ... or from text prompts (`tag --prompt`; the detector, segmenter and embeddings go in
    /// `options.tag`).
    pub prompts: Option<Vec<String>>,
    /// What to remove: labels (`remove --labels`) or object names (`remove --prompt`).
    pub labels: Option<Vec<u64>>,
    pub remove_names: Option<Vec<String>>,
    pub ground_truth: Option<GroundTruth>,
    #[serde(default)]
    pub options: StepOptions,
}

fn default_images() -> String {
    cogeo::scene::dataset::DEFAULT_IMAGE_FOLDER.into()
}

fn one() -> u32 {
    1
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct ManifestFile {
    output_root: PathBuf,
    #[serde(default)]
    defaults: StepOptions,
    scenes: Vec<Entry>,
}

pub struct Manifest {
    pub path: PathBuf,
    pub output_root: PathBuf,
    pub defaults: StepOptions,
    pub entries: Vec<Entry>,
}

#[derive(Clone, Copy, PartialEq, Debug)]
pub enum Step {
    Train,
    Tag,
    Remove,
    Eval,
}

impl Step {
    pub fn name(self) -> &'static str {
        match self {
            Step::Train => "train",
            Step::Tag => "tag",
            Step::Remove => "remove",
            Step::Eval => "eval",
        }
    }
}

impl Manifest {
    pub fn load(path: &Path) -> Result<Manifest> {
        let text = std::fs::read(path).with_context(|| format!("{}: cannot read the manifest", path.display()))?;
        let file: ManifestFile = serde_json::from_slice(&text)
            .with_context(|| format!("{}: not a cogeo batch manifest (see docs/usage.md)", path.display()))?;
        if file.scenes.is_empty() {
            bail!("{}: no scenes", path.display());
        }
        let base = path.parent().filter(|p| !p.as_os_str().is_empty()).unwrap_or(Path::new("."));
        let base = std::fs::canonicalize(base).with_context(|| format!("{}: cannot resolve", base.display()))?;
        let resolve = |p: &Path| if p.is_absolute() { p.to_path_buf() } else { base.join(p) };
        let mut entries = file.scenes;
        for e in &mut entries {
            e.data = resolve(&e.data);
            if let Some(gt) = &mut e.ground_truth {
                gt.images = resolve(&gt.images);
                gt.masks = resolve(&gt.masks);
            }
        }
        for (i, e) in entries.iter().enumerate() {
            if entries[..i].iter().any(|o| o.name == e.name) {
                bail!(
                    "{}: entry {i}: the name {:?} is used twice (each entry needs its own output folder)",
                    path.display(),
                    e.name
                );
            }
        }
        Ok(Manifest {
            path: path.to_path_buf(),
            output_root: resolve(&file.output_root),
            defaults: file.defaults,
            entries,
        })
    }
}

/// The flags of a command line grouped as (flag, values), in order; a later group with the same
/// flag replaces the earlier one.
fn merge_flags(layers: &[&[String]]) -> Result<Vec<String>> {
    let mut groups: Vec<(String, Vec<String>)> = Vec::new();
    for layer in layers {
        let mut i = 0;
        while i < layer.len() {
            let flag = &layer[i];
            if !flag.starts_with("--") {
                bail!("option {flag:?} does not start with --");
            }
            let mut values = Vec::new();
            i += 1;
            while i < layer.len() && !layer[i].starts_with("--") {
                values.push(layer[i].clone());
                i += 1;
            }
            match groups.iter_mut().find(|(f, _)| f == flag) {
                Some(g) => g.1 = values,
                None => groups.push((flag.clone(), values)),
            }
        }
    }
    Ok(groups.into_iter().flat_map(|(f, v)| std::iter::once(f).chain(v)).collect())
}

/// Flags the batch sets itself: an entry's options may not move a step's inputs or outputs.
const RESERVED: [&str; 9] =
    ["--data", "--out", "--scene", "--images", "--downscale", "--renders", "--gt", "--masks", "--resume"];

impl Entry {
    pub fn out_dir(&self, m: &Manifest) -> PathBuf {
        m.output_root.join(&self.name)
    }

    pub fn steps(&self) -> Vec<Step> {
        let mut s = vec![Step::Train, Step::Tag, Step::Remove];
        if self.ground_truth.is_some() {
            s.push(Step::Eval);
        }
        s
    }

    fn options<'a>(&'a self, m: &'a Manifest, step: Step) -> [&'a [String]; 2] {
        let pick = |o: &'a StepOptions| -> &'a [String] {
            match step {
                Step::Train => &o.train,
                Step::Tag => &o.tag,
                Step::Remove => &o.remove,
                Step::Eval => &o.eval,
            }
        };
        [pick(&m.defaults), pick(&self.options)]
    }

    /// The `cogeo` command line of one step.
    pub fn command_line(&self, m: &Manifest, step: Step) -> Result<Vec<String>> {
        let out = self.out_dir(m);
        let layout = Layout { out: &out };
        let capture = Capture { data: &self.data, images: Some(&self.images), downscale: Some(self.downscale) };
        let labels = self.labels.as_ref().map(|l| l.iter().map(|v| v.to_string()).collect::<Vec<_>>().join(","));
        let base: Vec<String> = match step {
            Step::Train => {
                let mut v = pipeline::train(&capture, &layout.train());
                v.push("--resume".into());
                v
            }
            Step::Tag => {
                let objects = match (&self.masks, &self.prompts) {
                    (Some(masks), None) => Objects::Masks(masks),
                    (None, Some(prompts)) => Objects::Prompts(prompts),
                    _ => bail!("give exactly one of \"masks\" and \"prompts\""),
                };
                pipeline::tag(&layout.trained_scene(), &capture, objects, None, &layout.tagged())
            }
            Step::Remove => {
                let chosen = match (&labels, &self.remove_names) {
                    (Some(l), None) => Chosen::Labels(l),
                    (None, Some(names)) => Chosen::Names(names),
                    _ => bail!("give exactly one of \"labels\" and \"remove_names\""),
                };
                let mut v = pipeline::remove(&layout.tagged(), &capture, chosen, &layout.removal());
                // a training that learned exposure maps hands them on
                if self.options(m, Step::Train).iter().any(|o| o.iter().any(|f| f == "--exposure")) {
                    v.extend(["--exposure".into(), layout.exposure().to_string_lossy().into_owned()]);
                }
                v
            }
            Step::Eval => {
                let gt = self.ground_truth.as_ref().ok_or_else(|| anyhow!("no ground_truth"))?;
                let mut v = pipeline::eval(&layout.removal(), &gt.images, &gt.masks, &out.join("eval.json"));
                if let Some(l) = &labels {
                    v.extend(["--labels".into(), l.clone()]);
                }
                if gt.synth {
                    v.extend(["--data".into(), self.data.to_string_lossy().into_owned()]);
                }
                v
            }
        };
        debug_assert_eq!(base[0], step.name());
        let [defaults, own] = self.options(m, step);
        if let Some(flag) = defaults.iter().chain(own).find(|f| RESERVED.contains(&f.as_str())) {
            bail!("options.{}: {flag} is set by the batch itself", step.name());
        }
        let head = base[..1].to_vec();
        Ok(head.into_iter().chain(merge_flags(&[&base[1..], defaults, own])?).collect())
    }

    /// What `batch plan` checks of one entry: its name, its input folders, its labels, that each
    /// step's command line parses, and that every model file it names exists.
    pub fn validate(&self, m: &Manifest) -> Result<()> {
        if self.name.is_empty()
            || !self.name.chars().all(|c| c.is_ascii_alphanumeric() || "._-".contains(c))
            || self.name.starts_with('.')
        {
            bail!("name {:?}: use letters, digits, '.', '_' and '-' (it names the output folder)", self.name);
        }
        cogeo::scene::dataset::read_capture(&self.data)?;
        let images = self.data.join(&self.images);
        if !images.is_dir() {
            bail!("{}: image folder not found", images.display());
        }
        if !(1..=16).contains(&self.downscale) {
            bail!("downscale {} outside 1..=16", self.downscale);
        }
        if let Some(masks) = &self.masks {
            let dir = self.data.join(masks);
            if !dir.is_dir() {
                bail!("{}: mask folder not found", dir.display());
            }
        }
        for l in self.labels.iter().flatten() {
            cogeo::flag_values::parse_object_label(&l.to_string()).map_err(|e| anyhow!("labels: {e}"))?;
        }
        if let Some(gt) = &self.ground_truth {
            for dir in [&gt.images, &gt.masks] {
                if !dir.is_dir() {
                    bail!("{}: ground-truth folder not found", dir.display());
                }
            }
        }
        for step in self.steps() {
            let args = self.command_line(m, step)?;
            super::Cli::try_parse_from(std::iter::once("cogeo".to_string()).chain(args.iter().cloned()))
                .map_err(|e| anyhow!("options.{}: {}", step.name(), e.to_string().lines().next().unwrap_or("")))?;
            for model in args.iter().filter(|a| a.ends_with(".onnx")) {
                if !Path::new(model).is_file() {
                    bail!("options.{}: model {model} not found", step.name());
                }
            }
        }
        Ok(())
    }
}
