//! (placeholder: being written in session 2)
