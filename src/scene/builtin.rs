//! The built-in scene: a procedural, seeded Gaussian scene (a checkered floor, a back wall and a
//! few colored objects) with an orbit of cameras, so the Quick start needs no downloaded data.

use crate::rng::Rng;
use crate::scene::{logit, Camera, GaussianScene};

fn rgb_to_dc(c: f64) -> f32 {
    ((c - 0.5) / crate::scene::SH_C0) as f32
}

/// Appends a flat-ish Gaussian at `p` with color `rgb`, scale `s` (sigma), and thin axis `thin`.
fn push(scene: &mut GaussianScene, p: [f64; 3], rgb: [f64; 3], s: [f64; 3], opacity: f64, rng: &mut Rng) {
    let q = [1.0 + 0.05 * rng.normal(), 0.05 * rng.normal(), 0.05 * rng.normal(), 0.05 * rng.normal()];
    let sh: Vec<f32> = (0..3 * scene.sh_coeffs())
        .map(|i| if i < 3 { rgb_to_dc(rgb[i]) } else { (0.02 * rng.normal()) as f32 })
        .collect();
    scene.push(p.map(|v| v as f32), s.map(|v| v.ln() as f32), q.map(|v| v as f32), logit(opacity), &sh);
}

/// The default demo scene (about 60k Gaussians, SH degree 1).
pub fn default_scene() -> GaussianScene {
    let mut rng = Rng::new(7);
    let mut scene = GaussianScene { sh_degree: 1, ..Default::default() };
    // floor: z = 0, checkerboard over [-2, 2]^2
    let step = 0.03;
    let mut x: f64 = -2.0;
    while x < 2.0 {
        let mut y: f64 = -2.0;
        while y < 2.0 {
            let check = ((x / 0.4).floor() + (y / 0.4).floor()) as i64 % 2 == 0;
            let base = if check { [0.85, 0.82, 0.75] } else { [0.25, 0.3, 0.38] };
            let p = [x + rng.range(0.0, step), y + rng.range(0.0, step), 0.0];
            push(&mut scene, p, base, [step * 0.7, step * 0.7, 0.003], 0.95, &mut rng);
            y += step;
        }
        x += step;
    }
    // back wall: y = 2, stripes
    let mut x: f64 = -2.0;
    while x < 2.0 {
        let mut z: f64 = 0.0;
        while z < 1.6 {
            let stripe = ((z / 0.2).floor() as i64) % 2 == 0;
            let base = if stripe { [0.7, 0.45, 0.35] } else { [0.9, 0.8, 0.6] };
            push(&mut scene, [x, 2.0, z], base, [step * 0.7, 0.003, step * 0.7], 0.95, &mut rng);
            z += step;
        }
        x += step;
    }
    // objects: spheres of Gaussians on the floor
    let objects = [
        ([-0.6, 0.2, 0.35], 0.35, [0.9, 0.2, 0.2]),
        ([0.5, -0.3, 0.25], 0.25, [0.2, 0.7, 0.3]),
        ([0.3, 0.8, 0.4], 0.4, [0.25, 0.35, 0.9]),
    ];
    for (c, r, rgb) in objects {
        for _ in 0..4000 {
            let d = [rng.normal(), rng.normal(), rng.normal()];
            let n = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
            let p = [c[0] + r * d[0] / n, c[1] + r * d[1] / n, c[2] + r * d[2] / n];
            let shade = 0.75 + 0.25 * (d[2] / n);
            push(&mut scene, p, rgb.map(|v| v * shade), [0.025, 0.025, 0.025], 0.9, &mut rng);
        }
    }
    scene
}

/// `count` cameras on a circle around the scene, looking at its center.
pub fn orbit_cameras(count: usize, width: u32, height: u32) -> Vec<Camera> {
    (0..count)
        .map(|i| {
            let a = -std::f64::consts::FRAC_PI_2 + (i as f64 / count as f64 - 0.5) * 1.6;
            let eye = [3.2 * a.cos(), 3.2 * a.sin(), 1.6];
            Camera::look_at(&format!("view_{i:03}"), width, height, 60.0, eye, [0.0, 0.3, 0.3], [0.0, 0.0, 1.0])
        })
        .collect()
}
