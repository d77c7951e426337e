//! Why an adjustment could not be set up or solved: every error names the offending item (recording, tie
//! point, observation, option) and says what to do. A module of its own, below everything else of the
//! adjustment, so that the block description and the option types it holds (robust loss, residual
//! weighting) can all report errors without depending on each other.

/// Why an adjustment could not be set up or solved.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum AdjustError {
    #[error("the block has no recordings; add at least one recording")]
    NoRecordings,
    #[error("recording {index}: {field} = {value} is not valid ({hint})")]
    InvalidRecording {
        index: usize,
        field: &'static str,
        value: f64,
        hint: &'static str,
    },
    #[error(
        "tie point {index}: initial coordinates are not finite; triangulate it first or drop it"
    )]
    InvalidPoint { index: usize },
    #[error("panorama observation {index}: {problem}")]
    InvalidPanoObservation { index: usize, problem: String },
    #[error("control point {index}: {problem}")]
    InvalidControlPoint { index: usize, problem: String },
    #[error("aerial observation {index}: {problem}")]
    InvalidAerialObservation { index: usize, problem: String },
    #[error("{item}: {problem}")]
    InvalidInput { item: String, problem: String },
    #[error("relative constraint {index}: {problem}")]
    InvalidRelativeConstraint { index: usize, problem: String },
    #[error("option {field} = {value} is not valid ({hint})")]
    InvalidOption {
        field: &'static str,
        value: f64,
        hint: &'static str,
    },
    #[error(
        "the reduced normal matrix is singular at recording {recording} (parameter {parameter}): the block does \
         not determine it; add priors (sigma_xy/sigma_z), control points or observations of that recording"
    )]
    Singular { recording: usize, parameter: usize },
}
