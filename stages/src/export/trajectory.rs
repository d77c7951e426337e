//! `trajectory_adjusted.csv`: the `mm/recordings.csv` columns with the adjusted x, y, z (and yaw + estimated
//! correction) plus the posterior `sigma_x, sigma_y, sigma_z` (metres), through
//! [`crate::campaign::write_trajectory_adjusted_csv`] so it reads back as a recordings file.

use crate::adjustment::AdjustmentRun;
use crate::campaign::{write_trajectory_adjusted_csv, Recording};
use std::io;
use std::path::Path;

/// The recordings with adjusted positions and yaw, and their posterior σ (x, y, z), metres. The run's
/// recordings must be `recordings` in the same order.
pub fn adjusted_recordings(
    recordings: &[Recording],
    run: &AdjustmentRun,
) -> io::Result<Vec<(Recording, [f64; 3])>> {
    if run.recordings.len() != recordings.len() {
        return Err(io::Error::new(
            io::ErrorKind::InvalidInput,
            format!(
                "the adjustment has {} recordings, the campaign {}; pass the recordings it was run on",
                run.recordings.len(),
                recordings.len()
            ),
        ));
    }
    recordings
        .iter()
        .zip(&run.recordings)
        .map(|(r, a)| {
            if a.image_id != r.image_id {
                return Err(io::Error::new(
                    io::ErrorKind::InvalidInput,
                    format!(
                        "adjusted recording '{}' does not match campaign recording '{}'",
                        a.image_id, r.image_id
                    ),
                ));
            }
            let mut adjusted = r.clone();
            [adjusted.x, adjusted.y, adjusted.z] = a.adjusted_world;
            adjusted.yaw_deg = r.yaw_deg + a.yaw_correction_deg;
            Ok((adjusted, a.sigma_m))
        })
        .collect()
}

/// Writes `trajectory_adjusted.csv` (atomically).
pub fn write_adjusted_trajectory(
    path: &Path,
    recordings: &[Recording],
    run: &AdjustmentRun,
) -> io::Result<()> {
    write_trajectory_adjusted_csv(path, &adjusted_recordings(recordings, run)?)
}
