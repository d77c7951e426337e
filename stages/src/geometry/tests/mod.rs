//! Known-answer tests of the geometry core (campaign-format.md conventions, Hartley & Zisserman 2004).

mod closest_approach_tests;
mod frame_tests;
mod homography_tests;
mod local_frame_tests;
mod panorama_tests;
mod ray_tests;
mod rotation_tests;
mod similarity_tests;
mod triangulation_tests;
