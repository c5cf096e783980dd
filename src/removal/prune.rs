//! Stage 4b of removal, pruning (kiddo): a background Gaussian is pruned when it lies within
//! `near` of a patch Gaussian AND has fewer than `min_neighbours` other background Gaussians
//! within `radius`.

use kiddo::{KdTree, SquaredEuclidean};

/// Pruning as the user sets it: each distance not given follows the patch spacing s.
#[derive(Clone, Debug, serde::Serialize, clap::Args)]
pub struct PruneSettings {
    /// Pruning: distance to the nearest patch Gaussian that makes a background Gaussian a candidate
    /// (scene units; default twice the patch spacing, or 2/3 of --prune-radius).
    #[arg(id = "prune-near", long = "prune-near")]
    pub near: Option<f64>,
    /// Pruning: neighbourhood radius of the density test (default three times the patch spacing,
    /// or 1.5 times --prune-near).
    #[arg(id = "prune-radius", long = "prune-radius")]
    pub radius: Option<f64>,
    /// Pruning: candidates with fewer background neighbours within the radius are pruned.
    #[arg(id = "prune-min-neighbours", long = "prune-min-neighbours", default_value_t = 4)]
    pub min_neighbours: usize,
}

crate::default_from_flags!(PruneSettings);

impl PruneSettings {
    /// The criteria, with `spacing()` (the patch spacing s) giving near 2 s and radius 3 s when
    /// neither distance is set.
    pub fn resolve(&self, spacing: impl FnOnce() -> f64) -> PruneConfig {
        let (near, radius) = match (self.near, self.radius) {
            (None, None) => {
                let s = spacing();
                (2.0 * s, 3.0 * s)
            }
            (Some(near), radius) => (near, radius.unwrap_or(near * 1.5)),
            (None, Some(radius)) => (radius * 2.0 / 3.0, radius),
        };
        PruneConfig { near, radius, min_neighbours: self.min_neighbours }
    }
}

#[derive(Clone, Debug, serde::Serialize)]
pub struct PruneConfig {
    /// A background Gaussian within this distance of a patch Gaussian is a candidate.
    pub near: f64,
    /// Neighbourhood radius of the density test.
    pub radius: f64,
    /// Candidates with fewer background neighbours than this within `radius` are pruned.
    pub min_neighbours: usize,
}

/// Which background Gaussians to prune (true = prune).
pub fn prune_mask(background: &[[f32; 3]], patch: &[[f32; 3]], cfg: &PruneConfig) -> Vec<bool> {
    if patch.is_empty() || background.is_empty() {
        return vec![false; background.len()];
    }
    let mut patch_tree: KdTree<f64, 3> = KdTree::new();
    for (i, p) in patch.iter().enumerate() {
        patch_tree.add(&p.map(|v| v as f64), i as u64);
    }
    let mut bg_tree: KdTree<f64, 3> = KdTree::new();
    for (i, p) in background.iter().enumerate() {
        bg_tree.add(&p.map(|v| v as f64), i as u64);
    }
    background
        .iter()
        .map(|p| {
            let q = p.map(|v| v as f64);
            let nearest = patch_tree.nearest_one::<SquaredEuclidean>(&q);
            if nearest.distance > cfg.near * cfg.near {
                return false;
            }
            // within_unsorted counts the Gaussian itself
            let neighbours = bg_tree.within_unsorted::<SquaredEuclidean>(&q, cfg.radius * cfg.radius).len() - 1;
            neighbours < cfg.min_neighbours
        })
        .collect()
}
