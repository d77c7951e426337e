//! Geometry core: rotations and the ω-φ-κ / panorama conventions of campaign-format.md, the panorama and
//! frame cameras, rays and planes, multi-view triangulation, 2-D similarity and homography, local origins.
//!
//! World coordinates are f64 metres in a projected frame (X east, Y north, Z up); angles carry their unit in
//! the name (`_deg`, `_rad`); pixels are continuous (first pixel centre at (0.5, 0.5)).

// `!(x > t)` is used on purpose throughout: it also rejects NaN, which `x <= t` would let through.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

pub mod aerial_intersection;
pub mod atan2_poly;
pub mod bounds;
pub mod closest_approach;
pub mod distortion;
pub mod frame;
pub mod homography;
pub mod homography_refine;
pub mod local_frame;
pub mod panorama;
pub mod perspective;
pub mod point_pair;
pub mod ray;
pub mod rotation;
pub mod similarity2;
pub mod triangulation;
pub mod trifocal;

#[cfg(test)]
mod tests;

pub use bounds::bounding_box;
pub use closest_approach::{closest_approach, ClosestApproach};
pub use distortion::BrownDistortion;
pub use frame::FrameCamera;
pub use homography::Homography;
pub use local_frame::LocalOrigin;
pub use panorama::PanoramaCamera;
pub use point_pair::PointPair;
pub use ray::{intersect_ray_plane, Plane, Ray};
pub use rotation::{
    look_at_matrix, matrix_to_opk, opk_to_matrix, panorama_rotation, rot_x, rot_y, rot_z,
};
pub use similarity2::Similarity2;
pub use triangulation::{triangulate_rays, Triangulation, TriangulationError};
