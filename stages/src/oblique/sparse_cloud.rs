//! Sparse cloud of a panorama triplet (thesis 4.4.1) — being written.
