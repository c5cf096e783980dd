//! Training: the photometric loss, Adam, datasets and the training loop.

pub mod adam;
pub mod loss;
