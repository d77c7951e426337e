//! Known-answer tests of the estimators (Hartley & Zisserman 2004, ch. 4).

mod fixtures;
mod ransac_homography_tests;
mod ransac_similarity_tests;
mod ransac_tests;
mod rng_tests;
