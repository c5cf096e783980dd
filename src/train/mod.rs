//! Training: the photometric loss, Adam, the training loop, densification and checkpoints.

pub mod adam;
pub mod checkpoint;
pub mod config;
pub mod exposure;
pub mod fused;
pub mod loss;
pub mod mcmc;
pub mod trainer;
