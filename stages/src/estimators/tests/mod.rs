//! Known-answer tests of the estimators (ALGORITHMS.md §11).

mod ransac_homography_tests;
mod ransac_similarity_tests;
mod ransac_tests;
mod rng_tests;
