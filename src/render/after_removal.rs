//! What `RenderSettings::after_removal` adds to a render: the scene less the removed Gaussians,
//! blended in the same walk over the tile lists (blend.comp's AFTER_REMOVAL).

/// The render of the scene less the removed Gaussians (the feature 1), the same bits a render of
/// that scene alone gives.
#[derive(Clone, Debug)]
pub struct AfterRemoval {
    pub rgb: Vec<f32>,
    pub alpha: Vec<f32>,
    pub expected_depth: Vec<f32>,
    /// Empty unless `RenderSettings::median_depth`.
    pub median_depth: Vec<f32>,
    /// The kept objects' weight (the Gaussians whose feature is 2).
    pub kept_weight: Vec<f32>,
}

/// Planes of blend.comp's `out_after`: R, G, B, alpha, expected depth, median depth, kept weight.
pub(super) const AFTER_PLANES: u64 = 7;

impl AfterRemoval {
    /// From the `AFTER_PLANES` planes of `hw` pixels each read back from `out_after`.
    pub(super) fn from_planes(planes: &[f32], hw: usize, median_depth: bool) -> AfterRemoval {
        let plane = |k: usize| planes[k * hw..(k + 1) * hw].to_vec();
        AfterRemoval {
            rgb: planes[..3 * hw].to_vec(),
            alpha: plane(3),
            expected_depth: plane(4),
            median_depth: if median_depth { plane(5) } else { Vec::new() },
            kept_weight: plane(6),
        }
    }
}
