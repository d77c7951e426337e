//! Sparse linear algebra of the adjustment, on 4 × 4 blocks (one block row per recording): a
//! fill-reducing ordering ([`ordering`]), the symbolic analysis ([`symbolic`]), the numeric Cholesky
//! factorisation and solves ([`factor`]) and the selected inverse for posterior covariances
//! ([`selected_inverse`]), over the dense block kernels ([`block4`]) and one index container ([`csr`]).
//! Nothing here knows about photogrammetry.

pub mod block4;
pub mod csr;
pub mod factor;
pub mod ordering;
pub mod selected_inverse;
pub mod symbolic;

pub use block4::{Block, BlockVector};
pub use csr::Csr;
pub use factor::{Factor, Pivot};
pub use selected_inverse::SelectedInverse;
pub use symbolic::{Slot, Symbolic};
