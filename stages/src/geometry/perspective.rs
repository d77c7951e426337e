//! Artificial perspective views of a panorama (thesis 4.4.1, eq. 4/1–4/3) — being written.
