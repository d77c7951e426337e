//! DAISY descriptor (Tola, Lepetit, Fua 2010; ALGORITHMS.md §6) — being written.
