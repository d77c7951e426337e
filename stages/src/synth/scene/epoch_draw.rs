//! Which epoch an element of the scene is present in when the `epoch` error profile changes it: a draw hashed
//! from the scene seed, the kind of element and its index, so that every other element stays as it is.

use super::objects::{IN_AERIAL, IN_MM};
use crate::synth::noise::{mix64, unit_f64};

/// A uniform number in [0, 1) for (seed, what, index).
pub fn draw(seed: u64, what: u64, index: u64) -> f64 {
    unit_f64(mix64(seed ^ mix64(what ^ mix64(index))))
}

/// One-epoch presence of element `index`: `Some(IN_MM or IN_AERIAL)` with probability `fraction`.
pub fn changed_epochs(seed: u64, what: u64, index: u64, fraction: f64) -> Option<u8> {
    (draw(seed, what, index) < fraction).then(|| {
        if draw(seed, what ^ 0x5EED, index) < 0.5 {
            IN_MM
        } else {
            IN_AERIAL
        }
    })
}
