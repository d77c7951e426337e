//! Bundle adjustment core (thesis 3.5.3 and chapter 5): corrects mobile-mapping recording positions (and,
//! optionally, a yaw correction per recording) from panorama observations of tie points, aerial control
//! points, weak priors on the recorded positions and optional relative constraints along the trajectory.
//!
//! Layers, bottom up: [`error`] (what can go wrong, naming the item), [`weighting`] (residual weighting
//! methods 1–4 of thesis 5.7), [`robust`] (Huber/Cauchy losses), [`problem`] (the block and the options),
//! [`aerial`] (aerial image observations with the aerial orientation fixed), [`residuals`]
//! (residuals and analytic Jacobians), [`parallel`] (thread-count-independent parallel loops), [`sparse`]
//! (block sparse Cholesky with a fill-reducing ordering, and selected inversion), [`layout`] (observations
//! by point and recording, structure of the reduced camera matrix), [`prepared`] (one solve's setup and
//! cost), [`linearization`] (normal-equation blocks), [`schur`] (the reduced camera system), [`solver`]
//! (Levenberg–Marquardt), [`relative_noise`] (the trajectory's relative accuracy from its own second differences),
//! [`gauss_markov`] (the trajectory error as a Gauss–Markov process: how much of a correction the next
//! recording shares), [`yaw_support`] (whether the evidence supports one heading correction per chain),
//! [`covariance`] (posterior σ per recording), [`adjust`](mod@adjust) (solve, reject by
//! normalised residuals, re-solve), [`evaluate`] (check-point triangulation and RMSE), [`id_index`] (rows
//! by their string id), [`synthetic_block`]
//! (known-answer test blocks). On top: [`config`] (the adjust node's params), [`in_frame`] (a block
//! in the campaign's tangent frame and its results back in map coordinates), [`from_correspondences`]
//! (correspondences → block → [`AdjustmentRun`]), [`height_observation`] (recording heights from a terrain
//! model), [`weak_control`] (weak orthophoto control checked against the strong control along the trajectory),
//! [`weak_control_sigma`] (weak control weighted by its σ measured against the strong control),
//! [`control_consistency`] (every control point checked against the neighbouring recordings' control),
//! [`build_counts`] (what went into a block, for `metrics.json`), [`control_screen`] (the evidence of
//! ground control and of aerial pixels in the bundle, and what the checks reject taken out of the block),
//! [`chain_end_evidence`] (a chain end's lone aerial evidence left out when nothing can check it),
//! [`extrapolation_anchor`] (recordings beyond the outermost control tied to its correction),
//! [`second_pass`] (the shifted inputs of a second registration pass around the adjusted trajectory),
//! [`verify`] (thesis Table 5-13 verification per trajectory
//! segment) and [`synthetic_campaign`] (a synthetic block as campaign rows and correspondences, with aerial
//! images, for known-answer tests).
//!
//! Scale: memory and time grow linearly with the observations for a trajectory (a chain of recordings) and
//! with the fill of the sparse factor for street networks with crossings and repeated passes.

pub mod adjust;
pub mod adjust_inputs;
pub mod aerial;
pub mod block_build;
pub mod block_point;
pub mod block_recordings;
pub mod build_counts;
pub mod campaign_checkpoints;
pub mod chain_end_evidence;
pub mod config;
pub mod control_consistency;
pub mod control_screen;
pub mod covariance;
pub mod error;
pub mod evaluate;
pub mod extrapolation_anchor;
pub mod from_correspondences;
pub mod gauss_markov;
pub mod height_observation;
pub mod id_index;
pub mod in_frame;
pub mod layout;
pub mod linearization;
pub mod parallel;
pub mod prepared;
pub mod problem;
pub mod relative_bridge;
pub mod relative_noise;
pub mod relative_release;
pub mod residuals;
pub mod robust;
pub mod schur;
pub mod second_pass;
pub mod solver;
pub mod sparse;
pub mod synthetic_block;
pub mod synthetic_campaign;
pub mod synthetic_streets;
pub mod tie_point_heights;
pub mod trajectory_errors;
pub mod verify;
pub mod weak_control;
pub mod weak_control_sigma;
pub mod weighting;
pub mod yaw_support;

pub use adjust::{adjust, AdjustedRecording, Adjustment, ObservationCounts, RoundReport};
pub use config::{AdjustConfig, ControlWeighting, Dimensions, LossKind, Sources, TrajectoryError};
pub use error::AdjustError;
pub use evaluate::{
    evaluate_checkpoints, CheckObservation, CheckPointError, CheckPointEvaluation, RmseSummary,
    ViewSelection,
};
pub use from_correspondences::{
    build_block, run, run_in_frame, AdjustInputs, AdjustmentRun, BlockBuild, BlockPoint,
    BuildCounts, HeldComponents, PointKind, RunPoint, RunRecording,
};
pub use problem::{
    AdjustOptions, AerialImageObservation, Block, BlockRecording, ControlPoint, HeightObservation,
    LmOptions, PanoObservation, PointHeight, RelativeConstraint,
};
pub use robust::RobustLoss;
pub use solver::Termination;
pub use synthetic_block::{consecutive_constraints, SyntheticBlock, SyntheticBlockSpec};
pub use weighting::{ResidualWeighting, WeightingMethod};
