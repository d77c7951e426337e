//! Campaign nodes: the synthetic generator, loading and validating a campaign folder, per-item selection of
//! recordings and aerial images, the campaign summary, and the images shared by every pipeline (decoded once
//! per process; cached as artifacts).

pub mod aerial;
pub mod decoded_images;
pub mod image_artifact;
pub mod load;
pub mod panorama_sizes;
pub mod summary;
pub mod synth;
pub mod validate;
