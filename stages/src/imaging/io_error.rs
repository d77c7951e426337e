//! The error of reading or writing an image file: the file and what to do.

use std::path::Path;

/// An image file that could not be read or written; the message names the file and what to do.
#[derive(Debug, thiserror::Error)]
#[error("{path}: {message}")]
pub struct ImageIoError {
    pub path: String,
    pub message: String,
}

impl ImageIoError {
    pub fn new(path: &Path, message: impl Into<String>) -> Self {
        ImageIoError {
            path: path.display().to_string(),
            message: message.into(),
        }
    }
}
