//! GPU backward passes against central finite differences of the f64 CPU reference renderer.
//!
//! The loss is a fixed random linear functional of every output (RGB, alpha, accumulated and expected
//! depth, features), so its pixel gradients are the random weights themselves. Finite differences
//! whose step crosses a discrete threshold (alpha = 1/255, T = 1e-4) are detected by comparing steps h
//! and h/2, skipped and counted; the test asserts they are rare.

mod common;

use cogeo::gpu::{Buffer, Recorder};
use cogeo::render::backward::{Backward, PixelGradients, SceneGradients};
use cogeo::render::reference::render_reference;
use cogeo::render::{BlendLayout, Rasterizer, RenderSettings, SceneBuffers};
use cogeo::rng::Rng;
use cogeo::scene::{logit, Camera, GaussianScene};
use common::gpu;

struct Weights {
    rgb: Vec<f32>,
    alpha: Vec<f32>,
    depth: Vec<f32>,
    expected_depth: Vec<f32>,
    features: Vec<f32>,
    /// Only the RGB weights are nonzero, and the backward gets no alpha or depth gradients at all
    /// (as in training): blend_backward's COLOR_ONLY variant.
    color_only: bool,
}

fn weights(hw: usize, d: usize, seed: u64) -> Weights {
    let mut rng = Rng::new(seed);
    let mut v = |n: usize, s: f64| (0..n).map(|_| (s * rng.range(-1.0, 1.0)) as f32).collect::<Vec<f32>>();
    Weights {
        rgb: v(3 * hw, 1.0),
        alpha: v(hw, 1.0),
        depth: v(hw, 0.3),
        expected_depth: v(hw, 0.3),
        features: v(d * hw, 1.0),
        color_only: false,
    }
}

/// `weights` with the alpha and depth weights zero, for the color-only backward.
fn color_weights(hw: usize, seed: u64) -> Weights {
    let w = weights(hw, 0, seed);
    Weights { alpha: vec![0.0; hw], depth: vec![0.0; hw], expected_depth: vec![0.0; hw], color_only: true, ..w }
}

fn loss(scene: &GaussianScene, cam: &Camera, bg: [f64; 3], w: &Weights, features: Option<(&[f32], usize)>) -> f64 {
    let r = render_reference(scene, cam, bg, 0.01, scene.sh_degree, features);
    let mut l = 0.0;
    for (a, b) in r.rgb.iter().zip(&w.rgb) {
        l += a * *b as f64;
    }
    for i in 0..r.alpha.len() {
        l += r.alpha[i] * w.alpha[i] as f64
            + r.depth[i] * w.depth[i] as f64
            + r.expected_depth[i] * w.expected_depth[i] as f64;
    }
    for (a, b) in r.features.iter().zip(&w.features) {
        l += a * *b as f64;
    }
    l
}

/// A scene with moderate opacities and sizes (so few pixels sit at the 0.99 clamp) around the origin.
fn scene(seed: u64, n: usize, degree: u32) -> GaussianScene {
    let mut rng = Rng::new(seed);
    let mut s = GaussianScene { sh_degree: degree, ..Default::default() };
    let k = s.sh_coeffs();
    for i in 0..n {
        // a few near the image border, where the Jacobian's x/z, y/z clamp is active
        let p = if i % 8 == 7 {
            [rng.range(2.5, 3.5) * if i % 16 == 7 { 1.0 } else { -1.0 }, rng.range(-0.8, 0.8), rng.range(0.0, 1.0)]
        } else {
            [rng.range(-1.3, 1.3), rng.range(-0.9, 0.9), rng.range(-1.0, 1.0)]
        };
        let log_scales = [0, 1, 2].map(|_| rng.range(-2.6, -1.4) as f32);
        let quat = [0, 1, 2, 3].map(|_| rng.normal() as f32);
        let opacity = logit(rng.range(0.15, 0.85));
        let sh: Vec<f32> = (0..3 * k).map(|i| (if i < 3 { 1.0 } else { 0.4 } * rng.normal()) as f32).collect();
        s.push(p.map(|v| v as f32), log_scales, quat, opacity, &sh);
    }
    s
}

fn camera() -> Camera {
    Camera::look_at("grad", 44, 34, 60.0, [0.2, -0.3, -3.5], [0.0; 3], [0.0, -1.0, 0.0])
}

struct GpuGradients {
    means: Vec<f32>,
    log_scales: Vec<f32>,
    quats: Vec<f32>,
    opacity_logits: Vec<f32>,
    sh: Vec<f32>,
    features: Vec<f32>,
}

/// The GPU's gradients; `layout` = the blend backward's pixels per invocation (None: the device's).
fn gpu_gradients(
    scene: &GaussianScene,
    cam: &Camera,
    bg: [f32; 3],
    w: &Weights,
    feats: Option<(&[f32], usize)>,
    cas: bool,
    layout: Option<BlendLayout>,
) -> GpuGradients {
    let g = gpu();
    let buffers = SceneBuffers::upload(&g, scene, feats).unwrap();
    let mut raster = Rasterizer::new(&g).unwrap();
    let settings = RenderSettings { background: bg, features: feats.is_some(), ..Default::default() };
    let frame = raster.forward(&buffers, cam, &settings).unwrap();
    let mut backward = match layout {
        Some(l) => Backward::with_layout(&g, cas, l).unwrap(),
        None => Backward::new(&g, cas).unwrap(),
    };
    assert_eq!(backward.uses_cas, cas || !g.info().float_atomic_add);
    let grads = SceneGradients::new(&g, &buffers).unwrap();
    let up = |v: &[f32]| Buffer::from_slice(&g, "upstream", v).unwrap();
    let (rgb, alpha, depth, ed) = (up(&w.rgb), up(&w.alpha), up(&w.depth), up(&w.expected_depth));
    let features = feats.map(|_| up(&w.features));
    let upstream = PixelGradients {
        rgb: &rgb,
        alpha: (!w.color_only).then_some(&alpha),
        depth: (!w.color_only).then_some(&depth),
        expected_depth: (!w.color_only).then_some(&ed),
        features: features.as_ref(),
    };
    let mut rec = Recorder::new(&g).unwrap();
    backward.record(&mut rec, raster.params_buffer(), &frame.params, &upstream, &grads, false).unwrap();
    rec.submit_and_wait().unwrap();
    let n = scene.len();
    GpuGradients {
        means: grads.means.download(&g, 3 * n).unwrap(),
        log_scales: grads.log_scales.download(&g, 3 * n).unwrap(),
        quats: grads.quats.download(&g, 4 * n).unwrap(),
        opacity_logits: grads.opacity_logits.download(&g, n).unwrap(),
        sh: grads.sh.download(&g, scene.sh.len()).unwrap(),
        features: grads.features.as_ref().map(|b| b.download(&g, n * feats.unwrap().1).unwrap()).unwrap_or_default(),
    }
}

/// One scalar parameter of the scene (or of the feature matrix).
#[derive(Clone, Copy)]
enum Param {
    Mean(usize),
    LogScale(usize),
    Quat(usize),
    OpacityLogit(usize),
    Sh(usize),
    Feature(usize),
}

fn param_mut<'a>(s: &'a mut GaussianScene, f: &'a mut [f32], p: Param) -> &'a mut f32 {
    match p {
        Param::Mean(i) => &mut s.means[i / 3][i % 3],
        Param::LogScale(i) => &mut s.log_scales[i / 3][i % 3],
        Param::Quat(i) => &mut s.quats[i / 4][i % 4],
        Param::OpacityLogit(i) => &mut s.opacity_logits[i],
        Param::Sh(i) => &mut s.sh[i],
        Param::Feature(i) => &mut f[i],
    }
}

/// The fixed data of a finite-difference check: scene, features, camera, background, loss weights.
struct Problem<'a> {
    scene: &'a GaussianScene,
    feats: &'a [f32],
    dim: usize,
    cam: &'a Camera,
    bg: [f64; 3],
    w: &'a Weights,
}

impl Problem<'_> {
    /// Central difference of the loss along one parameter, over the actual (float32-rounded) step.
    fn finite_difference(&self, p: Param, h: f64) -> f64 {
        let eval = |delta: f64| -> (f64, f64) {
            let mut s = self.scene.clone();
            let mut f = self.feats.to_vec();
            let v = param_mut(&mut s, &mut f, p);
            *v = (*v as f64 + delta) as f32;
            let moved = *v as f64;
            let fo = if self.dim > 0 { Some((f.as_slice(), self.dim)) } else { None };
            (loss(&s, self.cam, self.bg, self.w, fo), moved)
        };
        let (lp, xp) = eval(h);
        let (lm, xm) = eval(-h);
        (lp - lm) / (xp - xm)
    }

    /// Finite differences of every scalar of one group; NaN marks a step that crossed a threshold.
    fn fd_group(&self, params: &[Param]) -> (Vec<f64>, usize) {
        let mut skipped = 0;
        let out = params
            .iter()
            .map(|&p| {
                let x = *param_mut(&mut self.scene.clone(), &mut self.feats.to_vec(), p) as f64;
                // small: a hard 1/255 cutoff means a footprint moved by h crosses pixel centers with probability ~h
                let h = 1e-5 * x.abs().max(0.1);
                let a = self.finite_difference(p, h);
                let b = self.finite_difference(p, h / 2.0);
                if (a - b).abs() > 1e-5 * (a.abs() + b.abs()) + 1e-7 {
                    skipped += 1;
                    f64::NAN
                } else {
                    (4.0 * b - a) / 3.0 // Richardson extrapolation of the two central differences
                }
            })
            .collect();
        (out, skipped)
    }
}

struct GroupCheck {
    name: &'static str,
    gpu: Vec<f32>,
    fd: Vec<f64>,
    skipped: usize,
}

fn check_group(c: &GroupCheck) {
    let max_fd = c.fd.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    let (mut num, mut den) = (0.0, 0.0);
    let mut worst: (f64, usize) = (0.0, 0);
    for (i, (&g, &f)) in c.gpu.iter().zip(&c.fd).enumerate() {
        if f.is_nan() {
            continue; // skipped: threshold crossing
        }
        let err = (g as f64 - f).abs();
        num += err * err;
        den += f * f;
        // relative error, with a float32 noise floor at 1e-5 of the group's largest gradient (gradients
        // summed over many pixels with cancellation cannot be resolved below that in float32)
        let rel = err / (f.abs() + 1e-2 * max_fd);
        if rel > worst.0 {
            worst = (rel, i);
        }
    }
    let rel_l2 = (num / den.max(1e-300)).sqrt();
    println!(
        "{:<15} {} values, {} skipped, max |fd| {:.3e}, relative L2 error {:.2e}, worst element {} (gpu {:.6e}, fd {:.6e}, rel {:.2e})",
        c.name, c.gpu.len(), c.skipped, max_fd, rel_l2, worst.1, c.gpu[worst.1], c.fd[worst.1], worst.0
    );
    assert!(max_fd > 0.0, "{}: all finite differences are zero; the test would be vacuous", c.name);
    assert!(c.skipped * 20 <= c.gpu.len(), "{}: too many threshold crossings ({})", c.name, c.skipped);
    assert!(rel_l2 <= 1e-3, "{}: relative L2 error {rel_l2:.3e}", c.name);
    assert!(worst.0 <= 1e-3, "{}: element {} relative error {:.3e}", c.name, worst.1, worst.0);
}

fn run_gradient_check(degree: u32, cas: bool, seed: u64) {
    let hw = (camera().width * camera().height) as usize;
    check_against_finite_differences(degree, cas, seed, &weights(hw, 0, seed + 1));
}

fn check_against_finite_differences(degree: u32, cas: bool, seed: u64, w: &Weights) {
    let scene = scene(seed, 24, degree);
    let cam = camera();
    let bg = [0.3f32, 0.5, 0.7];
    let bgd = bg.map(|v| v as f64);
    let g = gpu_gradients(&scene, &cam, bg, w, None, cas, None);
    let n = scene.len();
    let k = scene.sh_coeffs();
    let groups: Vec<(&'static str, Vec<f32>, Vec<Param>)> = vec![
        ("means", g.means, (0..3 * n).map(Param::Mean).collect()),
        ("log_scales", g.log_scales, (0..3 * n).map(Param::LogScale).collect()),
        ("quats", g.quats, (0..4 * n).map(Param::Quat).collect()),
        ("opacity_logits", g.opacity_logits, (0..n).map(Param::OpacityLogit).collect()),
        ("sh", g.sh, (0..n * k * 3).map(Param::Sh).collect()),
    ];
    for (name, gpu_values, params) in groups {
        let problem = Problem { scene: &scene, feats: &[], dim: 0, cam: &cam, bg: bgd, w };
        let (fd, skipped) = problem.fd_group(&params);
        check_group(&GroupCheck { name, gpu: gpu_values, fd, skipped });
    }
}

#[test]
fn color_only_gradients_match_finite_differences() {
    // a loss of the colors alone, as training's: the backward runs its COLOR_ONLY variant, which
    // leaves out the alpha and depth terms
    let hw = (camera().width * camera().height) as usize;
    for (degree, cas, seed) in [(1, false, 15), (0, true, 16)] {
        check_against_finite_differences(degree, cas, seed, &color_weights(hw, seed + 1));
    }
    // and the same sums as the full pass fed zero alpha and depth gradients, up to the order of
    // the atomic adds
    let (scene, cam, bg) = (scene(17, 60, 1), camera(), [0.2f32, 0.1, 0.4]);
    let only = color_weights(hw, 18);
    let zeros = Weights { color_only: false, ..color_weights(hw, 18) };
    let a = gpu_gradients(&scene, &cam, bg, &only, None, false, None);
    let b = gpu_gradients(&scene, &cam, bg, &zeros, None, false, None);
    for (name, x, y) in
        [("means", &a.means, &b.means), ("log_scales", &a.log_scales, &b.log_scales), ("sh", &a.sh, &b.sh)]
    {
        let scale = y.iter().fold(0f32, |m, v| m.max(v.abs()));
        let err = x.iter().zip(y.iter()).fold(0f32, |m, (p, q)| m.max((p - q).abs()));
        assert!(scale > 0.0 && err <= 1e-6 * scale, "{name}: color-only against full, max difference {err} of {scale}");
    }
}

#[test]
fn gradients_match_finite_differences_sh0_and_sh1() {
    run_gradient_check(0, false, 11);
    run_gradient_check(1, false, 12);
}

#[test]
fn gradients_match_finite_differences_sh3() {
    run_gradient_check(3, false, 13);
}

#[test]
fn gradients_match_finite_differences_with_compare_and_swap_accumulation() {
    run_gradient_check(2, true, 14);
}

#[test]
fn feature_gradients_match_finite_differences() {
    let scene = scene(21, 20, 0);
    let cam = camera();
    let hw = (cam.width * cam.height) as usize;
    let d = 40; // more than one 32-channel chunk
    let mut rng = Rng::new(22);
    let feats: Vec<f32> = (0..scene.len() * d).map(|_| rng.normal() as f32).collect();
    let w = weights(hw, d, 23);
    for cas in [false, true] {
        let g = gpu_gradients(&scene, &cam, [0.0; 3], &w, Some((&feats, d)), cas, None);
        let params: Vec<Param> = (0..feats.len()).map(Param::Feature).collect();
        let problem = Problem { scene: &scene, feats: &feats, dim: d, cam: &cam, bg: [0.0; 3], w: &w };
        let (fd, skipped) = problem.fd_group(&params);
        check_group(&GroupCheck {
            name: if cas { "features (cas)" } else { "features" },
            gpu: g.features,
            fd,
            skipped,
        });
    }
}

#[test]
fn blend_backward_pixel_layouts_agree() {
    // The blend backward gives each invocation a block of 1..16 x 1..2 pixels
    // (render::BlendLayout::for_device picks per device); every layout must give the gradients of the
    // device's own, which the finite-difference tests above check. The camera's 44x34 leaves partial
    // tiles and columns. The color-only variant likewise.
    let scene = scene(31, 60, 1);
    let cam = camera();
    let hw = (cam.width * cam.height) as usize;
    let bg = [0.2f32, 0.1, 0.4];
    for (w, cas) in [(weights(hw, 0, 32), false), (weights(hw, 0, 32), true), (color_weights(hw, 33), false)] {
        let reference = gpu_gradients(&scene, &cam, bg, &w, None, cas, None);
        let groups = |g: &GpuGradients| {
            [g.means.clone(), g.log_scales.clone(), g.quats.clone(), g.opacity_logits.clone(), g.sh.clone()]
        };
        for (rows, cols) in [(1, 1), (2, 1), (4, 1), (8, 1), (16, 1), (1, 2), (16, 2)] {
            let layout = BlendLayout { backward_rows: rows, backward_cols: cols, ..BlendLayout::PIXEL };
            let other = gpu_gradients(&scene, &cam, bg, &w, None, cas, Some(layout));
            for (k, (a, b)) in groups(&other).iter().zip(groups(&reference)).enumerate() {
                let scale = b.iter().fold(0f32, |m, v| m.max(v.abs()));
                let err = a.iter().zip(&b).fold(0f32, |m, (x, y)| m.max((x - y).abs()));
                assert!(scale > 0.0, "group {k}: no gradient at all");
                assert!(
                    err <= 1e-5 * scale,
                    "{layout:?}, cas {cas}, color only {}, group {k}: max difference {err} of {scale}",
                    w.color_only
                );
            }
        }
    }
}

#[test]
fn feature_backward_layouts_agree() {
    // The feature backward's column of 1..16 pixels per invocation, against the device's own layout
    // (checked against finite differences above), with 40 channels (two dispatches) and both
    // accumulation variants.
    let scene = scene(41, 40, 0);
    let cam = camera();
    let hw = (cam.width * cam.height) as usize;
    let d = 40;
    let mut rng = Rng::new(42);
    let feats: Vec<f32> = (0..scene.len() * d).map(|_| rng.normal() as f32).collect();
    let w = weights(hw, d, 43);
    for cas in [false, true] {
        let reference = gpu_gradients(&scene, &cam, [0.0; 3], &w, Some((&feats, d)), cas, None).features;
        let scale = reference.iter().fold(0f32, |m, v| m.max(v.abs()));
        assert!(scale > 0.0, "no feature gradient at all");
        for feature_rows in [1, 2, 4, 8, 16] {
            let layout = BlendLayout { feature_rows, ..BlendLayout::PIXEL };
            let other = gpu_gradients(&scene, &cam, [0.0; 3], &w, Some((&feats, d)), cas, Some(layout)).features;
            let err = other.iter().zip(&reference).fold(0f32, |m, (x, y)| m.max((x - y).abs()));
            assert!(err <= 1e-5 * scale, "{feature_rows} rows, cas {cas}: max difference {err} of {scale}");
        }
    }
}

#[test]
fn a_render_of_only_some_tiles_has_no_backward() {
    // RenderSettings::only_tiles leaves the other tiles' per-pixel state unblended: the backward,
    // which replays every tile, refuses such a frame
    let (g, sc, cam) = (gpu(), scene(5, 40, 0), camera());
    let buffers = SceneBuffers::upload(&g, &sc, None).unwrap();
    let mut raster = Rasterizer::new(&g).unwrap();
    let tiles = (cam.width.div_ceil(16) * cam.height.div_ceil(16)) as usize;
    let settings = RenderSettings { only_tiles: Some(vec![true; tiles]), ..Default::default() };
    let frame = raster.forward(&buffers, &cam, &settings).unwrap();
    let w = color_weights((cam.width * cam.height) as usize, 3);
    let rgb = Buffer::from_slice(&g, "upstream", &w.rgb).unwrap();
    let upstream = PixelGradients { rgb: &rgb, alpha: None, depth: None, expected_depth: None, features: None };
    let grads = SceneGradients::new(&g, &buffers).unwrap();
    let mut rec = Recorder::new(&g).unwrap();
    let err = Backward::new(&g, false).unwrap().record(
        &mut rec,
        raster.params_buffer(),
        &frame.params,
        &upstream,
        &grads,
        false,
    );
    assert!(err.unwrap_err().to_string().contains("only_tiles"));
}
