//! (placeholder: exports being written in session 2)
