//! The oblique pipeline's nodes (thesis chapter 4): sparse clouds per panorama triplet, façade planes,
//! image-to-plane patch registration, the 3-D consensus with oblique control points, and the grading on truth.

pub mod consensus;
pub mod facades;
pub mod grade;
pub mod options;
pub mod patches;
pub mod sparse_cloud;
