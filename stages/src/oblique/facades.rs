//! Façade planes, visibility hypothesis and thinning (thesis 4.4.2–4.4.4) — being written.
