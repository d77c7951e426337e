//! Mattes mutual information (Mattes et al. 2001; ALGORITHMS.md §5) — being written.
