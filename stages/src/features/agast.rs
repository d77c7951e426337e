//! AGAST corner detector (Mair et al. 2010; ALGORITHMS.md §6) — being written.
