//! Median consensus and oblique control points (thesis 4.4.7) — being written.
