//! Trifocal tensor from three projection matrices and point transfer (ALGORITHMS.md §7) — being written.
