//! What an adjusted correction rests on and how precise it is, per recording: the support classification
//! ([`support`]: its own aerial control, control on both sides, on one side, none) and the σ of recordings
//! without control of their own ([`off_control_sigma`]), both read from an [`crate::adjustment::AdjustmentRun`],
//! and which corrections are significant enough to apply ([`significance`]). The adjust node applies them to
//! every run, so all outputs ([`crate::export`]) carry them.

#[cfg(test)]
pub(crate) mod fixture;
pub mod off_control_sigma;
pub mod significance;
pub mod support;

pub use off_control_sigma::{widen_off_control_sigma, OffControlSigma, VariogramBin};
pub use significance::{hold_insignificant, Significance};
pub use support::{linked_groups, recording_support, RecordingSupport, Support};
