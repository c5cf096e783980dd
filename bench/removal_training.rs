//! One scene of the removal bench (removal.rs): its composite or room trained and tagged (or a
//! kept training reused), each variant removed and scored, a row per variant.

use crate::common::{self, cogeo, read_json, s};
use crate::{
    CAPTURE_CEILING, CONSISTENT_SOURCE, DISAGREEING, DISAGREEING_ROTATIONS, DISAGREEING_SEEDS, PERFECT_INPAINTING,
    PERFECT_INPAINTING_MEDIAN, SEEDED_VARIANTS,
};
use cogeo::pipeline::{self, Capture, Chosen, Layout, Objects};
use serde_json::{json, Value};
use std::path::{Path, PathBuf};

/// One scene's dataset and how to train, tag, remove and score on it.
pub struct Training<'a> {
    /// The scene's name and the labels it removes.
    pub name: &'a str,
    pub labels: &'a str,
    pub data: &'a Path,
    pub truth: &'a Path,
    pub iters: &'a str,
    pub lpips: &'a Option<String>,
    pub fid: &'a Option<String>,
    /// Train with `--exposure` and hand the learned maps to `cogeo remove`.
    pub exposure: bool,
    /// Score with `cogeo eval --fit-exposure` (captures whose views' exposure varies).
    pub fit_exposure: bool,
    /// Where trained and tagged scenes are kept between runs (`--reuse-composites`), one folder
    /// per training seed; None trains and tags afresh.
    pub reuse: Option<PathBuf>,
    /// A real scene's capture trained without the objects (`CAPTURE_CEILING`); None for the synth
    /// rooms, which skip that variant.
    pub original: Option<&'a Path>,
    /// `cogeo remove --seed` of each run of the full pipeline and of the rivals it must beat
    /// (`SEEDED_VARIANTS`, `--removal-seeds N`: seeds 0 to N-1): their row is the run of median
    /// masked LPIPS, every run's scores beside it. One seed: the default's one run.
    pub removal_seeds: u64,
    /// Flags added to every `cogeo remove` the bench runs on this scene (`--remove-args`): a
    /// lever measured on every variant and seed alike, on a trial run.
    pub remove_args: &'a [String],
}

impl Training<'_> {
    /// A folder of completed views for `--inpainted`, view by view from the `--no-refine` runs of
    /// the built-in fill with `seeds` (view i, in name order, from `seeds[i % seeds.len()]`), with
    /// `--share-inventions` where `shared` (the views consistent: one invention per surface point).
    /// The runs are kept in `dir` for the next variant.
    fn seed_inpaintings(&self, dir: &Path, tagged: &Path, seeds: &[u64], shared: bool) -> PathBuf {
        let capture = Capture::at(self.data);
        let runs: Vec<PathBuf> = seeds
            .iter()
            .map(|seed| {
                let out = dir.join(format!("fill_seed{seed}{}", if shared { "_shared" } else { "" }));
                if !out.join("inpainted").is_dir() {
                    let mut a = pipeline::remove(tagged, &capture, Chosen::Labels(self.labels), &out);
                    a.extend(s(&["--no-refine", "--seed", &seed.to_string()]));
                    a.extend(self.remove_args.iter().cloned());
                    if shared {
                        a.push("--share-inventions".into());
                    }
                    cogeo(&a);
                }
                out.join("inpainted")
            })
            .collect();
        if let [one] = &runs[..] {
            return one.clone();
        }
        let mixed =
            dir.join(format!("inpainted_seeds_{}", seeds.iter().map(u64::to_string).collect::<Vec<_>>().join("_")));
        std::fs::create_dir_all(&mixed).expect("cannot create the mixed inpaintings' folder");
        let mut names: Vec<_> = std::fs::read_dir(&runs[0])
            .expect("cannot read a fill's inpainted views")
            .map(|e| e.expect("cannot read a folder entry").file_name())
            .collect();
        names.sort();
        for (i, name) in names.iter().enumerate() {
            std::fs::copy(runs[i % runs.len()].join(name), mixed.join(name)).expect("cannot copy an inpainted view");
        }
        mixed
    }

    /// `cogeo eval` of the held-out renders in `out/test_after` (made from `scene`) into
    /// `out/metrics.json`.
    fn score(&self, out: &Path, scene: &Path) {
        let p = |x: &Path| x.to_string_lossy().into_owned();
        let mut e = pipeline::eval(out, self.truth, &self.data.join("object_mask"), &out.join("metrics.json"));
        e.extend(s(&["--labels", self.labels, "--data", &p(self.data), "--scene", &p(scene)]));
        if let Some(m) = self.lpips {
            e.extend(s(&["--lpips-model", m]));
        }
        if let Some(m) = self.fid {
            e.extend(s(&["--fid-model", m]));
        }
        if self.fit_exposure {
            e.push("--fit-exposure".into());
        }
        cogeo(&e);
    }

    /// `CAPTURE_CEILING`'s row: the `original` training rendered at the composite's cameras, its
    /// held-out views (the dataset's test split) scored like a removal's. No removal ran: no
    /// time, no Gaussian counts; the training fields and the device are the original's.
    fn ceiling_row(&self, original: &Path, out: &Path) -> Value {
        let p = |x: &Path| x.to_string_lossy().into_owned();
        let all = out.join("all_views");
        cogeo(&s(&["render", "--scene", &p(original), "--colmap", &p(self.data), "--out", &p(&all)]));
        let held_out = out.join("test_after");
        std::fs::create_dir_all(&held_out).expect("cannot create the ceiling's test_after");
        // the held-out views are the dataset's split of the model's cameras (no photo need load)
        let model = cogeo::scene::dataset::read_capture(self.data).expect("the composite's model reads");
        for (_, cam) in model.cameras.iter().enumerate().filter(|(i, _)| cogeo::scene::dataset::is_test_view(*i)) {
            let name = format!("{}.png", cam.name);
            std::fs::copy(all.join(&name), held_out.join(&name)).expect("cannot copy a held-out render");
        }
        self.score(out, original);
        // the training is the original's (its own seed); `cogeo render` names no device: the one
        // that training ran on
        let trained = read_json(&original.with_file_name("metrics.json"));
        json!({
            "scene": self.name, "removed_labels": self.labels, "variant": CAPTURE_CEILING, "training_seed": Value::Null,
            "exposure": self.exposure, "train_test_psnr_exposure_fitted": trained["test"]["psnr_exposure_fitted"],
            "device": trained["device"], "train_test_psnr": trained["test"]["psnr"],
            "metrics": read_json(&out.join("metrics.json")), "stage_seconds": Value::Null, "total_seconds": Value::Null,
            "peak_rss_mib": Value::Null, "gaussians": Value::Null, "background_psnr_vs_original": Value::Null,
        })
    }

    /// Trains the composite with `seed` into `dir` and tags it by each of `methods`, or copies a
    /// kept training (`reuse`) and its taggings; a tagging the kept training lacks is made and
    /// kept beside the others (a run of some variants keeps only the taggings they ask for).
    fn train_and_tag(&self, dir: &Path, seed: u64, methods: &[&str]) {
        let layout = Layout { out: dir };
        let capture = Capture::at(self.data);
        let tagged_name = |method: &str| format!("tagged_{method}.ply");
        let kept = self.reuse.as_ref().map(|r| r.join(format!("seed{seed}")));
        let reusable = kept.as_ref().filter(|k| k.join("train/scene.ply").is_file());
        if let Some(k) = reusable {
            eprintln!("{}: reusing the training kept in {}", self.name, k.display());
            copy_tree(&k.join("train"), &layout.train());
        } else {
            let mut train_args = pipeline::train(&capture, &layout.train());
            // a composite trains as its capture did (removal_real::prepare), a synth room as the
            // synth rooms do
            train_args.extend(match self.original {
                Some(_) => pipeline::capture_training(self.iters, Some(seed)),
                None => pipeline::synth_training(self.iters.parse().expect("--iters is a number"), seed),
            });
            if self.exposure {
                train_args.push("--exposure".into());
            }
            cogeo(&train_args);
        }
        for method in methods {
            let tagged = dir.join(tagged_name(method));
            match reusable.map(|k| k.join(tagged_name(method))).filter(|t| t.is_file()) {
                Some(kept_tagging) => {
                    std::fs::copy(kept_tagging, &tagged).expect("cannot copy a kept tagging");
                }
                None => {
                    cogeo(&pipeline::tag(
                        &layout.trained_scene(),
                        &capture,
                        Objects::Masks("object_mask"),
                        Some(method),
                        &tagged,
                    ));
                }
            }
        }
        let Some(k) = &kept else { return };
        if reusable.is_none() {
            common::make_folder(k, |partial| copy_tree(&layout.train(), &partial.join("train")));
            eprintln!("{}: training kept in {}", self.name, k.display());
        }
        // the taggings made here join the kept ones (a copy renamed into place: a run stopped
        // halfway leaves no partial tagging there)
        for m in methods.iter().filter(|m| !k.join(tagged_name(m)).is_file()) {
            let partial = k.join(format!("{}.partial", tagged_name(m)));
            std::fs::copy(dir.join(tagged_name(m)), &partial).expect("cannot keep a tagging");
            std::fs::rename(&partial, k.join(tagged_name(m))).expect("cannot keep a tagging");
            eprintln!("{}: tagging by {m} kept in {}", self.name, k.display());
        }
    }

    /// Trains the scene with `seed` into `dir`, tags it, runs each variant and scores it: one row per
    /// variant, with the device and the training's seed and test PSNR.
    pub fn variants(&self, dir: &Path, seed: u64, variants: &[(&str, &str, &[&str])]) -> Vec<Value> {
        let p = |x: &Path| x.to_string_lossy().into_owned();
        let data = self.data;
        let layout = Layout { out: dir };
        let capture = Capture::at(data);
        // the ceiling removes nothing: it needs neither the composite's training nor a tagging
        let mut methods: Vec<&str> = variants.iter().filter(|v| v.0 != CAPTURE_CEILING).map(|v| v.1).collect();
        methods.sort();
        methods.dedup();
        let train_metrics = if methods.is_empty() {
            Value::Null
        } else {
            self.train_and_tag(dir, seed, &methods);
            read_json(&layout.train().join("metrics.json"))
        };
        let mut rows = Vec::new();
        for (k, (variant, method, extra)) in variants.iter().enumerate() {
            let out = dir.join(format!("variant_{k}"));
            if *variant == CAPTURE_CEILING {
                let Some(original) = self.original else { continue };
                rows.push(self.ceiling_row(original, &out));
                continue;
            }
            let tagged = dir.join(format!("tagged_{method}.ply"));
            // the consistent-source variant runs once per seed, each seed's fill with shared
            // inventions a consistent source of its own, the disagreeing one once per rotation of
            // the seeds over the views, the full pipeline and its rivals once per removal seed
            // (`--removal-seeds`); the others once
            let sources: Vec<RunSeeds> = match *variant {
                CONSISTENT_SOURCE => {
                    DISAGREEING_SEEDS.iter().map(|seed| RunSeeds::Inpainted(std::slice::from_ref(seed))).collect()
                }
                DISAGREEING => DISAGREEING_ROTATIONS.iter().map(|r| RunSeeds::Inpainted(&r[..])).collect(),
                v if SEEDED_VARIANTS.contains(&v) && self.removal_seeds > 1 => {
                    (0..self.removal_seeds).map(RunSeeds::Removal).collect()
                }
                _ => vec![RunSeeds::Default],
            };
            let mut runs = Vec::new();
            for (r, run_seeds) in sources.iter().enumerate() {
                let out = if sources.len() > 1 { dir.join(format!("variant_{k}_run{r}")) } else { out.clone() };
                let mut a = pipeline::remove(&tagged, &capture, Chosen::Labels(self.labels), &out);
                a.extend(s(extra));
                a.extend(self.remove_args.iter().cloned());
                let seeds = match run_seeds {
                    RunSeeds::Inpainted(seeds) => Some(*seeds),
                    RunSeeds::Removal(seed) => {
                        a.extend(s(&["--seed", &seed.to_string()]));
                        None
                    }
                    RunSeeds::Default => None,
                };
                if *variant == PERFECT_INPAINTING || *variant == PERFECT_INPAINTING_MEDIAN {
                    a.extend(s(&["--inpainted", &p(self.truth)]));
                }
                if let Some(seeds) = seeds {
                    let shared = *variant == CONSISTENT_SOURCE;
                    a.extend(s(&["--inpainted", &p(&self.seed_inpaintings(dir, &tagged, seeds, shared))]));
                }
                if self.exposure {
                    a.extend(s(&["--exposure", &p(&layout.exposure())]));
                }
                cogeo(&a);
                self.score(&out, &out.join("scene.ply"));
                let report = read_json(&out.join("report.json"));
                let m = read_json(&out.join("metrics.json"));
                runs.push(json!({
                    "scene": self.name, "removed_labels": self.labels, "variant": variant, "training_seed": seed,
                    "remove_args": self.remove_args, "exposure": self.exposure, "train_test_psnr_exposure_fitted": train_metrics["test"]["psnr_exposure_fitted"],
                    "device": report["device"], "train_test_psnr": train_metrics["test"]["psnr"],
                    "metrics": m, "stage_seconds": report["seconds"], "total_seconds": report["total_seconds"],
                    "peak_rss_mib": report["peak_rss_mib"], "gaussians": report["gaussians"],
                    "background_psnr_vs_original": report["background_psnr_vs_original"]["mean"],
                }));
            }
            let row = median_run(runs, seeds_of(&sources));
            // the median run's folder is the variant's, as a single run's (the contact sheet's)
            if let Some(r) = row["median_run"].as_u64() {
                let median = dir.join(format!("variant_{k}_run{r}"));
                std::fs::rename(&median, &out)
                    .unwrap_or_else(|e| panic!("cannot rename {} to {}: {e}", median.display(), out.display()));
            }
            rows.push(row);
        }
        rows
    }
}

/// What makes a variant's runs differ.
enum RunSeeds<'s> {
    /// One run with `cogeo remove`'s default seed.
    Default,
    /// The built-in fill's seeds fed back as `--inpainted`, view by view (`seed_inpaintings`).
    Inpainted(&'s [u64]),
    /// `cogeo remove --seed`: the exemplar fill's and the refinement's view order.
    Removal(u64),
}

/// The seeds of each run of a variant, for its row.
fn seeds_of(sources: &[RunSeeds]) -> Vec<Value> {
    sources
        .iter()
        .map(|s| match s {
            RunSeeds::Default => Value::Null,
            RunSeeds::Inpainted(seeds) => json!(seeds),
            RunSeeds::Removal(seed) => json!({ "removal_seed": seed }),
        })
        .collect()
}

/// A variant's row: its one run, or of several runs (the consistent source, a run per seed; the
/// disagreeing one, a run per rotation of the seeds; with `--removal-seeds`, the full pipeline and
/// its rivals, a run per removal seed) the one of median masked LPIPS, with every
/// run's seeds, masked PSNR and LPIPS beside it (`runs`): one seed's fill can be luckier than
/// another's by more than the disagreeing inpaintings' yardstick allows (statue-two-of-three,
/// seeds 0-3: masked LPIPS 0.210 / 0.199 / 0.225 / 0.204), so the yardstick compares the typical
/// run of each side, not one seed's.
fn median_run(mut runs: Vec<Value>, seeds: Vec<Value>) -> Value {
    if runs.len() == 1 {
        return runs.pop().expect("one run");
    }
    let lpips = |r: &Value| r["metrics"]["lpips"]["mask"].as_f64().unwrap_or(f64::NAN);
    let each: Vec<Value> = runs
        .iter()
        .zip(seeds)
        .map(|(r, seeds)| json!({"seeds": seeds, "mask_psnr": r["metrics"]["mask"]["psnr"], "mask_lpips": r["metrics"]["lpips"]["mask"]}))
        .collect();
    let mut order: Vec<usize> = (0..runs.len()).collect();
    order.sort_by(|&a, &b| lpips(&runs[a]).total_cmp(&lpips(&runs[b])));
    let median = order[order.len() / 2];
    let mut row = runs.swap_remove(median);
    row["runs"] = json!(each);
    row["median_run"] = json!(median);
    row
}

/// Copies the folder `from` (files and subfolders) to `to`, which is created.
fn copy_tree(from: &Path, to: &Path) {
    std::fs::create_dir_all(to).unwrap_or_else(|e| panic!("cannot create {}: {e}", to.display()));
    for entry in std::fs::read_dir(from).unwrap_or_else(|e| panic!("cannot read {}: {e}", from.display())) {
        let entry = entry.expect("cannot read a folder entry");
        let target = to.join(entry.file_name());
        if entry.file_type().expect("cannot stat a folder entry").is_dir() {
            copy_tree(&entry.path(), &target);
        } else {
            std::fs::copy(entry.path(), &target)
                .unwrap_or_else(|e| panic!("cannot copy {} to {}: {e}", entry.path().display(), target.display()));
        }
    }
}
