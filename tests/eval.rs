//! The evaluation suite: metrics against closed forms and constructed cases, and `cogeo eval` on a
//! synth dataset (ground truth against itself, the with-object images as a "render" that removed
//! nothing, planted floaters, tiny LPIPS / FID networks built by the test).

mod common;

use cogeo::eval::{bbox_scores, floater_score, frechet_distance, full_scores, leftover_fraction, mask_scores};
use cogeo::scene::{Camera, GaussianScene};
use common::{onnx, run_cogeo};

/// FID of two sets whose sample covariances are diagonal by construction (samples mu +- s_k e_k):
/// |mu_a - mu_b|^2 + sum_k (a_k + b_k - 2 sqrt(a_k b_k)). Then the same sets rotated and embedded
/// in more dimensions than samples (as Inception features are): the distance is invariant.
#[test]
fn frechet_distance_matches_the_closed_form() {
    let d = 3;
    let set = |mu: [f64; 3], s: [f64; 3]| -> Vec<Vec<f64>> {
        let mut v = Vec::new();
        for k in 0..d {
            for sign in [-1.0, 1.0] {
                let mut x = mu.to_vec();
                x[k] += sign * s[k];
                v.push(x);
            }
        }
        v
    };
    let (mu_a, s_a, mu_b, s_b) = ([0.1, 0.2, -0.3], [0.5, 1.0, 2.0], [0.4, -0.1, 0.0], [1.5, 0.2, 0.7]);
    let (a, b) = (set(mu_a, s_a), set(mu_b, s_b));
    let n = (2 * d - 1) as f64;
    let mut expect: f64 = mu_a.iter().zip(&mu_b).map(|(p, q)| (p - q).powi(2)).sum();
    for k in 0..d {
        let (va, vb) = (2.0 * s_a[k] * s_a[k] / n, 2.0 * s_b[k] * s_b[k] / n);
        expect += va + vb - 2.0 * (va * vb).sqrt();
    }
    let got = frechet_distance(&a, &b).unwrap();
    assert!((got - expect).abs() < 1e-9 * expect.max(1.0), "FID {got} vs closed form {expect}");
    // an orthonormal embedding of R^3 into R^10 (Gram-Schmidt of fixed vectors): 6 samples < 10 dims
    let mut rng = cogeo::rng::Rng::new(4);
    let mut basis: Vec<Vec<f64>> = Vec::new();
    while basis.len() < 3 {
        let mut v: Vec<f64> = (0..10).map(|_| rng.normal()).collect();
        for u in &basis {
            let p: f64 = v.iter().zip(u).map(|(x, y)| x * y).sum();
            v.iter_mut().zip(u).for_each(|(x, y)| *x -= p * y);
        }
        let l = v.iter().map(|x| x * x).sum::<f64>().sqrt();
        basis.push(v.iter().map(|x| x / l).collect());
    }
    let embed = |s: &[Vec<f64>]| -> Vec<Vec<f64>> {
        s.iter().map(|x| (0..10).map(|j| (0..3).map(|k| x[k] * basis[k][j]).sum()).collect()).collect()
    };
    let got = frechet_distance(&embed(&a), &embed(&b)).unwrap();
    assert!((got - expect).abs() < 1e-9 * expect.max(1.0), "embedded FID {got} vs {expect}");
    assert!(frechet_distance(&a, &a).unwrap() < 1e-9);
    assert!(frechet_distance(&a[..1], &b).is_none());
}

/// Mask, bounding-box and full-image PSNR on a constructed error pattern.
#[test]
fn region_protocols_count_the_right_pixels() {
    let (w, h) = (20usize, 10usize);
    let hw = w * h;
    let gt = vec![0.5f32; 3 * hw];
    let mut render = gt.clone();
    // the mask: a 4x3 block at (5, 2); the error: 0.1 on the mask, 0.2 on one pixel inside its
    // bounding box but outside the mask, and 0.3 far away
    let mut mask = vec![false; hw];
    for y in 2..5 {
        for x in 5..9 {
            mask[y * w + x] = true;
        }
    }
    mask[2 * w + 5] = false; // the box stays (5..9) x (2..5): 12 pixels, 11 in the mask
    for c in 0..3 {
        for i in (0..hw).filter(|&i| mask[i]) {
            render[c * hw + i] += 0.1;
        }
        render[c * hw + 2 * w + 5] += 0.2;
        render[c * hw + 9 * w + 19] += 0.3;
    }
    let psnr = |se: f64, n: f64| 10.0 * (n / se).log10();
    let m = mask_scores(&render, &gt, &mask, w, h).unwrap();
    assert!((m.psnr - 20.0).abs() < 1e-3, "mask PSNR {}", m.psnr);
    assert_eq!(m.pixels, 11);
    let b = bbox_scores(&render, &gt, &mask, w, h).unwrap();
    assert!((b.psnr - psnr(11.0 * 0.01 + 0.04, 12.0)).abs() < 1e-3, "bbox PSNR {}", b.psnr);
    assert_eq!(b.pixels, 12);
    let f = full_scores(&render, &gt, w, h).unwrap();
    assert!((f.psnr - psnr(11.0 * 0.01 + 0.04 + 0.09, hw as f64)).abs() < 1e-3, "full PSNR {}", f.psnr);
    assert!(mask_scores(&render, &gt, &vec![false; hw], w, h).is_none());
    assert!(bbox_scores(&render, &gt, &vec![false; hw], w, h).is_none());
}

#[test]
fn leftover_counts_pixels_that_still_look_like_the_object() {
    // 4 pixels, 1 channel: object 1.0, background 0.0; render: 0.9 (leftover), 0.1, 0.5 (tie),
    // and one pixel where object and background agree (uninformative, not counted)
    let with_objects = [1.0, 1.0, 1.0, 0.3];
    let background = [0.0, 0.0, 0.0, 0.3];
    let render = [0.9, 0.1, 0.5, 0.9];
    let mask = [true; 4];
    let l = leftover_fraction(&render, &with_objects, &background, &mask, 0.05).unwrap();
    assert!((l - 1.0 / 3.0).abs() < 1e-12, "leftover {l}");
    assert_eq!(leftover_fraction(&render, &with_objects, &background, &[false; 4], 0.05), None);
}

/// A plane at z = 5 seen by two cameras; Gaussians on it pass, ones floating in front of it in
/// every view whose region they project into count with their opacity.
#[test]
fn floater_score_counts_gaussians_off_the_true_surface() {
    let cams = [
        Camera::look_at("a", 40, 30, 60.0, [0.0, 0.0, 0.0], [0.0, 0.0, 5.0], [0.0, -1.0, 0.0]),
        Camera::look_at("b", 40, 30, 60.0, [1.0, 0.0, 0.0], [1.0, 0.0, 5.0], [0.0, -1.0, 0.0]),
    ];
    let depth = vec![vec![5.0f32; 1200]; 2];
    let region = vec![vec![true; 1200]; 2];
    let mut scene = GaussianScene { sh_degree: 0, ..Default::default() };
    let mut push = |p: [f32; 3], logit: f32| scene.push(p, [-3.0; 3], [1.0, 0.0, 0.0, 0.0], logit, &[0.0; 3]);
    push([0.2, 0.1, 5.0], 0.0); // on the plane
    push([0.2, 0.1, 5.1], 0.0); // 2 % behind: within tau
    push([0.2, 0.1, 3.0], 2.0); // floating
    push([0.5, -0.2, 4.0], -1.0); // floating
    push([0.0, 0.0, -3.0], 5.0); // behind both cameras: never inside a region, not counted
    let (score, count) = floater_score(&scene, &cams, &depth, &region, 0.05);
    let sig = |x: f64| 1.0 / (1.0 + (-x).exp());
    assert_eq!(count, 2);
    assert!((score - sig(2.0) - sig(-1.0)).abs() < 1e-9, "score {score}");
}

fn metrics(path: &std::path::Path) -> serde_json::Value {
    serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap()
}

/// LPIPS: 2 * mean |a - b| (inputs are in [-1, 1]). FID features: channel means.
fn tiny_lpips() -> Vec<u8> {
    use onnx::{model, node, Io, Node};
    model(
        &[
            node("Sub", &["in0", "in1"], &["diff"]),
            node("Abs", &["diff"], &["abs"]),
            Node { op: "ReduceMean", inputs: &["abs"], outputs: &["distance"], ints: &[], int: &[("keepdims", 1)] },
        ],
        &[
            Io { name: "in0", dims: &[Some(1), Some(3), None, None] },
            Io { name: "in1", dims: &[Some(1), Some(3), None, None] },
        ],
        &[Io { name: "distance", dims: &[Some(1), Some(1), Some(1), Some(1)] }],
        &[],
    )
}

fn tiny_fid() -> Vec<u8> {
    use onnx::{model, Io, Node};
    model(
        &[Node {
            op: "ReduceMean",
            inputs: &["images"],
            outputs: &["features"],
            ints: &[("axes", &[2, 3])],
            int: &[("keepdims", 0)],
        }],
        &[Io { name: "images", dims: &[None, Some(3), Some(299), Some(299)] }],
        &[Io { name: "features", dims: &[None, Some(3)] }],
        &[],
    )
}

#[test]
fn eval_cli_on_a_synth_dataset() {
    let exe = env!("CARGO_BIN_EXE_cogeo");
    let root = std::env::temp_dir().join(format!("cogeo_eval_{}", std::process::id()));
    let path = |p: &str| root.join(p).to_string_lossy().into_owned();
    let data = path("data");
    run_cogeo(
        exe,
        &["synth", "--out", &data, "--width", "40", "--height", "30", "--views", "8", "--objects", "2", "--seed", "3"],
    );
    let (gt, masks, images) =
        (format!("{data}/gt_background"), format!("{data}/object_mask"), format!("{data}/images"));
    let eval = |renders: &str, out: &str, extra: &[&str]| {
        let out = path(out);
        run_cogeo(
            exe,
            &[&["eval", "--renders", renders, "--gt", &gt, "--masks", &masks, "--out", &out][..], extra].concat(),
        );
        metrics(std::path::Path::new(&out))
    };
    // the ground truth against itself: perfect scores, nothing left, no depth error
    let m = eval(&gt, "self.json", &["--data", &data, "--depth", &format!("{data}/depth_background")]);
    assert!(m["mask"]["psnr"].as_f64().unwrap() > 100.0);
    assert!((m["bbox"]["ssim"].as_f64().unwrap() - 1.0).abs() < 1e-9);
    assert_eq!(m["leftover"].as_f64().unwrap(), 0.0);
    assert!(m["depth"]["abs_rel"].as_f64().unwrap() < 1e-9);
    assert!(m["lpips"].as_str().unwrap().starts_with("not computed"));
    assert!(m["fid"].as_str().unwrap().starts_with("not computed"));
    assert!(m["floaters"].as_str().unwrap().starts_with("not computed"));
    assert_eq!(m["views"].as_array().unwrap().len(), 8);
    // the images with the objects: a removal that removed nothing
    let lpips = onnx::write(&root.join("models"), "lpips.onnx", &tiny_lpips());
    let fid = onnx::write(&root.join("models"), "fid.onnx", &tiny_fid());
    let m = eval(
        &images,
        "objects.json",
        &[
            "--data",
            &data,
            "--labels",
            "1",
            "--protocol",
            "bbox",
            "--lpips-model",
            &lpips.to_string_lossy(),
            "--lpips-min-side",
            "16",
            "--fid-model",
            &fid.to_string_lossy(),
            "--fid-scale",
            "1",
            "--fid-offset",
            "0",
        ],
    );
    assert_eq!(m["leftover"].as_f64().unwrap(), 1.0, "every informative object pixel is left over");
    assert_eq!(m["headline"]["psnr"], m["bbox"]["psnr"]);
    // the headline is the independent PSNR of the bounding-box crops, averaged over views
    let mut expect = Vec::new();
    let (mut lp_full, mut feats_r, mut feats_g) = (Vec::new(), Vec::new(), Vec::new());
    for v in m["views"].as_array().unwrap() {
        let name = v["name"].as_str().unwrap();
        let load = |dir: &str| image::open(format!("{dir}/{name}.png")).unwrap().to_rgb8();
        let (r, g) = (load(&images), load(&gt));
        let mask = image::open(format!("{masks}/{name}.png")).unwrap().to_luma8();
        let sel: Vec<(u32, u32)> =
            (0..30).flat_map(|y| (0..40).map(move |x| (x, y))).filter(|&(x, y)| mask.get_pixel(x, y)[0] == 1).collect();
        let lp = r
            .pixels()
            .zip(g.pixels())
            .flat_map(|(p, q)| (0..3).map(move |c| 2.0 * (p[c] as f64 - q[c] as f64).abs() / 255.0))
            .sum::<f64>()
            / (3.0 * 1200.0);
        assert!((v["lpips_full"].as_f64().unwrap() - lp).abs() < 1e-5);
        lp_full.push(lp);
        let to_planar = |im: &image::RgbImage| -> Vec<f32> {
            (0..3).flat_map(|c| im.pixels().map(move |p| p[c] as f32 / 255.0)).collect()
        };
        let chan_means = |x: &[f32]| -> Vec<f64> {
            let s = cogeo::image_ops::resize_bilinear(x, 40, 30, 3, 299, 299);
            (0..3)
                .map(|c| s[c * 299 * 299..(c + 1) * 299 * 299].iter().map(|&v| v as f64).sum::<f64>() / (299.0 * 299.0))
                .collect()
        };
        feats_r.push(chan_means(&to_planar(&r)));
        feats_g.push(chan_means(&to_planar(&g)));
        if sel.is_empty() {
            assert!(v["bbox"].is_null());
            continue;
        }
        let (x0, x1) = (sel.iter().map(|p| p.0).min().unwrap(), sel.iter().map(|p| p.0).max().unwrap() + 1);
        let (y0, y1) = (sel.iter().map(|p| p.1).min().unwrap(), sel.iter().map(|p| p.1).max().unwrap() + 1);
        let mut se = 0f64;
        for y in y0..y1 {
            for x in x0..x1 {
                for c in 0..3 {
                    se += ((r.get_pixel(x, y)[c] as f64 - g.get_pixel(x, y)[c] as f64) / 255.0).powi(2);
                }
            }
        }
        let n = 3.0 * ((x1 - x0) * (y1 - y0)) as f64;
        expect.push(10.0 * (n / se.max(1e-12 * n)).log10());
    }
    let expect = expect.iter().sum::<f64>() / expect.len() as f64;
    let got = m["bbox"]["psnr"].as_f64().unwrap();
    assert!((got - expect).abs() < 1e-4, "bbox PSNR {got} vs {expect}");
    let lp_mean = lp_full.iter().sum::<f64>() / lp_full.len() as f64;
    assert!((m["lpips"]["full"].as_f64().unwrap() - lp_mean).abs() < 1e-5);
    let fid_expect = frechet_distance(&feats_r, &feats_g).unwrap();
    let fid_got = m["fid"]["value"].as_f64().unwrap();
    assert!((fid_got - fid_expect).abs() < 1e-6 * fid_expect.max(1e-3), "FID {fid_got} vs {fid_expect}");
    assert!(fid_got > 0.0);

    // floaters: a Gaussian on the true background behind object 1 and one in front of it
    let ds = cogeo::scene::dataset::load(std::path::Path::new(&data), "images", 1).unwrap();
    let cam = ds.train.iter().map(|v| &v.camera).find(|c| {
        let mask = image::open(format!("{masks}/{}.png", c.name)).unwrap().to_luma8();
        mask.pixels().any(|p| p[0] == 1)
    });
    let cam = cam.expect("object 1 is visible in a training view");
    let mask = image::open(format!("{masks}/{}.png", cam.name)).unwrap().to_luma8();
    let (x, y) =
        (0..30u32).flat_map(|y| (0..40u32).map(move |x| (x, y))).find(|&(x, y)| mask.get_pixel(x, y)[0] == 1).unwrap();
    let (_, _, depth) =
        cogeo::io::read_exr_channel(&root.join(format!("data/depth_background/{}.exr", cam.name)), None).unwrap();
    let z = depth[(y * 40 + x) as usize] as f64;
    let world = |z: f64| cam.pixel_point(x as usize, y as usize, z).map(|v| v as f32);
    let mut scene = GaussianScene { sh_degree: 0, ..Default::default() };
    for (p, logit) in [(world(z), 1.0f32), (world(0.5 * z), 1.0)] {
        scene.push(p, [-4.0; 3], [1.0, 0.0, 0.0, 0.0], logit, &[0.0; 3]);
    }
    let ply = root.join("floaters.ply");
    cogeo::scene::ply::write_ply(&scene, &ply).unwrap();
    let m = eval(&gt, "floaters.json", &["--data", &data, "--labels", "1", "--scene", &ply.to_string_lossy()]);
    assert_eq!(m["floaters"]["gaussians"].as_u64().unwrap(), 1);
    assert!((m["floaters"]["score"].as_f64().unwrap() - 1.0 / (1.0 + (-1.0f64).exp())).abs() < 1e-9);

    // a render without a mask is an error that names the folder and the view
    std::fs::create_dir_all(root.join("extra")).unwrap();
    std::fs::copy(format!("{gt}/{}.png", cam.name), root.join("extra/nomask.png")).unwrap();
    let out = std::process::Command::new(exe)
        .args([
            "eval",
            "--renders",
            &path("extra"),
            "--gt",
            &path("extra"),
            "--masks",
            &masks,
            "--out",
            &path("x.json"),
        ])
        .output()
        .unwrap();
    assert!(!out.status.success());
    assert!(String::from_utf8_lossy(&out.stderr).contains("no mask for render nomask"));
    std::fs::remove_dir_all(&root).ok();
}

/// `synth --gt-without 1` ray-casts the views without object 1 only: object 2 stays exactly where
/// it was visible, object 1's pixels change, and `ground_truth` resolves which truth is exact.
#[test]
fn synth_writes_the_ground_truth_of_removing_a_subset() {
    let exe = env!("CARGO_BIN_EXE_cogeo");
    let root = std::env::temp_dir().join(format!("cogeo_gt_subset_{}", std::process::id()));
    let data = root.join("data");
    let d = data.to_string_lossy().into_owned();
    run_cogeo(
        exe,
        &[
            "synth",
            "--out",
            &d,
            "--width",
            "40",
            "--height",
            "30",
            "--views",
            "8",
            "--objects",
            "2",
            "--seed",
            "3",
            "--gt-without",
            "1",
        ],
    );
    let truth = cogeo::synth::ground_truth(&data, &[1]);
    assert!(truth.exact && truth.images.ends_with("without_1/images"));
    assert!(cogeo::synth::ground_truth(&data, &[2, 1]).exact, "removing every object: gt_background is exact");
    assert!(!cogeo::synth::ground_truth(&data, &[2]).exact, "no truth was written for removing object 2 alone");
    let (mut kept, mut changed) = (0, 0);
    for i in 0..8 {
        let name = format!("view_{i:03}");
        let full = image::open(data.join(format!("images/{name}.png"))).unwrap().to_rgb8();
        let without = image::open(truth.images.join(format!("{name}.png"))).unwrap().to_rgb8();
        let mask = image::open(data.join(format!("object_mask/{name}.png"))).unwrap().to_luma8();
        for (p, m) in mask.pixels().enumerate() {
            let (x, y) = (p as u32 % 40, p as u32 / 40);
            match m[0] {
                2 => {
                    assert_eq!(full.get_pixel(x, y), without.get_pixel(x, y), "{name}: object 2 changed at ({x}, {y})");
                    kept += 1;
                }
                1 => changed += (full.get_pixel(x, y) != without.get_pixel(x, y)) as usize,
                _ => {}
            }
        }
        assert!(truth.unseen.join(format!("{name}.png")).exists() && truth.depth.join(format!("{name}.exr")).exists());
    }
    assert!(kept > 0 && changed > 0, "kept {kept}, changed {changed}");
    std::fs::remove_dir_all(&root).ok();
}

/// The real LPIPS network (AlexNet, v0.1) as published, fed by names read from the model: identical
/// images are at distance 0, a blurred copy of a photo is clearly farther, and the masked variant
/// only sees the pixels inside the mask.
#[test]
fn real_lpips_network_scores_a_blurred_photo() {
    let Some(photo) = common::shared_data("statue/images_2/IMG_2707.png") else {
        return;
    };
    let Some(model) = common::shared("models/lpips_alex_v0.1.onnx") else {
        return;
    };
    use cogeo::eval::models::{Lpips, NetworkInput};
    let mut lpips = Lpips::load(&model, NetworkInput::lpips_default(), 32).unwrap();
    let img = image::open(&photo).unwrap().resize_exact(128, 96, image::imageops::FilterType::Triangle).to_rgb8();
    let (w, h) = (128usize, 96usize);
    let planar: Vec<f32> = (0..3).flat_map(|c| img.pixels().map(move |p| p[c] as f32 / 255.0)).collect();
    // separable Gaussian blur, sigma 2, clamped edges
    let k: Vec<f32> = (-6..=6).map(|i: i32| (-(i * i) as f32 / 8.0).exp()).collect();
    let ks: f32 = k.iter().sum();
    let blur_1d = |src: &[f32], dx: usize, dy: usize| -> Vec<f32> {
        let mut out = vec![0f32; src.len()];
        for c in 0..3 {
            for y in 0..h {
                for x in 0..w {
                    let mut acc = 0f32;
                    for (j, kv) in k.iter().enumerate() {
                        let o = j as i64 - 6;
                        let sx = (x as i64 + o * dx as i64).clamp(0, w as i64 - 1) as usize;
                        let sy = (y as i64 + o * dy as i64).clamp(0, h as i64 - 1) as usize;
                        acc += kv * src[c * w * h + sy * w + sx];
                    }
                    out[c * w * h + y * w + x] = acc / ks;
                }
            }
        }
        out
    };
    let blurred = blur_1d(&blur_1d(&planar, 1, 0), 0, 1);
    let same = lpips.distance(&planar, &planar, w, h).unwrap();
    let blur = lpips.distance(&blurred, &planar, w, h).unwrap();
    eprintln!("LPIPS: d(x, x) = {same}, d(blur(x), x) = {blur}");
    assert!(same.abs() < 1e-6, "d(x, x) = {same}");
    assert!(blur > 0.05, "d(blur(x), x) = {blur}");
    // masked: a box-shaped hole; the blurred copy pasted inside it only
    let mask: Vec<bool> = (0..w * h).map(|i| (40..80).contains(&(i % w)) && (30..70).contains(&(i / w))).collect();
    let masked = lpips.masked(&blurred, &planar, &mask, w, h).unwrap().unwrap();
    let bbox = lpips.bbox(&blurred, &planar, &mask, w, h).unwrap().unwrap();
    assert!(masked > 0.05, "masked LPIPS of a blurred hole {masked}");
    assert!((masked - bbox).abs() < 1e-6, "a box-shaped mask is its own bounding box: {masked} vs {bbox}");
    let elsewhere = lpips.masked(&planar, &planar, &mask, w, h).unwrap().unwrap();
    assert!(elsewhere.abs() < 1e-6, "a hole filled with the truth scores {elsewhere}");
    // a small mask is scored on a crop grown to the network's 32-pixel minimum, still inside the image
    let dot: Vec<bool> = (0..w * h).map(|i| i % w >= 120 && i / w >= 90).collect();
    let r = lpips.region_box(&dot, w, h).unwrap();
    assert_eq!((r.x0, r.x1, r.y0, r.y1), (96, 128, 64, 96));
    assert!(lpips.masked(&blurred, &planar, &dot, w, h).unwrap().unwrap() > 0.0);
}

/// The floater score's true surface is the scene after the removal: where the synth wrote the
/// configuration without the removed objects only (`--gt-without`), a Gaussian on a kept object
/// that stands behind a removed one is on the surface, not a floater; measured against the empty
/// room it would be one.
#[test]
fn a_kept_object_behind_a_removed_one_is_not_a_floater() {
    let exe = env!("CARGO_BIN_EXE_cogeo");
    let root = common::scratch_dir("eval-kept-object");
    let path = |p: &str| root.join(p).to_string_lossy().into_owned();
    let data = path("data");
    let (w, h) = (64u32, 48u32);
    run_cogeo(
        exe,
        &[
            "synth",
            "--out",
            &data,
            "--width",
            "64",
            "--height",
            "48",
            "--views",
            "12",
            "--objects",
            "3",
            "--seed",
            "5",
            "--gt-without",
            "1",
        ],
    );
    let ds = cogeo::scene::dataset::load(std::path::Path::new(&data), "images", 1).unwrap();
    let exr = |sub: &str, name: &str| {
        cogeo::io::read_exr_channel(&root.join(format!("data/{sub}/{name}.exr")), None).unwrap().2
    };
    // a pixel of object 1's silhouette where a kept object is what the view sees once object 1 is
    // gone (of 3 objects, seed 5 has views where one stands 10 % or more in front of the room)
    let found = ds.train.iter().map(|v| &v.camera).find_map(|c| {
        let mask = image::open(root.join(format!("data/object_mask/{}.png", c.name))).unwrap().to_luma8();
        let (kept, room) = (exr("without_1/depth", &c.name), exr("depth_background", &c.name));
        (0..(w * h) as usize)
            .find(|&i| mask.as_raw()[i] == 1 && kept[i] > 0.0 && kept[i] < 0.9 * room[i])
            .map(|i| (c.clone(), i, kept[i] as f64))
    });
    let (cam, i, z) = found.expect("a kept object stands behind object 1 in some view of this scene");
    let on_kept = cam.pixel_point(i % w as usize, i / w as usize, z).map(|v| v as f32);
    let mut scene = GaussianScene { sh_degree: 0, ..Default::default() };
    scene.push(on_kept, [-4.0; 3], [1.0, 0.0, 0.0, 0.0], 0.0, &[0.0; 3]);
    let ply = root.join("kept.ply");
    cogeo::scene::ply::write_ply(&scene, &ply).unwrap();
    let gt = format!("{data}/without_1/images");
    let out = path("kept.json");
    let masks = format!("{data}/object_mask");
    let args = ["eval", "--renders", &gt, "--gt", &gt, "--masks", &masks, "--labels", "1", "--data", &data];
    run_cogeo(exe, &[&args[..], &["--scene", &ply.to_string_lossy(), "--out", &out]].concat());
    let m: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&out).unwrap()).unwrap();
    assert_eq!(m["floaters"]["gaussians"].as_u64().unwrap(), 0, "{}", m["floaters"]);
    // the same point against the empty room's depth, as the score measured it before
    let cams: Vec<Camera> = ds.train.iter().chain(&ds.test).map(|v| v.camera.clone()).collect();
    let room: Vec<Vec<f32>> = cams.iter().map(|c| exr("depth_background", &c.name)).collect();
    let regions: Vec<Vec<bool>> = cams
        .iter()
        .map(|c| {
            let mask = image::open(root.join(format!("data/object_mask/{}.png", c.name))).unwrap().to_luma8();
            mask.as_raw().iter().map(|&l| l == 1).collect()
        })
        .collect();
    assert_eq!(floater_score(&scene, &cams, &room, &regions, 0.05).1, 1);
    std::fs::remove_dir_all(&root).ok();
}
