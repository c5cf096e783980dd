//! `--downscale N` (dataset loading): each image is box-filtered by N x N pixels and the intrinsics
//! divided by N. Checked against block means computed here, and against a capture of the same scene
//! taken directly at the lower resolution with N x N rays per pixel (`cogeo synth --supersample N`),
//! which is what an area-integrating camera of that resolution records.

mod common;

use cogeo::scene::dataset::{box_downscale, load};
use cogeo::synth::{generate, SynthConfig};

fn value(c: usize, x: usize, y: usize) -> f32 {
    // no two blocks alike, nothing a wrong block offset could still match
    ((c * 131 + x * 17 + y * y * 7 + x * y) % 97) as f32 / 97.0
}

#[test]
fn box_downscale_averages_blocks_and_drops_the_partial_edge() {
    let (w, h) = (11usize, 7usize);
    let mut rgb = vec![0f32; 3 * w * h];
    for c in 0..3 {
        for y in 0..h {
            for x in 0..w {
                rgb[c * w * h + y * w + x] = value(c, x, y);
            }
        }
    }
    for n in [1usize, 2, 3] {
        let (ow, oh, out) = box_downscale(w as u32, h as u32, &rgb, n as u32);
        assert_eq!((ow as usize, oh as usize), (w / n, h / n));
        for c in 0..3 {
            for y in 0..h / n {
                for x in 0..w / n {
                    let mut sum = 0f64;
                    for dy in 0..n {
                        for dx in 0..n {
                            sum += value(c, n * x + dx, n * y + dy) as f64;
                        }
                    }
                    let got = out[c * ow as usize * oh as usize + y * ow as usize + x] as f64;
                    assert!((got - sum / (n * n) as f64).abs() < 1e-6, "n {n} c {c} ({x}, {y}): {got}");
                }
            }
        }
    }
}

fn synth(dir: &std::path::Path, width: u32, height: u32, supersample: u32) {
    let cfg = SynthConfig {
        width,
        height,
        views: 9,
        objects: 2,
        rig: cogeo::synth::Rig::Forward,
        seed: 3,
        points_per_view: 20,
        gt_without: Vec::new(),
        supersample,
        distortion: [0.0; 4],
        exposure_jitter: 0.0,
    };
    generate(&cfg, dir, &|_, _| {}).unwrap();
}

#[test]
fn downscaled_load_matches_an_area_sampled_capture() {
    let root = std::env::temp_dir().join(format!("cogeo_downscale_{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&root);
    let (w, h, n) = (36u32, 26u32, 2u32);
    synth(&root.join("fine"), w * n, h * n, 1);
    synth(&root.join("coarse"), w, h, n);
    let fine = load(&root.join("fine"), "images", n).unwrap();
    let coarse = load(&root.join("coarse"), "images", 1).unwrap();
    assert!(load(&root.join("fine"), "images", 0).is_err());
    assert_eq!((fine.train.len(), fine.test.len()), (coarse.train.len(), coarse.test.len()));
    let (mut compared, mut off, mut textured) = (0usize, 0usize, 0usize);
    for (a, b) in fine.train.iter().chain(&fine.test).zip(coarse.train.iter().chain(&coarse.test)) {
        let (ca, cb) = (&a.camera, &b.camera);
        assert_eq!((ca.name.as_str(), ca.width, ca.height), (cb.name.as_str(), cb.width, cb.height));
        for (p, q) in [(ca.fx, cb.fx), (ca.fy, cb.fy), (ca.cx, cb.cx), (ca.cy, cb.cy)] {
            assert!((p - q).abs() < 1e-6 * q.abs().max(1.0), "intrinsics {p} vs {q} in {}", ca.name);
        }
        assert_eq!(ca.rotation, cb.rotation);
        assert_eq!(ca.translation, cb.translation);
        // both are 8-bit PNGs: the mean of four rounded values and the rounded mean differ by at
        // most one step; a sub-pixel ray may still land across a texture edge now and then
        for (i, (&x, &y)) in a.image.iter().zip(&b.image).enumerate() {
            compared += 1;
            if (x - y).abs() > 1.01 / 255.0 {
                off += 1;
            }
            let (c, p) = (i / (w * h) as usize, i % (w * h) as usize);
            let (px, py) = (p % w as usize, p / w as usize);
            if px + 1 < w as usize && (b.image[c * (w * h) as usize + py * w as usize + px + 1] - y).abs() > 0.1 {
                textured += 1;
            }
        }
    }
    assert!(textured * 20 > compared, "too little texture ({textured} of {compared}) to tell filters apart");
    assert!(off * 200 <= compared, "{off} of {compared} values differ from the area-sampled capture");
    let _ = std::fs::remove_dir_all(&root);
}

/// Rewrites `dir`'s COLMAP images.txt with every quaternion conjugated (the rotation transposed)
/// and the translation kept: the slip of writing camera-to-world rotations beside world-to-camera
/// translations.
fn conjugate_quaternions(dir: &std::path::Path) {
    let path = dir.join("sparse/0/images.txt");
    let text = std::fs::read_to_string(&path).unwrap();
    let mut changed = 0;
    let out: Vec<String> = text
        .lines()
        .map(|l| {
            let t: Vec<&str> = l.split_whitespace().collect();
            if l.starts_with('#') || t.len() != 10 {
                return l.to_string();
            }
            changed += 1;
            let neg = |s: &str| format!("{}", -s.parse::<f64>().unwrap());
            [t[0].to_string(), t[1].to_string(), neg(t[2]), neg(t[3]), neg(t[4])]
                .into_iter()
                .chain(t[5..].iter().map(|s| s.to_string()))
                .collect::<Vec<_>>()
                .join(" ")
        })
        .collect();
    assert!(changed >= 8, "only {changed} image lines in {}", path.display());
    std::fs::write(&path, out.join("\n") + "\n").unwrap();
}

#[test]
fn transposed_rotations_are_detected_and_undone() {
    let root = std::env::temp_dir().join(format!("cogeo_pose_check_{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&root);
    let (good, bad) = (root.join("good"), root.join("bad"));
    synth(&good, 48, 36, 1);
    synth(&bad, 48, 36, 1);
    conjugate_quaternions(&bad);
    let a = load(&good, "images", 1).unwrap();
    let b = load(&bad, "images", 1).unwrap();
    // a right model: points agree with the images, nothing is changed or said
    let ca = a.pose_check.as_ref().expect("synth points carry colors");
    assert!(ca.stored < 0.5 * ca.chance, "right poses: {ca:?}");
    assert!(!ca.transposed_rotations() && !ca.disagrees());
    assert!(a.warnings.is_empty(), "{:?}", a.warnings);
    // the slipped one: detected, said, and undone exactly
    let cb = b.pose_check.as_ref().unwrap();
    assert!(cb.transposed_rotations(), "{cb:?}");
    assert!(b.warnings.iter().any(|w| w.contains("transposed rotations")), "{:?}", b.warnings);
    for (x, y) in a.train.iter().chain(&a.test).zip(b.train.iter().chain(&b.test)) {
        for i in 0..3 {
            for j in 0..3 {
                assert!((x.camera.rotation[i][j] - y.camera.rotation[i][j]).abs() < 1e-6, "{}", x.camera.name);
            }
        }
        assert_eq!(x.camera.translation, y.camera.translation);
    }
    let _ = std::fs::remove_dir_all(&root);
}

#[test]
fn statue_capture_rotations_are_repaired() {
    let Some(dir) = common::shared_data("statue") else {
        return;
    };
    let d = load(&dir, "images_2", 4).unwrap();
    let c = d.pose_check.unwrap();
    // as stored, the points match the photos hardly better than unrelated pixels; transposed, they
    // match to about a quarter of that
    assert!(c.stored > 0.8 * c.chance && c.transposed < 0.35 * c.chance, "{c:?}");
    assert!(d.warnings.iter().any(|w| w.contains("transposed rotations")));
}
