//! `cogeo synth --composite-into`: objects composited into a capture whose geometry is known
//! exactly. The capture is a floor of flat Gaussians on z = 0, photographed by rendering it, with
//! sparse points on the floor; the composite must find that plane, stand its objects on it, draw
//! them only where they are (everything else stays the photo, which is the ground truth), and
//! write the subset ground truth with the kept object only.

mod common;

use cogeo::rng::Rng;
use cogeo::scene::{logit, GaussianScene};
use cogeo::synth::composite::{composite, CompositeConfig};
use cogeo::synth::{make_cameras, qvec_from_rotation, Rig, SynthConfig};
use std::path::Path;

/// A 6 x 6 floor of thin Gaussians on z = 0 with random colors.
fn floor() -> GaussianScene {
    let mut rng = Rng::new(11);
    let mut s = GaussianScene { sh_degree: 0, ..Default::default() };
    let n = 80;
    for i in 0..n {
        for j in 0..n {
            let (x, y) = (-3.0 + 6.0 * (i as f64 + 0.5) / n as f64, -3.0 + 6.0 * (j as f64 + 0.5) / n as f64);
            s.means.push([x as f32, y as f32, 0.0]);
            s.normals.push([0.0; 3]);
            s.log_scales.push([(0.05f32).ln(), (0.05f32).ln(), (0.002f32).ln()]);
            s.quats.push([1.0, 0.0, 0.0, 0.0]);
            s.opacity_logits.push(logit(0.98));
            for _ in 0..3 {
                s.sh.push(((rng.range(0.2, 0.8) - 0.5) / 0.282_094_79) as f32);
            }
        }
    }
    s
}

/// Writes the capture: photos rendered from the floor, a COLMAP text model with one PINHOLE
/// camera per image, and sparse points on the floor.
fn write_capture(gpu: &cogeo::gpu::Gpu, dir: &Path, scene: &GaussianScene) -> Vec<cogeo::scene::Camera> {
    let cfg = SynthConfig {
        width: 96,
        height: 72,
        views: 12,
        objects: 1,
        rig: Rig::Forward,
        seed: 1,
        points_per_view: 0,
        gt_without: vec![],
        supersample: 1,
        distortion: [0.0; 4],
        exposure_jitter: 0.0,
    };
    let cameras = make_cameras(&cfg);
    std::fs::create_dir_all(dir.join("images")).unwrap();
    std::fs::create_dir_all(dir.join("sparse/0")).unwrap();
    let photos = cogeo::render::render_rgb(gpu, scene, &cameras, [0.5; 3]).unwrap();
    let (mut cams, mut images) = (String::new(), String::new());
    for (i, (c, photo)) in cameras.iter().zip(&photos).enumerate() {
        cogeo::io::write_png_rgb(&dir.join(format!("images/{}.png", c.name)), c.width, c.height, photo).unwrap();
        cams += &format!("{} PINHOLE {} {} {} {} {} {}\n", i + 1, c.width, c.height, c.fx, c.fy, c.cx, c.cy);
        let (q, t) = (qvec_from_rotation(&c.rotation), c.translation);
        images += &format!(
            "{} {} {} {} {} {} {} {} {} {}.png\n\n",
            i + 1,
            q[0],
            q[1],
            q[2],
            q[3],
            t[0],
            t[1],
            t[2],
            i + 1,
            c.name
        );
    }
    let mut rng = Rng::new(5);
    let points: String = (0..3000)
        .map(|k| format!("{} {} {} 0 128 128 128 0.5\n", k + 1, rng.range(-2.8, 2.8), rng.range(-2.8, 2.8)))
        .collect();
    std::fs::write(dir.join("sparse/0/cameras.txt"), cams).unwrap();
    std::fs::write(dir.join("sparse/0/images.txt"), images).unwrap();
    std::fs::write(dir.join("sparse/0/points3D.txt"), points).unwrap();
    cameras
}

fn rgb(path: &Path) -> (u32, u32, Vec<f32>) {
    cogeo::scene::dataset::load_rgb(path).unwrap()
}

fn gray(path: &Path) -> Vec<u8> {
    image::open(path).unwrap().to_luma8().into_raw()
}

#[test]
fn objects_stand_on_the_capture_plane_and_only_their_pixels_change() {
    let gpu = common::gpu();
    let root = common::scratch_dir("composite_floor");
    let scene = floor();
    let cameras = write_capture(&gpu, &root.join("capture"), &scene);
    cogeo::scene::ply::write_ply(&scene, &root.join("floor.ply")).unwrap();
    let cfg = CompositeConfig {
        capture: root.join("capture"),
        images: "images".into(),
        downscale: 1,
        scene: root.join("floor.ply"),
        objects: 2,
        seed: 3,
        supersample: 2,
        gt_without: vec![1],
        object_size: 0.06,
        contact_shadow: 0.0,
        points: 2000,
        placement: None,
    };
    let out = root.join("bench");
    let summary = composite(&gpu, &cfg, &out, &|_, _, _| {}).unwrap();

    // the plane is the floor, and each object's base lies on it
    let g = &summary.ground;
    assert!(g.n[2] > 0.9999, "ground normal {:?} is not the floor's +z", g.n);
    assert!(g.origin[2].abs() < 1e-3, "ground origin {:?} is off the floor", g.origin);
    for o in &summary.objects {
        let half_height = if o.shape == cogeo::synth::Shape::Box { o.size } else { 1.2 * o.size };
        let base = g.to_world([o.center[0], o.center[1], o.center[2] - half_height]);
        assert!(base[2].abs() < 2e-3, "object {} stands at height {} instead of on the floor", o.label, base[2]);
    }

    let mut object_pixels = [0usize; 2];
    for cam in &cameras {
        let name = &cam.name;
        let (w, h, composited) = rgb(&out.join(format!("images/{name}.png")));
        let (_, _, photo) = rgb(&out.join(format!("gt_background/{name}.png")));
        let (_, _, original) = rgb(&root.join(format!("capture/images/{name}.png")));
        let (_, _, kept_only) = rgb(&out.join(format!("without_1/images/{name}.png")));
        let labels = gray(&out.join(format!("object_mask/{name}.png")));
        let (w, h) = (w as usize, h as usize);
        // the ground truth is the photo as the capture holds it
        assert_eq!(photo, original, "{name}: gt_background differs from the capture's photo");
        // a pixel away from every object pixel (one-pixel ring: supersampled edges) keeps the photo
        let near_object = |p: usize, which: &dyn Fn(u8) -> bool| {
            let (x, y) = ((p % w) as i64, (p / w) as i64);
            (-1..=1).any(|dy| {
                (-1..=1).any(|dx| {
                    let (xx, yy) = (x + dx, y + dy);
                    xx >= 0 && yy >= 0 && xx < w as i64 && yy < h as i64 && which(labels[yy as usize * w + xx as usize])
                })
            })
        };
        for p in 0..w * h {
            let same = |a: &[f32], b: &[f32]| (0..3).all(|c| (a[c * w * h + p] - b[c * w * h + p]).abs() < 1.5 / 255.0);
            if !near_object(p, &|l| l != 0) {
                assert!(same(&composited, &photo), "{name}: pixel {p} changed away from the objects");
            }
            // the subset ground truth shows object 2 where it is seen and the photo elsewhere
            if !near_object(p, &|l| l != 2) {
                assert!(same(&kept_only, &composited), "{name}: without_1 differs where object 2 is");
            }
            if labels[p] > 0 {
                object_pixels[labels[p] as usize - 1] += 1;
            }
        }
        // each object's world center, where it is in front of everything, carries its label
        for o in &summary.objects {
            let Some((x, y, _)) = cam.project_to_image(g.to_world(o.center)) else { continue };
            let label = labels[y as usize * w + x as usize];
            assert!(label != 0, "{name}: object {}'s center pixel has no label", o.label);
        }
    }
    assert!(object_pixels.iter().all(|&n| n > 200), "objects cover too few pixels: {object_pixels:?}");
    never_seen_is_the_floor_no_training_view_sees(&cameras, &summary, &out);

    // the composite's sparse model: the capture's own points, less those the objects stand on
    // (within a tenth of their size of their surface) or hide (fewer training views than two, or
    // than saw it without them, see the point past the objects: the closed form of `blocked`),
    // and points on the objects' surfaces
    let read_points = |dir: &Path| -> Vec<[f64; 3]> {
        cogeo::scene::dataset::read_capture(dir).unwrap().points.iter().map(|p| p.xyz).collect()
    };
    let captured = read_points(&root.join("capture"));
    let model = read_points(&out);
    let surface_distance = |p: [f64; 3]| {
        let local = g.to_local(p);
        summary.objects.iter().map(|o| o.sdf(local) / o.size).fold(f64::INFINITY, f64::min)
    };
    let train = training_views(&cameras);
    let hidden = |c: [f64; 3]| {
        let framing: Vec<_> = train.iter().filter(|v| v.project_to_image(c).is_some()).collect();
        let past = framing.iter().filter(|v| sees_past_objects(&summary, v, c)).count();
        !framing.is_empty() && past < framing.len().min(2)
    };
    // the depths' tolerance: a view sees a point where a pixel within one of where it lands shows
    // its depth, so only points whose neighbours 1.5 pixels away on the floor (in every training
    // view) share its verdict count, as the never-seen masks' 3 x 3 neighbourhoods do
    let steady = |c: [f64; 3], verdict: bool| {
        let step = train.iter().map(|v| 1.5 * v.to_camera(c)[2] / v.fx).fold(0.0, f64::max);
        let offsets =
            [(-1.0, -1.0), (0.0, -1.0), (1.0, -1.0), (-1.0, 0.0), (1.0, 0.0), (-1.0, 1.0), (0.0, 1.0), (1.0, 1.0)];
        offsets.iter().all(|(i, j)| hidden([c[0] + i * step, c[1] + j * step, c[2]]) == verdict)
    };
    let is_captured = |p: &[f64; 3]| captured.iter().any(|c| (0..3).all(|k| (c[k] - p[k]).abs() < 1e-9));
    let (mut kept, mut swallowed, mut left_out, mut disagree) = (0, 0, 0, 0);
    for c in &captured {
        let in_model = model.iter().any(|p| (0..3).all(|k| (c[k] - p[k]).abs() < 1e-9));
        if surface_distance(*c) < 0.1 {
            assert!(!in_model, "capture point {c:?} under an object is in the composite's model");
            swallowed += 1;
            continue;
        }
        let verdict = hidden(*c);
        if !steady(*c, verdict) {
            continue;
        }
        if verdict {
            left_out += 1;
            disagree += in_model as usize;
        } else {
            kept += 1;
            disagree += !in_model as usize;
        }
    }
    eprintln!("steady capture points: {kept} seen, {left_out} hidden, {disagree} against the closed form; {swallowed} swallowed");
    assert!(swallowed > 0 && kept > 2000 && left_out > 20, "{swallowed} swallowed, {kept} seen, {left_out} hidden");
    // 1 % of them: keeping every hidden point (the rule before) is 49 of 2801 here
    assert!(disagree * 100 <= kept + left_out, "{disagree} capture points disagree with the closed form of hiding");
    let on_objects: Vec<f64> = model.iter().filter(|p| !is_captured(p)).map(|&p| surface_distance(p)).collect();
    assert!(on_objects.len() > 20, "only {} points on the objects", on_objects.len());
    for d in &on_objects {
        // a composited depth sample of an object pixel (supersampled edges blend in some floor)
        assert!(d.abs() < 0.05, "a model point off the capture lies {d} sizes from every object's surface");
    }

    // the same placement again from the first composite's synth.json, with another seed (which
    // would place the objects elsewhere): the same objects, masks and depths
    let again = root.join("again");
    let cfg_again = CompositeConfig { placement: Some(out.join("synth.json")), seed: cfg.seed + 1, ..cfg.clone() };
    let summary_again = composite(&gpu, &cfg_again, &again, &|_, _, _| {}).unwrap();
    assert_eq!(summary_again.objects.len(), summary.objects.len());
    for (a, b) in summary.objects.iter().zip(&summary_again.objects) {
        assert_eq!((a.label, a.center, a.size), (b.label, b.center, b.size), "object moved");
    }
    for cam in &cameras {
        for file in [format!("object_mask/{}.png", cam.name), format!("depth/{}.exr", cam.name)] {
            let (a, b) = (std::fs::read(out.join(&file)).unwrap(), std::fs::read(again.join(&file)).unwrap());
            assert!(a == b, "{file} differs when composited from the placement file");
        }
    }
    // a placement with another number of objects is refused, naming the file
    let three = CompositeConfig { objects: 3, gt_without: vec![], ..cfg_again };
    let Err(err) = composite(&gpu, &three, &root.join("three"), &|_, _, _| {}) else {
        panic!("a placement of two objects was taken for three")
    };
    let err = err.to_string();
    assert!(err.contains("synth.json") && err.contains("holds 2 objects"), "unexpected error: {err}");
}

/// The never-seen masks against their closed form: behind an object's pixel lies the floor point
/// where the pixel's ray meets z = 0; a training view sees it when it lies in that view's frame and
/// the segment from the view's center to it passes through no object (sphere-traced on the
/// objects' exact distance functions). Only pixels inside the objects' masks count (the floor
/// elsewhere is seen by the view itself or its neighbours), and only those whose 3 x 3
/// neighbourhood agrees on the closed form (pixel steps and supersampled rims are the masks'
/// tolerance).
fn never_seen_is_the_floor_no_training_view_sees(
    cameras: &[cogeo::scene::Camera],
    summary: &cogeo::synth::composite::CompositeSummary,
    out: &Path,
) {
    let train = training_views(cameras);
    let (mut agree, mut disagree, mut closed_form_unseen) = (0usize, 0usize, 0usize);
    for cam in cameras {
        let (w, h) = (cam.width as usize, cam.height as usize);
        let labels = gray(&out.join(format!("object_mask/{}.png", cam.name)));
        let unseen = gray(&out.join(format!("unseen_mask/{}.png", cam.name)));
        let center = cam.center();
        let expected: Vec<Option<bool>> = (0..w * h)
            .map(|p| {
                let far = cam.pixel_point(p % w, p / w, 1.0);
                let dir = [far[0] - center[0], far[1] - center[1], far[2] - center[2]];
                let t = -center[2] / dir[2];
                (t > 0.0).then(|| {
                    let floor = [center[0] + t * dir[0], center[1] + t * dir[1], 0.0];
                    !train.iter().any(|v| sees_past_objects(summary, v, floor))
                })
            })
            .collect();
        for p in (0..w * h).filter(|&p| labels[p] != 0) {
            let (x, y) = (p % w, p / w);
            if x == 0 || y == 0 || x + 1 == w || y + 1 == h {
                continue;
            }
            let Some(e) = expected[p] else { continue };
            let steady = (y - 1..=y + 1).all(|yy| (x - 1..=x + 1).all(|xx| expected[yy * w + xx] == Some(e)));
            if !steady {
                continue;
            }
            closed_form_unseen += e as usize;
            if (unseen[p] > 0) == e {
                agree += 1;
            } else {
                disagree += 1;
            }
        }
    }
    eprintln!("never-seen masks: {agree} object pixels agree with the closed form, {disagree} not, {closed_form_unseen} never seen");
    assert!(closed_form_unseen > 50, "only {closed_form_unseen} object pixels hide floor no training view sees");
    assert!(
        disagree * 50 <= agree + disagree,
        "never-seen masks disagree with the closed form on {disagree} of {} object pixels",
        agree + disagree
    );
}

/// Whether the segment `from` -> `to` passes through one of the objects (sphere-traced on their
/// exact distance functions).
fn blocked(summary: &cogeo::synth::composite::CompositeSummary, from: [f64; 3], to: [f64; 3]) -> bool {
    let g = &summary.ground;
    let d = [to[0] - from[0], to[1] - from[1], to[2] - from[2]];
    let length = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
    let mut t = 0.0;
    while t < length - 1e-6 * length {
        let q = [from[0] + d[0] * t / length, from[1] + d[1] * t / length, from[2] + d[2] * t / length];
        let local = g.to_local(q);
        let sdf = summary.objects.iter().map(|o| o.sdf(local)).fold(f64::INFINITY, f64::min);
        if sdf < 1e-7 * length {
            return true;
        }
        t += sdf;
    }
    false
}

/// Whether `view` frames `point` and the segment from its center to it passes through no object.
fn sees_past_objects(
    summary: &cogeo::synth::composite::CompositeSummary,
    view: &cogeo::scene::Camera,
    point: [f64; 3],
) -> bool {
    view.project_to_image(point).is_some() && !blocked(summary, view.center(), point)
}

/// The cameras the composite's training (and its never-seen test) uses: all but the held-out ones.
fn training_views(cameras: &[cogeo::scene::Camera]) -> Vec<&cogeo::scene::Camera> {
    cameras.iter().enumerate().filter(|(i, _)| !cogeo::scene::dataset::is_test_view(*i)).map(|(_, c)| c).collect()
}
