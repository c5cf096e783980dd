//! How many pixels each invocation of the blend passes owns, per device (`BlendLayout`).

use anyhow::{bail, Result};

/// Pixels per invocation of the blend passes on one device. An invocation owns a block of a 16x16
/// tile, so it fetches each Gaussian once for the block (forward) and shares a Gaussian's
/// subgroup reductions and atomics over it (backward). Each count is 1, 2, 4, 8 or 16.
#[derive(Clone, Copy, Debug)]
pub struct BlendLayout {
    /// blend.comp: a column of this many rows.
    pub forward_rows: u32,
    /// blend_backward: a block of rows x columns.
    pub backward_rows: u32,
    pub backward_cols: u32,
    /// blend_features_backward: a column of this many rows.
    pub feature_rows: u32,
}

impl BlendLayout {
    /// One pixel per invocation: the INRIA and gsplat layout.
    pub const PIXEL: BlendLayout = BlendLayout { forward_rows: 1, backward_rows: 1, backward_cols: 1, feature_rows: 1 };

    /// The layout for this device. Measured on llvmpipe with the subgroup-fed blends (a trained 31.5k
    /// scene at 256x192, ms per pass, repeated runs): forward rows 2/4/8/16 took 216/149/106-132/71-100;
    /// the color backward with 4 x 2, 8 x 1, 8 x 2, 16 x 1 and 16 x 2 pixels 201/206/123/155/95-161
    /// (one pixel per invocation: 437 and 895). GPUs keep a pixel per invocation until measured there.
    pub fn for_device(info: &crate::gpu::DeviceInfo) -> BlendLayout {
        if info.is_cpu() {
            BlendLayout { forward_rows: 16, backward_rows: 16, backward_cols: 2, feature_rows: 4 }
        } else {
            BlendLayout::PIXEL
        }
    }

    pub(crate) fn check(&self) -> Result<()> {
        let counts = [self.forward_rows, self.backward_rows, self.backward_cols, self.feature_rows];
        if !counts.iter().all(|v| matches!(v, 1 | 2 | 4 | 8 | 16)) {
            bail!("blend layout {self:?}: each count must be 1, 2, 4, 8 or 16");
        }
        Ok(())
    }
}
