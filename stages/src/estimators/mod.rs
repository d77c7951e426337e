//! Robust estimation: the deterministic PRNG of [`crate::rng`], generic RANSAC ([`ransac`](mod@ransac)) and the [`Model`]
//! implementations of the 2-D transforms of [`crate::geometry`] ([`models`]), and the quantiles that turn a
//! significance level into a test's threshold ([`normal_quantile`]).

// `!(x > t)` is used on purpose throughout: it also rejects NaN, which `x <= t` would let through.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

pub mod median_consensus;
pub mod mlesac;
pub mod models;
pub mod normal_quantile;
pub mod one_plus_one;
pub mod ransac;

#[cfg(test)]
mod tests;

pub use crate::rng::{mix64, mix_seed, SplitMix64};
pub use ransac::{ransac, ransac_filtered, required_iterations, Model, RansacParams, RansacResult};
