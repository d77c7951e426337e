//! An aerial pose as a reader delivers it, before conversion into the campaign, and the configuration
//! problem every reader reports for a missing key.

use crate::campaign::Problem;
use crate::formats::camera_model::CameraModel;
use crate::formats::opk_list::PoseRow;
use std::path::Path;

/// An oriented image as read, before conversion: pose in the source CRS, camera in campaign convention.
pub(crate) struct SourcePose {
    pub pose: PoseRow,
    pub camera: CameraModel,
}

/// A key the configuration lacks for `file`.
pub(crate) fn missing(file: &Path, key: &str, hint: &str) -> Problem {
    Problem::error(
        "import configuration",
        None,
        Some(key),
        format!("is required for {}", file.display()),
        hint,
    )
}
