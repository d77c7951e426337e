//! Campaign nodes: the synthetic generator, loading and validating a campaign folder, per-item selection of
//! recordings and aerial images, the campaign summary, and the images shared by every pipeline (each image
//! file ingested once into a tiled pyramid; tiles shared through one cache sized by the memory budget).

pub mod aerial;
pub mod image_artifact;
pub mod image_tiles;
pub mod ingest;
pub mod load;
pub mod map_frame;
pub mod panorama_sizes;
pub mod row_index;
pub mod summary;
pub mod synth;
pub mod validate;
