//! MLESAC plane fitting (Torr & Zisserman 2000; ALGORITHMS.md §8) — being written.
