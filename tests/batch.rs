//! `cogeo batch`: the manifest checks, one entry end to end with its markers, a rerun that skips
//! every step, a kill inside training that the next run resumes from the checkpoint, the index
//! from Slurm's and Kubernetes' variables, the exit statuses, the report, the Kubernetes Indexed
//! Job's fields, and a real single-node Slurm cluster running the sbatch file
//! (scripts/slurm_test.sh; skipped with a message where Slurm cannot be installed).

mod common;

use common::run_cogeo;
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

const EXE: &str = env!("CARGO_BIN_EXE_cogeo");

fn batch(args: &[&str], env: &[(&str, &str)]) -> Output {
    let mut c = Command::new(EXE);
    c.arg("batch").args(args).env("COGEO_VALIDATE", std::env::var("COGEO_VALIDATE").unwrap_or_else(|_| "1".into()));
    for v in ["SLURM_ARRAY_TASK_ID", "JOB_COMPLETION_INDEX", "SLURM_RESTART_COUNT"] {
        c.env_remove(v);
    }
    c.envs(env.iter().copied()).output().unwrap()
}

fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

/// Two tiny synth scenes and a manifest over them (entry 1 has ground truth and its own options).
fn setup(name: &str, train_iters: u32) -> (PathBuf, PathBuf) {
    let root = std::env::temp_dir().join(format!("cogeo_batch_{name}_{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&root);
    for i in 0..2 {
        let data = root.join(format!("scenes/s{i}")).to_string_lossy().into_owned();
        let seed = (i + 1).to_string();
        let synth = ["synth", "--out", &data, "--width", "32", "--height", "24", "--views", "8", "--objects", "2"];
        run_cogeo(EXE, &[&synth[..], &["--seed", &seed, "--gt-without", "1"]].concat());
    }
    let manifest = root.join("scenes.json");
    let text = format!(
        r#"{{
  "output_root": "out",
  "defaults": {{
    "train": ["--iters", "{train_iters}", "--sh-degree", "0", "--checkpoint-every", "20"],
    "tag": ["--method", "vote"],
    "remove": ["--refine-iters", "10"]
  }},
  "scenes": [
    {{"name": "a", "data": "scenes/s0", "masks": "object_mask", "labels": [1, 2]}},
    {{"name": "b", "data": "scenes/s1", "masks": "object_mask", "labels": [1],
      "ground_truth": {{"images": "scenes/s1/without_1/images", "masks": "scenes/s1/object_mask", "synth": true}},
      "options": {{"train": ["--iters", "{}", "--exposure"]}}}}
  ]
}}"#,
        train_iters + 10
    );
    std::fs::write(&manifest, text).unwrap();
    (root, manifest)
}

#[test]
fn one_entry_end_to_end_then_skipped_then_reported() {
    let (root, manifest) = setup("e2e", 40);
    let m = manifest.to_str().unwrap();
    let plan = batch(&["plan", m, "--count"], &[]);
    assert!(plan.status.success(), "{}", stderr(&plan));
    assert_eq!(String::from_utf8_lossy(&plan.stdout).trim(), "2");

    // the index from Kubernetes' variable; every step runs and leaves its marker
    let first = batch(&["run", m], &[("JOB_COMPLETION_INDEX", "1")]);
    assert!(first.status.success(), "{}", stderr(&first));
    let out = root.join("out/b");
    for step in ["train", "tag", "remove", "eval"] {
        let marker: serde_json::Value =
            serde_json::from_slice(&std::fs::read(out.join(format!(".batch/{step}.json"))).unwrap()).unwrap();
        assert_eq!(marker["step"], step);
    }
    // the entry's own --iters replaced the default
    let metrics: serde_json::Value =
        serde_json::from_slice(&std::fs::read(out.join("train/metrics.json")).unwrap()).unwrap();
    assert_eq!(metrics["iterations"], 50);
    // the entry's --exposure training left its maps, and its removal took them
    let maps: serde_json::Value =
        serde_json::from_slice(&std::fs::read(out.join("train/exposure.json")).unwrap()).unwrap();
    assert_eq!(maps["views"].as_array().unwrap().len(), 7);
    let marker = std::fs::read_to_string(out.join(".batch/remove.json")).unwrap();
    assert!(marker.contains("exposure.json"), "{marker}");
    let eval: serde_json::Value = serde_json::from_slice(&std::fs::read(out.join("eval.json")).unwrap()).unwrap();
    assert!(eval["mask"]["psnr"].as_f64().unwrap() > 5.0);

    // a second run (Slurm's variable this time) skips everything and changes nothing
    let scene = std::fs::read(out.join("removal/scene.ply")).unwrap();
    let again = batch(&["run", m], &[("SLURM_ARRAY_TASK_ID", "1")]);
    assert!(again.status.success(), "{}", stderr(&again));
    for step in ["train", "tag", "remove", "eval"] {
        assert!(stderr(&again).contains(&format!("batch: skip {step}")), "{}", stderr(&again));
    }
    assert_eq!(std::fs::read(out.join("removal/scene.ply")).unwrap(), scene);

    let report = batch(&["report", m], &[]);
    assert!(report.status.success(), "{}", stderr(&report));
    let table = String::from_utf8_lossy(&report.stdout).into_owned();
    assert!(table.contains("| a | not started |") && table.contains("| b | done | "), "{table}");
    let json: serde_json::Value =
        serde_json::from_slice(&std::fs::read(root.join("out/report.json")).unwrap()).unwrap();
    assert_eq!(json["entries"][1]["iterations"], 50);
    assert!(json["entries"][1]["masked_psnr"].as_f64().is_some());
    assert!(json["entries"][1]["seconds"]["train"].as_f64().is_some());
    std::fs::remove_dir_all(&root).ok();
}

#[test]
fn a_task_killed_in_training_resumes_from_its_checkpoint() {
    let (root, manifest) = setup("resume", 400);
    let m = manifest.to_str().unwrap();
    let checkpoint = root.join("out/a/train/checkpoint/state.json");
    let mut child = Command::new(EXE)
        .args(["batch", "run", m, "--index", "0"])
        .env("COGEO_VALIDATE", std::env::var("COGEO_VALIDATE").unwrap_or_else(|_| "1".into()))
        .stderr(std::process::Stdio::null())
        .spawn()
        .unwrap();
    let start = std::time::Instant::now();
    while !checkpoint.exists() && start.elapsed().as_secs() < 120 {
        std::thread::sleep(std::time::Duration::from_millis(50));
    }
    child.kill().unwrap(); // SIGKILL, as a preemption without grace would
    child.wait().unwrap();
    assert!(checkpoint.exists(), "no checkpoint within 120 s");
    assert!(!root.join("out/a/.batch/train.json").exists(), "training finished before the kill");
    let resumed = batch(&["run", m, "--index", "0"], &[]);
    let log = stderr(&resumed);
    assert!(resumed.status.success(), "{log}");
    assert!(log.contains("resumed at iteration"), "the rerun did not resume training:\n{log}");
    assert!(root.join("out/a/.batch/remove.json").exists());
    std::fs::remove_dir_all(&root).ok();
}

#[test]
fn exit_status_says_whether_a_retry_can_help() {
    let (root, manifest) = setup("exit", 20);
    let m = manifest.to_str().unwrap();
    let code = |o: &Output| o.status.code();
    // no index anywhere, an index past the end: permanent (65), naming the problem
    let none = batch(&["run", m], &[]);
    assert_eq!(code(&none), Some(65), "{}", stderr(&none));
    assert!(stderr(&none).contains("SLURM_ARRAY_TASK_ID"));
    let past = batch(&["run", m, "--index", "2"], &[]);
    assert_eq!(code(&past), Some(65));
    assert!(stderr(&past).contains("entry 2 does not exist (2 entries)"), "{}", stderr(&past));
    // bad entries: plan names each, run gives 65
    let bad = |field: &str, value: &str| {
        let text = std::fs::read_to_string(&manifest).unwrap().replace(field, value);
        let path = root.join("bad.json");
        std::fs::write(&path, text).unwrap();
        let plan = batch(&["plan", path.to_str().unwrap()], &[]);
        let run = batch(&["run", path.to_str().unwrap(), "--index", "0"], &[]);
        assert_eq!(code(&run), Some(65), "{}", stderr(&run));
        stderr(&plan)
    };
    assert!(
        bad(r#""labels": [1, 2]"#, r#""labels": [0]"#).contains("entry 0 (\"a\"): labels: label 0 is the background")
    );
    assert!(bad(r#""data": "scenes/s0""#, r#""data": "scenes/nope""#).contains("entry 0 (\"a\")"));
    assert!(bad(r#""tag": ["--method", "vote"]"#, r#""tag": ["--method", "guess"]"#).contains("options.tag"));
    assert!(
        bad(r#""tag": ["--method", "vote"]"#, r#""tag": ["--out", "x"]"#).contains("--out is set by the batch itself")
    );
    assert!(bad(r#""masks": "object_mask", "labels": [1, 2]"#, r#""labels": [1, 2]"#).contains("exactly one of"));
    assert!(bad(r#""name": "b""#, r#""name": "a""#).contains("the name \"a\" is used twice"));
    // a step that fails (here: no GPU memory) is retryable (75)
    let oom = Command::new(EXE)
        .args(["batch", "run", m, "--index", "0"])
        .env("COGEO_MAX_DEVICE_MEMORY_MIB", "0.01")
        .output()
        .unwrap();
    assert_eq!(code(&oom), Some(75), "{}", stderr(&oom));
    assert!(
        stderr(&oom).contains("retryable failure") && stderr(&oom).contains("out of GPU memory"),
        "{}",
        stderr(&oom)
    );
    std::fs::remove_dir_all(&root).ok();
}

/// The Kubernetes Indexed Job: parsed with PyYAML (Kubernetes itself cannot run here) and checked
/// for what the recipe relies on.
#[test]
fn kubernetes_indexed_job_has_what_the_recipe_needs() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("deploy/k8s/indexed-job.yaml");
    let py = "import json, sys, yaml; print(json.dumps(yaml.safe_load(open(sys.argv[1]))))";
    let out = match Command::new("python3").args(["-c", py]).arg(&path).output() {
        Ok(o) if o.status.success() => o,
        _ => {
            eprintln!("kubernetes YAML check skipped: python3 with PyYAML (python3-yaml) is not available");
            return;
        }
    };
    let job: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(job["apiVersion"], "batch/v1");
    assert_eq!(job["kind"], "Job");
    let spec = &job["spec"];
    assert_eq!(spec["completionMode"], "Indexed");
    assert!(spec["completions"].as_u64().unwrap() >= 1 && spec["parallelism"].as_u64().is_some());
    let rules = spec["podFailurePolicy"]["rules"].as_array().unwrap();
    assert!(rules.iter().any(|r| r["action"] == "FailIndex" && r["onExitCodes"]["values"] == serde_json::json!([65])));
    assert!(spec["backoffLimitPerIndex"].as_u64().unwrap() >= 1, "exit 75 must be retried per index");
    let pod = &spec["template"]["spec"];
    assert_eq!(pod["restartPolicy"], "Never");
    let c = &pod["containers"][0];
    let cmd: Vec<&str> = c["command"].as_array().unwrap().iter().map(|v| v.as_str().unwrap()).collect();
    assert_eq!(
        &cmd[..3],
        ["cogeo", "batch", "run"],
        "the pod must run one entry; its index comes from JOB_COMPLETION_INDEX"
    );
    assert!(!cmd.contains(&"--index"));
    assert_eq!(c["resources"]["limits"]["nvidia.com/gpu"], 1);
    let mount = c["volumeMounts"][0]["name"].clone();
    let volume = pod["volumes"].as_array().unwrap().iter().find(|v| v["name"] == mount).unwrap();
    assert!(volume["persistentVolumeClaim"]["claimName"].is_string(), "the work volume must be a shared claim");
    let caps = c["env"].as_array().unwrap().iter().find(|e| e["name"] == "NVIDIA_DRIVER_CAPABILITIES").unwrap();
    assert!(caps["value"].as_str().unwrap().contains("graphics"), "the Vulkan ICD needs the graphics capability");
}

#[test]
fn slurm_job_array_with_a_cancelled_and_requeued_task() {
    let script = Path::new(env!("CARGO_MANIFEST_DIR")).join("scripts/slurm_test.sh");
    let out = Command::new("bash").arg(&script).arg(EXE).output().unwrap();
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(out.status.success(), "{stdout}\n{}", stderr(&out));
    if stdout.contains("slurm test skipped") {
        eprintln!("{}", stdout.trim());
        return;
    }
    assert!(stdout.contains("slurm test: passed"), "{stdout}");
    eprintln!("{stdout}");
}
