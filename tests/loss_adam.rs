//! The GPU photometric loss (L1 + SSIM) and Adam against f64 CPU implementations.

mod common;

use cogeo::gpu::{Buffer, Recorder};
use cogeo::rng::Rng;
use cogeo::train::adam::{Adam, Moments, BETA1, BETA2, EPS};
use cogeo::train::loss::{reference, LossInputs, PhotometricLoss};
use common::gpu;

fn image(rng: &mut Rng, n: usize) -> Vec<f32> {
    (0..n).map(|_| rng.uniform() as f32).collect()
}

/// GPU loss value and gradient against the CPU reference and its central finite differences.
fn check_loss(width: usize, height: usize, masked: bool, seed: u64, run: u32) {
    let g = gpu();
    let mut rng = Rng::new(seed);
    let hw = width * height;
    // a smooth-ish target plus noise, and a render near it, so SSIM is far from trivial
    let target: Vec<f32> = (0..3 * hw)
        .map(|i| {
            let p = i % hw;
            (0.5 + 0.3 * ((p % width) as f64 * 0.4).sin() * ((p / width) as f64 * 0.3).cos() + 0.1 * rng.normal())
                as f32
        })
        .collect();
    let render: Vec<f32> = target.iter().map(|&t| t + (0.15 * rng.normal()) as f32).collect();
    let mask: Vec<f32> = (0..hw).map(|p| if masked && (p % width) < width / 3 { 0.0 } else { 1.0 }).collect();
    let mask_sum: f64 = mask.iter().map(|&v| v as f64).sum();

    let render_buf = Buffer::from_slice(&g, "render", &render).unwrap();
    // the target sits at an offset inside a larger buffer, as a dataset's images do
    let mut targets = image(&mut rng, 3 * hw);
    targets.extend(&target);
    let target_buf = Buffer::from_slice(&g, "targets", &targets).unwrap();
    let mask_buf = Buffer::from_slice(&g, "mask", &mask).unwrap();
    let mut loss = PhotometricLoss::with_run(&g, run).unwrap();
    let mut rec = Recorder::new(&g).unwrap();
    let inputs = LossInputs {
        render: &render_buf,
        target: &target_buf,
        target_offset: (3 * hw) as u64,
        mask: masked.then_some((&mask_buf, 0, mask_sum)),
    };
    // widths that are a multiple of 4 take the vec4 passes wherever the run is one too
    let vectorized = loss.vectorized(width as u32, height as u32, &inputs).unwrap();
    assert_eq!(vectorized, width.is_multiple_of(4) && run.is_multiple_of(4), "{width}x{height}, run {run}");
    loss.record(&mut rec, width as u32, height as u32, &inputs).unwrap();
    rec.submit_and_wait().unwrap();
    let (value, l1, ssim) = loss.read_values().unwrap();
    let grad: Vec<f32> = loss.dl_drgb().download(&g, 3 * hw).unwrap();

    let x: Vec<f64> = render.iter().map(|&v| v as f64).collect();
    let y: Vec<f64> = target.iter().map(|&v| v as f64).collect();
    let m: Vec<f64> = mask.iter().map(|&v| v as f64).collect();
    let mref = masked.then_some(m.as_slice());
    let ref_ssim = reference::ssim(&x, &y, width, height, mref);
    let ref_l1 = reference::l1(&x, &y, width, height, mref);
    let ref_loss = reference::loss(&x, &y, width, height, mref, 0.2);
    println!("{width}x{height} masked={masked} run={run} vec4={vectorized}: SSIM gpu {ssim:.7} cpu {ref_ssim:.7}; L1 gpu {l1:.7} cpu {ref_l1:.7}");
    assert!(ref_ssim > 0.2 && ref_ssim < 0.9, "SSIM {ref_ssim} should be far from 0 and 1");
    assert!((ssim - ref_ssim).abs() < 1e-5);
    assert!((l1 - ref_l1).abs() < 1e-6);
    assert!((value - ref_loss).abs() < 1e-5);

    let mut max_err: f64 = 0.0;
    let mut max_g: f64 = 0.0;
    for i in 0..3 * hw {
        let h = 1e-5;
        let mut xp = x.clone();
        xp[i] += h;
        let mut xm = x.clone();
        xm[i] -= h;
        let fd = (reference::loss(&xp, &y, width, height, mref, 0.2)
            - reference::loss(&xm, &y, width, height, mref, 0.2))
            / (2.0 * h);
        max_err = max_err.max((grad[i] as f64 - fd).abs());
        max_g = max_g.max(fd.abs());
        if masked && mask[i % hw] == 0.0 {
            // masked-out pixels still shape SSIM windows of counted pixels next to them, but have no L1 term
            assert!(fd.abs() < 0.2 / mask_sum || (i % hw) % width >= width / 3 - 6);
        }
    }
    println!("  gradient: max |fd| {max_g:.3e}, max error {max_err:.3e}");
    assert!(max_err <= 1e-3 * max_g, "loss gradient error {max_err:.3e} vs scale {max_g:.3e}");
}

#[test]
fn loss_value_and_gradient_match_cpu() {
    // one output per invocation, and runs of 8, 16, 32 and 64 along the blurred axis (GPU and CPU devices),
    // on sizes that are no multiple of a run; widths 28 and 36 take the vec4 passes (blur along y,
    // gradient along x) for runs of 8 and more
    for run in [1, 8, 16, 32, 64] {
        check_loss(23, 19, false, 1, run);
        check_loss(30, 17, true, 2, run);
        check_loss(28, 19, false, 3, run);
        check_loss(36, 17, true, 4, run);
    }
}

/// The f64 twin of one Adam step of one element (PyTorch's formulation): updates the moments `m`
/// and `v` with gradient `g` and returns the update to subtract at `rate`.
fn adam_update_f64(m: &mut f64, v: &mut f64, g: f64, step: u32, rate: f64) -> f64 {
    let (b1, b2) = (BETA1 as f64, BETA2 as f64);
    *m = b1 * *m + (1.0 - b1) * g;
    *v = b2 * *v + (1.0 - b2) * g * g;
    let (mh, vh) = (*m / (1.0 - b1.powi(step as i32)), *v / (1.0 - b2.powi(step as i32)));
    rate * mh / (vh.sqrt() + EPS as f64)
}

/// Five Adam steps on `n` elements with rates (lr, period, head, tail factor) against an f64 twin;
/// returns the max error.
fn check_adam(n: usize, period: u32, head: u32, tail: f32) -> f64 {
    let g = gpu();
    let mut rng = Rng::new(5);
    let mut p: Vec<f32> = image(&mut rng, n);
    let p_buf = Buffer::from_slice(&g, "p", &p).unwrap();
    let moments = Moments::new(&g, "p", n as u32).unwrap();
    let adam = Adam::new(&g).unwrap();
    let (mut m, mut v) = (vec![0f64; n], vec![0f64; n]);
    let mut pd: Vec<f64> = p.iter().map(|&x| x as f64).collect();
    for step in 1..=5u32 {
        let grad: Vec<f32> = (0..n).map(|_| (rng.normal() * 0.1) as f32).collect();
        let g_buf = Buffer::from_slice(&g, "g", &grad).unwrap();
        let lr = 0.01 * step as f32;
        let mut rec = Recorder::new(&g).unwrap();
        adam.record_split(&mut rec, &p_buf, &g_buf, &moments, (lr, period, head, lr * tail), step);
        rec.submit_and_wait().unwrap();
        for i in 0..n {
            let rate = if (i as u32 % period) < head { lr } else { lr * tail } as f64;
            pd[i] -= adam_update_f64(&mut m[i], &mut v[i], grad[i] as f64, step, rate);
        }
    }
    p = p_buf.download(&g, n).unwrap();
    let err = p.iter().zip(&pd).map(|(a, b)| (*a as f64 - b).abs()).fold(0.0, f64::max);
    // Adam's steps move parameters by about lr each: the comparison is not between two no-ops
    let moved: f64 =
        p.iter().zip(image(&mut Rng::new(5), n)).map(|(a, b)| (a - b).abs() as f64).sum::<f64>() / n as f64;
    assert!(moved > 0.01 * tail.min(1.0) as f64, "mean movement {moved}");
    err
}

#[test]
fn adam_matches_cpu_for_several_steps() {
    let err = check_adam(1000, 1, 1, 1.0);
    println!("adam max error after 5 steps: {err:.3e}");
    assert!(err < 1e-5, "adam error {err}");
}

#[test]
fn adam_split_rates_follow_the_period() {
    // SH-3 layout (48 floats per Gaussian, the first 3 at the DC rate) over several workgroup
    // blocks and a partial one; the higher bands at 1/20 of the rate, as in training
    let err = check_adam(5000, 48, 3, 0.05);
    println!("split adam max error after 5 steps: {err:.3e}");
    assert!(err < 1e-5, "adam error {err}");
}

/// The trust region bounds each Gaussian's step: rows of 3 (means, scales) and 4 (rotations),
/// three Adam steps of random gradients (so that rows differ in size), each row's update clipped
/// to the radius on its own, against an f64 reference of Adam and the clip.
#[test]
fn trust_region_clips_each_gaussians_update_to_the_radius() {
    let g = gpu();
    let adam = Adam::new(&g).unwrap();
    let mut rng = Rng::new(9);
    let lr = 0.01f64;
    for (width, rows) in [(3usize, 2000usize), (4, 700)] {
        let n = width * rows;
        let start = image(&mut rng, n);
        let p_buf = Buffer::from_slice(&g, "p", &start).unwrap();
        let moments = Moments::new(&g, "p", n as u32).unwrap();
        let (mut p, mut m, mut v) = (start.iter().map(|&x| x as f64).collect::<Vec<_>>(), vec![0.0; n], vec![0.0; n]);
        // about half of the rows clip: the radius sits between the typical and the largest norms
        let radius = 0.8 * lr * (width as f64).sqrt();
        let (mut clipped, mut free) = (0, 0);
        for step in 1..=3u32 {
            let grad: Vec<f32> = (0..n).map(|_| rng.normal() as f32).collect();
            let g_buf = Buffer::from_slice(&g, "g", &grad).unwrap();
            let mut rec = Recorder::new(&g).unwrap();
            adam.record_clipped(&mut rec, &p_buf, &g_buf, &moments, lr as f32, step, width as u32, radius as f32);
            rec.submit_and_wait().unwrap();
            let before = p.clone();
            let u: Vec<f64> = (0..n).map(|i| adam_update_f64(&mut m[i], &mut v[i], grad[i] as f64, step, lr)).collect();
            for r in 0..rows {
                let row = &u[r * width..(r + 1) * width];
                let norm = row.iter().map(|x| x * x).sum::<f64>().sqrt();
                let s = if norm > radius { radius / norm } else { 1.0 };
                if norm > radius {
                    clipped += 1
                } else {
                    free += 1
                }
                for k in 0..width {
                    p[r * width + k] -= s * row[k];
                }
            }
            let got: Vec<f32> = p_buf.download(&g, n).unwrap();
            let err = got.iter().zip(&p).map(|(a, b)| (*a as f64 - b).abs()).fold(0.0, f64::max);
            // every row's applied step, measured on the GPU's parameters, stays within the radius
            let longest = (0..rows)
                .map(|r| {
                    (0..width).map(|k| (got[r * width + k] as f64 - before[r * width + k]).powi(2)).sum::<f64>().sqrt()
                })
                .fold(0.0, f64::max);
            println!(
                "width {width}, step {step}: max error {err:.2e}, longest row step {longest:.5} (radius {radius:.5})"
            );
            assert!(err < 2e-6, "width {width}, step {step}: error {err}");
            assert!(longest < radius + 2e-6, "a row moved {longest} > {radius}");
        }
        assert!(clipped > rows / 4 && free > rows / 4, "width {width}: {clipped} clipped, {free} free rows");
    }
}
