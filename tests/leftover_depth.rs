//! The leftovers' depth against the closed form of a textured wall (common/wall.rs): a fill
//! pixel takes the depth of the Gaussians left behind the object only where the other views'
//! photos agree on it better than on the completed depth.

mod common;

use cogeo::removal::complete::leftover_depth::prefer_leftover_depth;
use cogeo::removal::complete::Completed;
use common::wall::{self, WALL_Z};

/// Four fill regions of a view of the wall (z = 5), with a completed and a leftover depth each:
/// A, completed 2 % too near, leftover on the wall: the photos agree on the leftover, which wins;
/// B, the other way round: the completion stays;
/// C, completed 20 % too near, where no view's depth says it saw the point, leftover on the wall:
///    only the leftover's point was seen, and it wins;
/// D, completed 20 % too near, no leftover (not covered): stays.
#[test]
fn fill_takes_the_leftover_depth_only_where_the_photos_agree_on_it_better() {
    let (w, h) = (96usize, 72usize);
    let rig = wall::Rig::new(w, h);
    let sources = rig.sources();
    let region = |p: usize| {
        let (x, y) = (p % w, p / w);
        match (x, y) {
            (20..40, 16..34) => Some('A'),
            (56..76, 16..34) => Some('B'),
            (20..40, 40..58) => Some('C'),
            (56..76, 40..58) => Some('D'),
            _ => None,
        }
    };
    let z = WALL_Z as f32;
    // (completed, leftover) depth
    let depths = |p: usize| match region(p) {
        Some('A') => (0.98 * z, z),
        Some('B') => (z, 0.98 * z),
        Some('C') => (0.8 * z, z),
        Some('D') => (0.8 * z, 0.0),
        _ => (z, z),
    };
    let completed_at = |p: usize| depths(p).0;
    let fill: Vec<bool> = (0..w * h).map(|p| region(p).is_some()).collect();
    let leftover: Vec<f32> = (0..w * h).map(|p| depths(p).1).collect();
    let mut completed = Completed::unguided(fill.clone(), vec![0.5; 3 * w * h], (0..w * h).map(completed_at).collect());
    let taken = prefer_leftover_depth(0, &rig.cams[0], &mut completed, &leftover, &sources, &rig.interleaved, 0.05);
    // the share of region r's pixels seen twice whose depth is the wall's
    let on_wall = |r: char| {
        let pixels: Vec<usize> = (0..w * h).filter(|&p| region(p) == Some(r) && rig.seen_twice(p)).collect();
        assert!(pixels.len() > 300, "region {r}: {} pixels", pixels.len());
        pixels.iter().filter(|&&p| completed.depth[p] == z).count() as f64 / pixels.len() as f64
    };
    let (a, c) = (on_wall('A'), on_wall('C'));
    assert!(a > 0.95 && c > 0.95, "the leftover depth where the photos agree on it: A {a}, C {c}");
    let b = on_wall('B');
    assert!(b == 1.0, "the completed depth where the photos agree on it: B {b}");
    assert!((0..w * h).filter(|&p| region(p) == Some('D')).all(|p| completed.depth[p] == 0.8 * z), "D: no leftover");
    assert!((0..w * h).filter(|&p| !fill[p]).all(|p| completed.depth[p] == z), "off the fill nothing changes");
    let changed = (0..w * h).filter(|&p| completed.depth[p] != completed_at(p)).count();
    assert_eq!(taken, changed);
}
