//! Patch registration, coarse/fine (thesis 4.4.6) — being written.
