//! Image-to-plane patch projection (thesis 4.4.5) — being written.
