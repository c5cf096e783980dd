//! Text prompts for tagging through the detector + segmenter ONNX contracts, with tiny models the
//! test builds (tests/common/onnx.rs): exact label maps on a constructed image, and `cogeo tag
//! --prompt` end to end on a synth scene.

mod common;

use cogeo::tag::prompt::PromptSegmenter;
use common::onnx::{self, PROMPT_H, PROMPT_W};
use common::run_cogeo;

fn models(dir: &std::path::Path) -> (std::path::PathBuf, std::path::PathBuf, std::path::PathBuf) {
    let det = onnx::write(dir, "detector.onnx", &onnx::tiny_detector());
    let seg = onnx::write(dir, "segmenter.onnx", &onnx::tiny_segmenter());
    let emb = dir.join("embeddings.json");
    std::fs::write(&emb, r#"{"red": [1, -1, -1], "green": [-1, 1, -1], "blue": [-1, -1, 1], "anything": [1, 1, 1]}"#)
        .unwrap();
    (det, seg, emb)
}

#[test]
fn prompts_give_exact_label_maps_on_a_constructed_image() {
    let dir = std::env::temp_dir().join(format!("cogeo_prompt_{}", std::process::id()));
    let (det, seg, emb) = models(&dir);
    let (w, h) = (PROMPT_W, PROMPT_H);
    let mut rgb = vec![0.5f32; 3 * w * h];
    let mut expect = vec![0u8; w * h];
    let mut paint = |x0: usize, x1: usize, y0: usize, y1: usize, color: [f32; 3], label: u8| {
        for y in y0..y1 {
            for x in x0..x1 {
                for c in 0..3 {
                    rgb[c * w * h + y * w + x] = color[c];
                }
                expect[y * w + x] = label;
            }
        }
    };
    paint(4, 12, 3, 9, [0.9, 0.1, 0.1], 1);
    paint(18, 28, 10, 20, [0.1, 0.9, 0.1], 2);
    let prompts: Vec<String> = ["red", "green", "blue"].iter().map(|s| s.to_string()).collect();
    let mut ps = PromptSegmenter::load(&det, &seg, &emb, &prompts, 0.3).unwrap();
    let (maps, found) = ps.label_maps(&[(&rgb, w, h)]).unwrap();
    assert_eq!(maps.num_objects, 3);
    assert_eq!(maps.names, prompts);
    assert_eq!(maps.maps[0], expect);
    let red = found[0][0].as_ref().unwrap();
    assert_eq!(red.bbox, [4.0, 3.0, 12.0, 9.0]);
    assert_eq!(red.pixels, 48);
    assert_eq!(found[0][1].as_ref().unwrap().pixels, 100);
    assert!(found[0][2].is_none(), "blue is not in the image");
    // a prompt without an embedding is refused by name
    let err = PromptSegmenter::load(&det, &seg, &emb, &["purple".to_string()], 0.3).err().unwrap().to_string();
    assert!(err.contains("purple") && err.contains("embeddings.json"), "{err}");
    // the models' roles are checked by their inputs
    let err = PromptSegmenter::load(&seg, &det, &emb, &prompts, 0.3).err().unwrap().to_string();
    assert!(err.contains("detector contract"), "{err}");
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn tag_with_prompts_end_to_end() {
    let exe = env!("CARGO_BIN_EXE_cogeo");
    let root = std::env::temp_dir().join(format!("cogeo_prompt_cli_{}", std::process::id()));
    let path = |p: &str| root.join(p).to_string_lossy().into_owned();
    let (det, seg, emb) = models(&root.join("models"));
    let data = path("data");
    let (w, h) = (PROMPT_W.to_string(), PROMPT_H.to_string());
    run_cogeo(exe, &["synth", "--out", &data, "--width", &w, "--height", &h, "--views", "8", "--objects", "2"]);
    run_cogeo(
        exe,
        &[
            "train",
            "--data",
            &data,
            "--out",
            &path("train"),
            "--iters",
            "30",
            "--sh-degree",
            "0",
            "--no-densify",
            "--checkpoint-every",
            "0",
        ],
    );
    let scene = path("train/scene.ply");
    let tagged = path("tagged.ply");
    // without models: a clear message
    let out = std::process::Command::new(exe)
        .args(["tag", "--scene", &scene, "--data", &data, "--prompt", "anything", "--method", "vote", "--out", &tagged])
        .output()
        .unwrap();
    assert!(!out.status.success());
    assert!(String::from_utf8_lossy(&out.stderr).contains("text prompts need ONNX models"));
    let (det, seg, emb) = (det.to_string_lossy(), seg.to_string_lossy(), emb.to_string_lossy());
    run_cogeo(
        exe,
        &[
            "tag",
            "--scene",
            &scene,
            "--data",
            &data,
            "--prompt",
            "anything",
            "--detector",
            &det,
            "--segmenter",
            &seg,
            "--prompt-embeddings",
            &emb,
            "--method",
            "vote",
            "--out",
            &tagged,
        ],
    );
    // the written prompt masks are what the models give on each training image
    let ds = cogeo::scene::dataset::load(std::path::Path::new(&data), "images", 1).unwrap();
    let mut ps = PromptSegmenter::load(
        std::path::Path::new(&*det),
        std::path::Path::new(&*seg),
        std::path::Path::new(&*emb),
        &["anything".to_string()],
        0.3,
    )
    .unwrap();
    let mut labelled = 0;
    for v in &ds.train {
        let (expect, _) = ps.label_map(&v.image, PROMPT_W, PROMPT_H).unwrap();
        let written = image::open(root.join(format!("tagged_prompt_masks/{}.png", v.camera.name))).unwrap().to_luma8();
        assert_eq!(written.into_raw(), expect, "{}", v.camera.name);
        labelled += expect.iter().filter(|&&l| l == 1).count();
    }
    assert!(labelled > 0);
    let sidecar: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(path("tagged.json")).unwrap()).unwrap();
    assert_eq!(sidecar["names"][0], "anything");
    assert_eq!(sidecar["prompts"]["views_detected"][0].as_u64().unwrap(), ds.train.len() as u64);
    let tagged_scene = cogeo::scene::ply::read_ply(std::path::Path::new(&tagged)).unwrap();
    let labels = cogeo::tag::scene_labels(&tagged_scene).unwrap();
    assert!(labels.contains(&1), "no Gaussian took the prompt's label");
    std::fs::remove_dir_all(&root).ok();
}
