//! Robust estimation: a deterministic PRNG ([`rng`]), generic RANSAC ([`ransac`]) and the [`Model`]
//! implementations of the 2-D transforms of [`crate::geometry`] ([`models`]).

// `!(x > t)` is used on purpose throughout: it also rejects NaN, which `x <= t` would let through.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

pub mod median_consensus;
pub mod mlesac;
pub mod models;
pub mod one_plus_one;
pub mod ransac;
pub mod rng;

#[cfg(test)]
mod tests;

pub use ransac::{ransac, ransac_filtered, required_iterations, Model, RansacParams, RansacResult};
pub use rng::{mix64, mix_seed, SplitMix64};
