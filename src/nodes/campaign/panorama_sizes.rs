//! Panorama sizes read from the files' headers, for the nodes that need image geometry without pixels
//! (adjustment, verification, oblique consensus).

use crate::dag::{RawFileValue, StageError};
use skytie_stages::imaging::io::dimensions;

/// Panorama sizes from the panorama files (parallel to the campaign's recordings).
pub fn pano_sizes(panos: &[RawFileValue]) -> Result<Vec<(u32, u32)>, StageError> {
    panos
        .iter()
        .map(|p| dimensions(&p.path).map_err(|e| StageError::new(e.to_string())))
        .collect()
}
