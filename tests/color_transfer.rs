//! Stage 3c, the color transfer (removal/complete/transfer.rs), against closed-form scenes: a
//! hole pixel takes the color another view saw at its completed depth, each source's photo mapped
//! to the target's exposure, and each source's tint around the hole matched to the target's.

/// Color transfer on a fronto-parallel plane z = 5 seen by two translated cameras, where pixel and
/// world coordinates are affinely related: at the true depth every target pixel off the target's
/// own hole keeps its own photo's color exactly (the own capture comes first); in the hole, every
/// pixel that the source sees gets exactly the source photo's color of its surface point plus the
/// blue cast by which the target's own photo differs from the source's around the hole (local
/// color matching); off the source's image, in its hole, or at a depth 10 % off, nothing is
/// transferred.
#[test]
fn color_transfer_takes_the_color_other_views_saw_at_the_completed_depth() {
    use cogeo::removal::complete::source_views::SourceView;
    use cogeo::removal::complete::transfer::transfer;
    use cogeo::scene::exposure::ColorAffine;
    use cogeo::scene::Camera;
    const IDENTITY: ColorAffine = ColorAffine::IDENTITY;
    let (w, h) = (40usize, 30usize);
    let cam = |name: &str, x: f64| {
        Camera::look_at(name, w as u32, h as u32, 60.0, [x, 0.0, 0.0], [x, 0.0, 5.0], [0.0, -1.0, 0.0])
    };
    let (target_cam, source_cam) = (cam("t", 0.0), cam("s", 0.4));
    let color = |p: [f64; 3]| [0.5 + 0.1 * p[0], 0.5 + 0.1 * p[1], 0.3];
    let world = |c: &Camera, px: usize, z: f64| {
        let (u, v) = ((px % w) as f64 + 0.5, (px / w) as f64 + 0.5);
        let ctr = c.center();
        let x = (u - c.cx) / c.fx * z;
        let y = (v - c.cy) / c.fy * z;
        // the cameras look along +z with image y down = world y down... as look_at builds them
        let r = c.rotation;
        [0, 1, 2].map(|k| ctr[k] + r[0][k] * x + r[1][k] * y + r[2][k] * z)
    };
    let mut photo = vec![0f32; 3 * w * h];
    // the target's own capture: the same surface, with a blue cast that tells it apart
    let mut own_photo = vec![0f32; 3 * w * h];
    for p in 0..w * h {
        let c = color(world(&source_cam, p, 5.0));
        let own = color(world(&target_cam, p, 5.0));
        for k in 0..3 {
            photo[k * w * h + p] = c[k] as f32;
            own_photo[k * w * h + p] = own[k] as f32 + if k == 2 { 0.2 } else { 0.0 };
        }
    }
    let mut hole = vec![false; w * h];
    for y in 10..20 {
        for x in 25..30 {
            hole[y * w + x] = true;
        }
    }
    let depth = vec![5.0f32; w * h];
    let alpha = vec![1.0f32; w * h];
    let sources = [
        SourceView {
            camera: &target_cam,
            photo: &own_photo,
            hole: &hole,
            depth: &depth,
            alpha: &alpha,
            photo_colors: IDENTITY,
        },
        SourceView {
            camera: &source_cam,
            photo: &photo,
            hole: &hole,
            depth: &depth,
            alpha: &alpha,
            photo_colors: IDENTITY,
        },
    ];
    let fill = vec![true; w * h];
    let t = transfer(0, &target_cam, &depth, &fill, &sources, 0.05);
    let (mut found, mut blocked, mut own) = (0, 0, 0);
    for p in 0..w * h {
        if !hole[p] {
            // the point projects back onto this pixel's center, where Lanczos-3 is the sample
            assert!(t.found[p], "pixel {p} off the hole did not take its own photo");
            for k in 0..3 {
                let (got, want) = (t.rgb[k * w * h + p], own_photo[k * w * h + p]);
                assert!((got - want).abs() < 1e-5, "pixel {p} channel {k}: {got} vs its own photo's {want}");
            }
            own += 1;
            continue;
        }
        let pt = world(&target_cam, p, 5.0);
        let pc = source_cam.to_camera(pt);
        let (x, y) = (source_cam.fx * pc[0] / pc[2] + source_cam.cx, source_cam.fy * pc[1] / pc[2] + source_cam.cy);
        let inside = x >= 0.0 && y >= 0.0 && x < w as f64 && y < h as f64;
        let in_hole = inside && hole[y as usize * w + x as usize];
        assert_eq!(t.found[p], inside && !in_hole, "pixel {p}");
        blocked += in_hole as usize;
        // away from the source's border, where the Lanczos taps clamp, the color is the surface
        // point's: Lanczos-3 reproduces the photo's ramp (0.008 per pixel) to 0.02 pixel
        if t.found[p] && x > 3.0 && x < w as f64 - 3.0 && y > 3.0 && y < h as f64 - 3.0 {
            let c = color(pt);
            for (k, &ck) in c.iter().enumerate() {
                let cast = if k == 2 { 0.2 } else { 0.0 };
                assert!((t.rgb[k * w * h + p] as f64 - ck - cast).abs() < 5e-4, "pixel {p} channel {k}");
            }
            found += 1;
        }
    }
    assert!(own > 1000 && found > 20 && blocked > 10, "own {own}, found {found}, blocked {blocked}");
    // a completed depth 10 % off does not match what the source rendered there
    let off = vec![5.5f32; w * h];
    let t = transfer(0, &target_cam, &off, &fill, &sources, 0.05);
    assert!(t.found.iter().all(|&f| !f));
}

/// The same two views, each photo with its own per-channel gains (exposure and white balance) of
/// the scene's colors, and the target's whole image covered (no own pixel to match locally): the
/// transfer maps the source's colors back through its gains and on through the target's, so the
/// hole takes the target's colors of each surface point (to the Lanczos-3 interpolation's 5e-4);
/// the source's raw colors are 28-60 % off.
#[test]
fn color_transfer_maps_a_source_photos_exposure_to_the_targets() {
    use cogeo::removal::complete::source_views::SourceView;
    use cogeo::removal::complete::transfer::transfer;
    use cogeo::scene::exposure::ColorAffine;
    use cogeo::scene::Camera;
    let (w, h) = (40usize, 30usize);
    let cam = |name: &str, x: f64| {
        Camera::look_at(name, w as u32, h as u32, 60.0, [x, 0.0, 0.0], [x, 0.0, 5.0], [0.0, -1.0, 0.0])
    };
    let (target_cam, source_cam) = (cam("t", 0.0), cam("s", 0.4));
    let color = |p: [f64; 3]| [0.4 + 0.1 * p[0], 0.4 + 0.1 * p[1], 0.3];
    let (target_gains, source_gains) = ([1.1, 0.9, 1.2], [0.8, 1.25, 0.75]);
    let photo_of = |c: &Camera, gains: [f64; 3]| {
        let mut img = vec![0f32; 3 * w * h];
        for p in 0..w * h {
            let pt = c.pixel_point(p % w, p / w, 5.0);
            let rgb = color(pt);
            for k in 0..3 {
                img[k * w * h + p] = (gains[k] * rgb[k]) as f32;
            }
        }
        img
    };
    let (own_photo, photo) = (photo_of(&target_cam, target_gains), photo_of(&source_cam, source_gains));
    let (covered, open) = (vec![true; w * h], vec![false; w * h]);
    let (depth, alpha) = (vec![5.0f32; w * h], vec![1.0f32; w * h]);
    let sources = [
        SourceView {
            camera: &target_cam,
            photo: &own_photo,
            hole: &covered,
            depth: &depth,
            alpha: &alpha,
            photo_colors: ColorAffine::gains(target_gains),
        },
        SourceView {
            camera: &source_cam,
            photo: &photo,
            hole: &open,
            depth: &depth,
            alpha: &alpha,
            photo_colors: ColorAffine::gains(source_gains),
        },
    ];
    let t = transfer(0, &target_cam, &depth, &vec![true; w * h], &sources, 0.05);
    let mut checked = 0;
    for p in 0..w * h {
        let pt = target_cam.pixel_point(p % w, p / w, 5.0);
        let (x, y, _) = source_cam.project_to_image(pt).map_or((-1.0, -1.0, 0.0), |v| v);
        if !(x > 3.0 && x < w as f64 - 3.0 && y > 3.0 && y < h as f64 - 3.0) {
            continue;
        }
        assert!(t.found[p], "pixel {p}: the source saw it");
        let c = color(pt);
        for k in 0..3 {
            let (got, want) = (t.rgb[k * w * h + p] as f64, target_gains[k] * c[k]);
            assert!((got - want).abs() < 5e-4, "pixel {p} channel {k}: {got} vs the target's {want}");
        }
        checked += 1;
    }
    assert!(checked > 500, "{checked} pixels checked");
}

/// Two sources see a wall from either side, each with its own tint of the target's colors (the
/// light a glossy surface sends their way: +0.1 / -0.05 / +0.03 and -0.08 / +0.06 / 0), the
/// nearer one only the hole's right half, and the target's own photo shows the wall only around
/// the hole (no own pixel inside to match locally): each source's colors are matched to the
/// target's over the points around the hole that both saw (`source_offsets`), so the whole hole
/// takes the target's colors (to 2e-3), not the patchwork of the two tints.
#[test]
fn color_transfer_matches_each_sources_tint_around_the_hole() {
    use cogeo::removal::complete::source_views::SourceView;
    use cogeo::removal::complete::transfer::transfer;
    use cogeo::scene::exposure::ColorAffine;
    use cogeo::scene::Camera;
    let (w, h) = (60usize, 40usize);
    let cam = |name: &str, x: f64| {
        Camera::look_at(name, w as u32, h as u32, 60.0, [x, 0.0, 0.0], [x, 0.0, 5.0], [0.0, -1.0, 0.0])
    };
    let cams = [cam("t", 0.0), cam("left", -0.6), cam("right", 0.4)];
    let color = |p: [f64; 3]| [0.4 + 0.1 * p[0], 0.45 + 0.1 * p[1], 0.35 + 0.05 * p[0]];
    let tints = [[0.0; 3], [0.1, -0.05, 0.03], [-0.08, 0.06, 0.0]];
    let photos: Vec<Vec<f32>> = cams
        .iter()
        .zip(tints)
        .map(|(c, tint)| {
            let mut img = vec![0f32; 3 * w * h];
            for p in 0..w * h {
                let rgb = color(c.pixel_point(p % w, p / w, 5.0));
                (0..3).for_each(|k| img[k * w * h + p] = (rgb[k] + tint[k]) as f32);
            }
            img
        })
        .collect();
    // the hole, and the target's footprint: all of it (the objects covered it in its photo)
    let hole: Vec<bool> = (0..w * h).map(|p| (22..38).contains(&(p % w)) && (12..28).contains(&(p / w))).collect();
    // the nearer source, on the right, had the objects over the hole's left half: the left
    // source fills that half
    let left_half = |q: usize, c: &Camera| {
        let world = c.pixel_point(q % w, q / w, 5.0);
        let in_hole = cams[0].pixel_of(world).is_some_and(|(t, _)| hole[t]);
        world[0] < 0.0 && in_hole
    };
    let covered = [hole.clone(), vec![false; w * h], (0..w * h).map(|q| left_half(q, &cams[2])).collect()];
    let (depth, alpha) = (vec![5.0f32; w * h], vec![1.0f32; w * h]);
    let sources: Vec<SourceView> = (0..3)
        .map(|i| SourceView {
            camera: &cams[i],
            photo: &photos[i],
            hole: &covered[i],
            depth: &depth,
            alpha: &alpha,
            photo_colors: ColorAffine::IDENTITY,
        })
        .collect();
    let t = transfer(0, &cams[0], &depth, &hole, &sources, 0.05);
    let mut checked = 0;
    for p in (0..w * h).filter(|&p| hole[p]) {
        assert!(t.found[p], "pixel {p}: both sources saw it");
        let want = color(cams[0].pixel_point(p % w, p / w, 5.0));
        for (k, &wk) in want.iter().enumerate() {
            let got = t.rgb[k * w * h + p] as f64;
            assert!((got - wk).abs() < 2e-3, "pixel {p} channel {k}: {got} vs the target's {wk}");
        }
        checked += 1;
    }
    assert_eq!(checked, 16 * 16);
}
