//! (1+1) evolutionary optimiser (Styner et al. 2000; ALGORITHMS.md §5) — being written.
