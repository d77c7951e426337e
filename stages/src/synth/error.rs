//! Errors of the synthetic campaign generator; each names the file or option concerned and what to do.

/// Why a synthetic campaign could not be generated.
#[derive(Debug, thiserror::Error)]
pub enum SynthError {
    #[error("unknown synthetic preset '{name}'; valid presets are: {valid}")]
    UnknownPreset { name: String, valid: String },
    #[error("{path}: {message}")]
    Io { path: String, message: String },
    #[error(
        "{path} exists and is not a synthetic campaign (no campaign.toml and truth/README.md); \
         choose another output folder or delete it"
    )]
    OutputExists { path: String },
    #[error("scene area {area} of preset '{preset}' has no usable driving route (fewer than 2 route points)")]
    EmptyRoute { preset: String, area: usize },
    #[error("invalid synthetic option {option}: {message}")]
    InvalidOption { option: String, message: String },
}

impl SynthError {
    /// An I/O error about `path`.
    pub fn io(path: &std::path::Path, e: impl std::fmt::Display) -> Self {
        SynthError::Io {
            path: path.display().to_string(),
            message: e.to_string(),
        }
    }
}
