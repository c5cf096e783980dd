//! Stage 1b of removal (`removal::hull`) against a closed form: a box standing on a floor before a
//! wall, built of flat Gaussians, whose tagging missed some of the box's Gaussians (every fifth
//! one on its faces, and a few inside it). The floor runs on under the box untagged, so its
//! Gaussians under the footprint are in every view's hole as well: the stage must take exactly
//! the missed box Gaussians that stand clear of the floor, and no Gaussian of the floor or wall.

mod common;

use cogeo::removal::hull::{leftovers_inside, remove_leftovers_inside, HullConfig};
use cogeo::removal::select::{
    hole_masks, select_gaussians, splat_tiles, splat_window, DepthPlanes, HoleConfig, MaskedView,
};
use cogeo::render::reference::render_reference;
use cogeo::scene::{logit, Camera, GaussianScene, SH_C0};

/// Where a Gaussian of the scene belongs.
#[derive(Clone, Copy, PartialEq, Debug)]
enum Part {
    Floor,
    Wall,
    /// The box, tagged as such.
    Tagged,
    /// The box, left untagged by the tagging; at this height above the floor.
    Missed(f32),
}

const SPACING: f32 = 0.05;
const HALF: f32 = 0.3; // the box: [-0.3, 0.3] x [-0.3, 0.3] x [0, 0.6]
const HEIGHT: f32 = 0.6;
const WALL_Y: f32 = 1.5;

/// Integer steps of SPACING covering [a, b].
fn steps(a: f32, b: f32) -> Vec<f32> {
    let n = ((b - a) / SPACING).round() as i32;
    (0..=n).map(|k| a + k as f32 * SPACING).collect()
}

fn scene() -> (GaussianScene, Vec<Part>) {
    let mut scene = GaussianScene { sh_degree: 0, ..Default::default() };
    let mut parts = Vec::new();
    let (flat, wide) = ((0.2 * SPACING).ln(), (0.8 * SPACING).ln());
    let mut push = |p: [f32; 3], thin_axis: usize, color: f32, part: Part| {
        let mut s = [wide; 3];
        s[thin_axis] = flat;
        scene.push(p, s, [1.0, 0.0, 0.0, 0.0], logit(0.99), &[(color - 0.5) / SH_C0 as f32; 3]);
        parts.push(part);
    };
    for x in steps(-2.0, 2.0) {
        for y in steps(-2.5, WALL_Y) {
            let checker = ((x / 0.2).floor() + (y / 0.2).floor()).rem_euclid(2.0);
            push([x, y, 0.0], 2, 0.3 + 0.3 * checker, Part::Floor);
        }
        for z in steps(0.0, 2.0) {
            push([x, WALL_Y, z], 1, 0.8 - 0.2 * ((z / 0.25).floor().rem_euclid(2.0)), Part::Wall);
        }
    }
    // the box's faces (top and four sides), every fifth Gaussian missed by the tagging
    let mut k = 0;
    let mut face = |p: [f32; 3], axis: usize, push: &mut dyn FnMut([f32; 3], usize, f32, Part)| {
        k += 1;
        let part = if k % 5 == 0 { Part::Missed(p[2]) } else { Part::Tagged };
        push(p, axis, 0.15, part);
    };
    for a in steps(-HALF, HALF) {
        for b in steps(-HALF, HALF) {
            face([a, b, HEIGHT], 2, &mut push);
        }
        for z in steps(SPACING, HEIGHT - SPACING) {
            face([a, -HALF, z], 1, &mut push);
            face([a, HALF, z], 1, &mut push);
            face([-HALF, a, z], 0, &mut push);
            face([HALF, a, z], 0, &mut push);
        }
    }
    // and a few inside it
    for p in [[0.0, 0.0, 0.3], [0.1, -0.1, 0.45], [-0.15, 0.1, 0.2]] {
        push(p, 2, 0.15, Part::Missed(p[2]));
    }
    (scene, parts)
}

/// Eight views of the box from in front of the wall, 2.5 away, looking down on it.
fn cameras() -> Vec<Camera> {
    (0..8)
        .map(|k| {
            let a = (-160.0 + 20.0 * k as f64).to_radians();
            let eye = [2.5 * a.cos(), 2.5 * a.sin(), 1.4];
            Camera::look_at(&format!("v{k}"), 96, 72, 60.0, eye, [0.0, 0.0, 0.3], [0.0, 0.0, 1.0])
        })
        .collect()
}

#[test]
fn the_missed_gaussians_of_a_removed_box_go_and_the_floor_under_it_stays() {
    let gpu = common::gpu();
    let (scene, parts) = scene();
    let labels: Vec<u8> = parts.iter().map(|p| (*p == Part::Tagged) as u8).collect();
    let cams = cameras();
    let selection = select_gaussians(&scene, &labels, &[1]).unwrap();
    let holes =
        HoleConfig { threshold: 0.3, dilate: 2.0, keep_alpha: 0.9, background: [0.0; 3], depth: DepthPlanes::Expected };
    let masked = hole_masks(&gpu, &scene, &selection, &cams, &holes, &mut |_, _| {}).unwrap();
    let cfg = HullConfig::default();
    let mut peeled = select_gaussians(&scene, &labels, &[1]).unwrap();
    let mut remasked = hole_masks(&gpu, &scene, &peeled, &cams, &holes, &mut |_, _| {}).unwrap();
    let taken = remove_leftovers_inside(
        &gpu,
        &scene,
        &labels,
        &[1],
        &cams,
        &holes,
        &cfg,
        &mut peeled,
        &mut remasked,
        &mut |_, _| {},
    )
    .unwrap();
    let inside: Vec<bool> = (0..scene.len()).map(|i| peeled.removed[i] && !selection.removed[i]).collect();
    assert_eq!(taken, inside.iter().filter(|&&g| g).count());
    let under = |i: usize| {
        let m = scene.means[i];
        m[0].abs() <= HALF && m[1].abs() <= HALF
    };
    let floor_under = (0..scene.len()).filter(|&i| parts[i] == Part::Floor && under(i)).count();
    assert!(floor_under >= 100, "{floor_under} floor Gaussians under the box");
    let mut missed_clear = 0;
    for (i, part) in parts.iter().enumerate() {
        match *part {
            Part::Floor | Part::Wall => {
                assert!(!inside[i], "{part:?} Gaussian at {:?} taken as a leftover of the box", scene.means[i])
            }
            Part::Tagged => assert!(peeled.removed[i], "a tagged Gaussian stays"),
            // the box's lowest Gaussians touch the floor: within the tolerance of its plane
            Part::Missed(z) if z >= 0.15 => {
                missed_clear += 1;
                assert!(inside[i], "missed box Gaussian at {:?} kept", scene.means[i]);
            }
            Part::Missed(_) => {}
        }
    }
    assert!(missed_clear >= 60, "{missed_clear} missed Gaussians clear of the floor");
    // the near side's leftovers hide the far side's in the first round's renders: a second
    // round takes them
    let first = leftovers_inside(&scene, &labels, &selection.removed, &cams, &masked, &cfg);
    let hidden = (0..scene.len()).filter(|&i| inside[i] && !first[i]).count();
    assert!(hidden > 0 && (0..scene.len()).all(|i| !first[i] || inside[i]), "{hidden} found after the first round");
    // the stage off keeps them all
    let off = HullConfig { share: 0.0, ..cfg.clone() };
    assert!(leftovers_inside(&scene, &labels, &selection.removed, &cams, &masked, &off).iter().all(|&g| !g));
    // what spares the floor under the footprint is the planes' test: every view that frames one
    // of its Gaussians has it in the hole
    let in_every_hole = (0..scene.len())
        .filter(|&i| parts[i] == Part::Floor && under(i))
        .filter(|&i| {
            let m = scene.means[i].map(f64::from);
            cams.iter().zip(&masked).all(|(c, v)| c.pixel_of(m).is_none_or(|(p, _)| v.hole[p]))
        })
        .count();
    assert!(in_every_hole * 2 >= floor_under, "{in_every_hole} of {floor_under} floor Gaussians in every hole");
    // the rounds draw the holes again only where the Gaussians taken blend: the same holes and
    // renders as drawing every view anew for the final selection
    let anew = hole_masks(&gpu, &scene, &peeled, &cams, &holes, &mut |_, _| {}).unwrap();
    for (k, (redrawn, fresh)) in remasked.iter().zip(&anew).enumerate() {
        same_view(k, redrawn, fresh);
    }
}

/// Two drawings of one view's hole agree: masks exactly, renders to float rounding. (A window's
/// render moves the principal point: where a pixel's transmittance ends near 1e-4, or a Gaussian
/// blends near alpha 1/255, that rounding can flip one Gaussian in or out; one pixel of the box's
/// eight views does, by 1e-3.)
fn same_view(k: usize, a: &MaskedView, b: &MaskedView) {
    assert!(a.hole == b.hole && a.fill == b.fill && a.footprint == b.footprint, "view {k}: masks differ");
    let channels = [
        ("rgb before", &a.before.rgb, &b.before.rgb),
        ("removed weight", &a.before.weight, &b.before.weight),
        ("rgb after removal", &a.after_removal.rgb, &b.after_removal.rgb),
        ("alpha after removal", &a.after_removal.alpha, &b.after_removal.alpha),
        ("depth after removal", &a.after_removal.depth, &b.after_removal.depth),
        ("kept weight", &a.after_removal.weight, &b.after_removal.weight),
    ];
    for (name, x, y) in channels {
        assert_eq!(x.len(), y.len(), "view {k}: {name}");
        let worst = x.iter().zip(y.iter()).map(|(p, q)| (p - q).abs()).fold(0f32, f32::max);
        let off = x.iter().zip(y.iter()).filter(|(p, q)| (*p - *q).abs() > 1e-4).count();
        assert!(worst <= 1e-2 && off * 1000 <= x.len(), "view {k}: {name}: {off} values off, by up to {worst}");
    }
}

/// `splat_window` holds every pixel where the marked Gaussians blend, by the dense f64
/// reference (every Gaussian at every pixel), and not much more.
#[test]
fn the_splat_window_holds_every_pixel_the_marked_gaussians_blend() {
    let (scene, parts) = scene();
    let marked: Vec<bool> = parts.iter().map(|p| matches!(p, Part::Missed(_))).collect();
    let feature: Vec<f32> = marked.iter().map(|&m| m as u8 as f32).collect();
    for cam in cameras().iter().step_by(3) {
        let (w, h) = (cam.width as usize, cam.height as usize);
        let reference = render_reference(&scene, cam, [0.0; 3], 0.01, 0, Some((&feature, 1)));
        let blended: Vec<bool> = reference.features.iter().map(|&f| f > 0.0).collect();
        let tight = cogeo::image_ops::bounding_box(&blended, w).expect("the missed Gaussians are in view");
        let window = splat_window(&scene, &marked, cam).expect("a window");
        for p in (0..w * h).filter(|&p| blended[p]) {
            let (x, y) = (p % w, p / w);
            assert!(
                (window.x0..window.x1).contains(&x) && (window.y0..window.y1).contains(&y),
                "{} ({x}, {y})",
                cam.name
            );
        }
        // a pixel of float32 margin each side, and the supports' boxes around their ellipses
        let (gw, gh) = (window.width() - tight.width(), window.height() - tight.height());
        assert!(gw <= 8 && gh <= 8, "{}: window {window:?} around {tight:?}", cam.name);
        // its tiles that the marked Gaussians reach (`splat_tiles`) hold every such pixel too, and
        // grown by 4 pixels every pixel within 4 of one
        for grow in [0, 4] {
            let (tiled, tiles) = splat_tiles(&scene, &marked, cam, grow).expect("a window");
            let window = window.grown(grow, grow, w, h);
            assert_eq!(tiled, window, "{}: grown {grow}", cam.name);
            let tiles_x = window.width().div_ceil(16);
            assert_eq!(tiles.len(), tiles_x * window.height().div_ceil(16));
            let grown = cogeo::image_ops::dilate(&blended, w, h, grow as f32);
            for p in (0..w * h).filter(|&p| grown[p]) {
                let (x, y) = (p % w - window.x0, p / w - window.y0);
                assert!(tiles[(y / 16) * tiles_x + x / 16], "{}: grown {grow}: ({x}, {y}) in the window", cam.name);
            }
        }
        // and leave some of its tiles out: the point of rendering only them
        let (_, tiles) = splat_tiles(&scene, &marked, cam, 0).expect("a window");
        assert!(tiles.contains(&false), "{}: every tile of {window:?}", cam.name);
    }
    // none marked, none in view: no window
    let none = vec![false; scene.len()];
    assert!(splat_window(&scene, &none, &cameras()[0]).is_none());
    assert!(splat_tiles(&scene, &none, &cameras()[0], 4).is_none());
}
