//! Undistortion on load (scene/undistort.rs): a synth capture ray-cast through a lens, loaded as a
//! user's COLMAP capture would be, against the same views ray-cast through the pinhole camera the
//! loader chose.

mod common;

use cogeo::scene::dataset::load;
use cogeo::synth::{generate, render_view, Rig, SynthConfig};

fn psnr_inside(a: &[f32], b: &[f32], w: usize, h: usize, border: usize) -> f64 {
    let mut se = 0.0f64;
    let mut n = 0usize;
    for c in 0..3 {
        for y in border..h - border {
            for x in border..w - border {
                let i = c * w * h + y * w + x;
                se += ((a[i] - b[i]) as f64).powi(2);
                n += 1;
            }
        }
    }
    10.0 * (n as f64 / se).log10()
}

/// A forward-facing synth room with two objects, `views` views of `width` x `height`.
fn room(width: u32, height: u32, views: usize, seed: u64, supersample: u32, distortion: [f64; 4]) -> SynthConfig {
    SynthConfig {
        width,
        height,
        views,
        objects: 2,
        rig: Rig::Forward,
        seed,
        points_per_view: (width * height / 24) as usize,
        gt_without: Vec::new(),
        supersample,
        distortion,
        exposure_jitter: 0.0,
    }
}

#[test]
fn opencv_photos_undistort_to_the_pinhole_views_at_35_db() {
    let dir = common::scratch_dir("undistort_opencv");
    let data = dir.join("data");
    // 640x480: the synth's checkerboards alias at 4x4 rays per pixel, and resampling aliased
    // texture by a fraction of a pixel costs decibels by itself (33 dB at 160x120, 34-35 at 320x240
    // even for k1 = 0.033; the lens's own share is under 1 dB)
    // a wide phone lens's barrel distortion: the corners move by about 50 pixels
    let cfg = room(640, 480, 3, 4, 4, [-0.08, 0.015, 0.001, -0.0015]);
    let objects = generate(&cfg, &data, &|_, _| {}).unwrap();
    let model = cogeo::scene::colmap::read_colmap(&data).unwrap();
    assert!(!model.lenses[0].is_pinhole());
    let ds = load(&data, "images", 1).unwrap();
    let mut worst = f64::INFINITY;
    for view in ds.train.iter().chain(&ds.test) {
        let cam = &view.camera;
        assert!(view.undistortion.is_some(), "{}: not undistorted", cam.name);
        // COLMAP's choice: the focal lengths kept, the image cropped to what the photo saw
        assert_eq!((cam.fx, cam.fy), (model.cameras[0].fx, model.cameras[0].fy));
        // barrel distortion squeezed the photo's edges: the pinhole image is a little larger
        assert!((641..700).contains(&cam.width) && (481..530).contains(&cam.height), "{}x{}", cam.width, cam.height);
        let truth = render_view(cam, &objects, cfg.seed, cfg.supersample);
        let p = psnr_inside(&view.image, &truth.rgb, cam.width as usize, cam.height as usize, 8);
        worst = worst.min(p);
    }
    eprintln!("undistorted photos against the pinhole ray-cast: worst view {worst:.2} dB");
    assert!(worst >= 35.0, "worst view {worst:.2} dB");
    // what ignoring the lens trains against: the photo read as if its camera were a pinhole
    let cam = &model.cameras[1];
    let raw = cogeo::scene::dataset::load_rgb(&data.join(format!("images/{}.png", cam.name))).unwrap();
    let truth = render_view(cam, &objects, cfg.seed, cfg.supersample);
    let ignored = psnr_inside(&raw.2, &truth.rgb, 640, 480, 8);
    eprintln!("the same view with the distortion ignored: {ignored:.2} dB");
    assert!(ignored < worst - 10.0, "ignoring the lens gives {ignored:.2} dB");
}

#[test]
fn masks_follow_their_photos_into_the_pinhole_frame() {
    let dir = common::scratch_dir("undistort_masks");
    let data = dir.join("data");
    let cfg = room(96, 72, 9, 6, 1, [-0.15, 0.02, 0.0, 0.0]);
    let objects = generate(&cfg, &data, &|_, _| {}).unwrap();
    let ds = load(&data, "images", 1).unwrap();
    let views: Vec<_> = ds.train.iter().collect();
    let maps = cogeo::tag::labels::load(&data.join("object_mask"), &views).unwrap();
    // the instance map drawn on the distorted photo, undistorted, against the pinhole ray-cast's
    let (mut agree, mut total) = (0usize, 0usize);
    for (view, map) in views.iter().zip(&maps.maps) {
        let truth = render_view(&view.camera, &objects, cfg.seed, 1);
        for (a, b) in map.iter().zip(&truth.labels) {
            agree += (a == b) as usize;
            total += 1;
        }
    }
    let share = agree as f64 / total as f64;
    // the same masks read as if the photos were pinhole images
    let model = cogeo::scene::colmap::read_colmap(&data).unwrap();
    let (mut agree_raw, mut total_raw) = (0usize, 0usize);
    for cam in model.cameras.iter().filter(|c| ds.train.iter().any(|v| v.camera.name == c.name)) {
        let stored = cogeo::tag::labels::decode_mask(
            &std::fs::read(data.join(format!("object_mask/{}.png", cam.name))).unwrap(),
            "mask",
            cam.width,
            cam.height,
        )
        .unwrap();
        let pinhole_truth = render_view(
            &cogeo::scene::undistort::pinhole_camera(cam, model.lenses[0], "t").unwrap(),
            &objects,
            cfg.seed,
            1,
        );
        // the ignored reading pairs the stored mask, resized, with the pinhole camera's pixels
        let resized = cogeo::image_ops::resize_nearest_u8(
            &stored,
            cam.width,
            cam.height,
            ds.train[0].camera.width,
            ds.train[0].camera.height,
        );
        for (a, b) in resized.iter().zip(&pinhole_truth.labels) {
            agree_raw += (a == b) as usize;
            total_raw += 1;
        }
    }
    let raw_share = agree_raw as f64 / total_raw as f64;
    eprintln!(
        "undistorted masks agree with the pinhole labels on {:.2} % of pixels, the stored ones on {:.2} %",
        100.0 * share,
        100.0 * raw_share
    );
    assert!(share > 0.99, "{share}");
    assert!(1.0 - share < 0.5 * (1.0 - raw_share), "undistorted {share}, ignored {raw_share}");
}

/// Trains `data` as `cogeo train` would (SH degree 1, no densification) and returns the held-out
/// PSNR.
fn train_held_out_psnr(gpu: &cogeo::gpu::Gpu, data: &std::path::Path, iters: u32) -> f64 {
    use cogeo::train::trainer::{init_from_points, TrainConfig, Trainer};
    let ds = load(data, "images", 1).unwrap();
    let scene = init_from_points(&ds.points, 1).unwrap();
    let cfg = TrainConfig { iters, sh_degree: 1, densify: false, seed: 3, ..Default::default() };
    let mut t = Trainer::new(gpu, &ds, &scene, cfg).unwrap();
    while t.step < iters {
        t.iterate(&ds, false).unwrap();
    }
    t.evaluate(&ds.test).unwrap().psnr
}

#[test]
fn training_on_the_distorted_capture_matches_the_pinhole_capture() {
    let gpu = common::gpu();
    let dir = common::scratch_dir("undistort_train");
    let mut cfg = room(96, 72, 16, 8, 4, [0.0; 4]);
    generate(&cfg, &dir.join("pinhole"), &|_, _| {}).unwrap();
    cfg.distortion = [-0.1, 0.02, 0.001, -0.0015];
    generate(&cfg, &dir.join("opencv"), &|_, _| {}).unwrap();
    let pinhole = train_held_out_psnr(&gpu, &dir.join("pinhole"), 300);
    let undistorted = train_held_out_psnr(&gpu, &dir.join("opencv"), 300);
    eprintln!(
        "held-out PSNR after 300 iterations: pinhole capture {pinhole:.2} dB, OPENCV capture {undistorted:.2} dB"
    );
    // each scored in its own frame: the undistorted views see a little more or less of the room
    // than the pinhole ones, so the lens may not cost more than 0.3 dB but may come out ahead
    assert!(undistorted >= pinhole - 0.3, "pinhole {pinhole:.2} dB, undistorted {undistorted:.2} dB");
}

/// The removal's ground-truth scoring of an undistorted capture: the synth's object-free truth,
/// stored in the photos' distorted frame, is undistorted like the photos, so a render in the
/// pinhole frame that equals the truth scores high inside the objects' silhouettes (which are
/// undistorted by the nearest pixel too), and the same render against the truth left distorted
/// is refused for its size.
#[test]
fn ground_truth_of_an_undistorted_capture_is_scored_in_the_pinhole_frame() {
    let dir = common::scratch_dir("undistort_ground_truth");
    let data = dir.join("data");
    let cfg = room(320, 240, 9, 4, 4, [-0.08, 0.015, 0.001, -0.0015]);
    let objects = generate(&cfg, &data, &|_, _| {}).unwrap();
    let labels: Vec<u8> = objects.iter().map(|o| o.label).collect();
    let ds = load(&data, "images", 1).unwrap();
    let cameras: Vec<_> = ds.test.iter().map(|v| v.camera.clone()).collect();
    let frames: Vec<_> = ds.test.iter().map(|v| v.undistortion.as_deref()).collect();
    assert!(!cameras.is_empty() && frames.iter().all(|f| f.is_some()));
    // the perfect removal: the room ray-cast without the objects through the pinhole cameras
    let renders: Vec<Vec<f32>> = cameras.iter().map(|c| render_view(c, &[], cfg.seed, cfg.supersample).rgb).collect();
    let m = cogeo::eval::synth_metrics(&data, &cameras, &frames, &renders, &labels).unwrap().unwrap();
    eprintln!("a perfect removal scored against the undistorted truth: masked PSNR {:.2} dB", m.masked_psnr);
    assert!(m.views == cameras.len() && m.masked_psnr > 30.0, "{m:?}");
    let unframed = vec![None; cameras.len()];
    assert!(cogeo::eval::synth_metrics(&data, &cameras, &unframed, &renders, &labels).is_err());
    // cogeo eval on the same renders written out: the truth, masks and unseen masks undistorted
    let folder = dir.join("renders");
    std::fs::create_dir_all(&folder).unwrap();
    for (c, r) in cameras.iter().zip(&renders) {
        cogeo::io::write_png_rgb(&folder.join(format!("{}.png", c.name)), c.width, c.height, r).unwrap();
    }
    let thresholds = cogeo::eval::folder::SynthThresholds::default();
    let cfg = cogeo::eval::folder::EvalConfig {
        renders: folder,
        gt: data.join("gt_background"),
        masks: data.join("object_mask"),
        labels: Vec::new(),
        protocol: cogeo::eval::folder::Protocol::Mask,
        data: Some(data.clone()),
        depth: None,
        scene: None,
        tau: thresholds.tau,
        leftover_margin: thresholds.leftover_margin,
        lpips: None,
        lpips_input: cogeo::eval::models::NetworkInput::lpips_default(),
        lpips_min_side: 32,
        fid: None,
        fid_input: cogeo::eval::models::NetworkInput::fid_default(),
        fit_exposure: false,
    };
    let metrics = cogeo::eval::folder::evaluate(&cfg).unwrap();
    let (mask, leftover) = (metrics["mask"]["psnr"].as_f64().unwrap(), metrics["leftover"].as_f64().unwrap());
    eprintln!("cogeo eval of the same renders: masked PSNR {mask:.2} dB, leftover {leftover:.3}");
    assert!((mask - m.masked_psnr).abs() < 0.5 && leftover < 0.02, "{metrics}");
}

/// Held-out PSNR of training `ds` (SH degree 1, no densification), each training view's loss
/// weighted by `masks` where given, every held-out view scored against the pinhole ray-cast of its
/// own camera over `score_mask`'s pixels (all but an 8-pixel border when None).
fn trained_held_out(
    gpu: &cogeo::gpu::Gpu,
    ds: &cogeo::scene::dataset::Dataset,
    masks: Option<Vec<Vec<f32>>>,
    score_masks: Option<Vec<Vec<f32>>>,
    truth: &dyn Fn(&cogeo::scene::Camera) -> Vec<f32>,
    iters: u32,
) -> f64 {
    use cogeo::render::render_rgb;
    use cogeo::train::trainer::{init_from_points, TrainConfig, Trainer};
    let scene = init_from_points(&ds.points, 1).unwrap();
    let cfg = TrainConfig { iters, sh_degree: 1, densify: false, seed: 3, ..Default::default() };
    let mut t = Trainer::new(gpu, ds, &scene, cfg).unwrap();
    if let Some(m) = masks {
        t.set_loss_masks(&m).unwrap();
    }
    while t.step < iters {
        t.iterate(ds, false).unwrap();
    }
    let trained = t.download_scene().unwrap();
    let cameras: Vec<_> = ds.test.iter().map(|v| v.camera.clone()).collect();
    let renders = render_rgb(gpu, &trained, &cameras, [0.0; 3]).unwrap();
    let mut total = 0.0;
    for (k, (cam, render)) in cameras.iter().zip(&renders).enumerate() {
        let (w, h) = (cam.width as usize, cam.height as usize);
        let truth = truth(cam);
        let keep: Vec<bool> = match &score_masks {
            Some(m) => m[k].iter().map(|&v| v > 0.5).collect(),
            None => (0..w * h).map(|p| (8..w - 8).contains(&(p % w)) && (8..h - 8).contains(&(p / w))).collect(),
        };
        let clamped: Vec<f32> = render.iter().map(|v| v.clamp(0.0, 1.0)).collect();
        total += cogeo::eval::masked_psnr(&clamped, &truth, &keep).unwrap();
    }
    total / cameras.len() as f64
}

/// `mask` (1 / 0, `w` wide) where every pixel within `r` (a square) is 1 and inside the image.
fn eroded(mask: &[f32], w: usize, r: usize) -> Vec<f32> {
    let h = mask.len() / w;
    (0..mask.len())
        .map(|p| {
            let (x, y) = (p % w, p / w);
            let clear = x >= r
                && y >= r
                && x + r < w
                && y + r < h
                && (y - r..=y + r).all(|yy| (x - r..=x + r).all(|xx| mask[yy * w + xx] > 0.5));
            if clear {
                1.0
            } else {
                0.0
            }
        })
        .collect()
}

/// The other choice of pinhole, measured: the whole photo's frame (black corners) with a
/// valid-pixel mask in the loss, against COLMAP's crop, on the same barrel-distorted capture, each
/// scored against the pinhole ray-cast of its own frame over the pixels its photo saw, 8 pixels
/// clear of where its image or photo ends. They train alike (crop 25.10 dB, whole frame 25.16 dB
/// when this was written), so the loader keeps the crop: no later stage then needs a mask.
#[test]
fn cropped_frame_trains_no_worse_than_the_whole_frame_with_a_valid_mask() {
    let gpu = common::gpu();
    let dir = common::scratch_dir("undistort_whole_frame");
    let data = dir.join("opencv");
    let cfg = room(96, 72, 16, 8, 4, [-0.1, 0.02, 0.001, -0.0015]);
    let objects = generate(&cfg, &data, &|_, _| {}).unwrap();
    let truth = |cam: &cogeo::scene::Camera| render_view(cam, &objects, cfg.seed, cfg.supersample).rgb;
    let iters = 300;
    let cropped = load(&data, "images", 1).unwrap();
    let crop_psnr = trained_held_out(&gpu, &cropped, None, None, &truth, iters);
    // the same capture undistorted into whole frames
    let mut whole = load(&data, "images", 1).unwrap();
    let mut masks = Vec::new();
    let mut test_masks = Vec::new();
    for (k, view) in whole.train.iter_mut().chain(whole.test.iter_mut()).enumerate() {
        let frame = view.undistortion.as_ref().unwrap().whole_frame("test").unwrap();
        let photo = cogeo::scene::dataset::load_rgb(&view.path).unwrap().2;
        view.image = frame.rgb(&photo);
        view.camera = frame.pinhole.clone();
        let valid = frame.valid_mask();
        assert!(valid.contains(&0.0), "the whole frame has no corner beyond the photo");
        if k < cropped.train.len() {
            masks.push(valid);
        } else {
            // scored as the crop is: 8 pixels clear of where the photo ends
            test_masks.push(eroded(&valid, frame.pinhole.width as usize, 8));
        }
    }
    let whole_psnr = trained_held_out(&gpu, &whole, Some(masks), Some(test_masks), &truth, iters);
    eprintln!(
        "held-out PSNR after {iters} iterations: cropped frame {crop_psnr:.2} dB, whole frame with a valid mask {whole_psnr:.2} dB"
    );
    assert!(crop_psnr >= whole_psnr - 0.3, "crop {crop_psnr:.2} dB, whole frame {whole_psnr:.2} dB");
}
