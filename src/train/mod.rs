//! Training: the photometric loss, Adam, datasets and the training loop.

pub mod adam;
pub mod checkpoint;
pub mod dataset;
pub mod fused;
pub mod loss;
pub mod mcmc;
pub mod trainer;
