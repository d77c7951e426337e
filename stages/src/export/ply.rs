//! `tie_points.ply` (CloudCompare, binary little-endian through [`crate::campaign::write_ply`]): the adjusted
//! tie points coloured by source — MM tie points grey, aerial control points (≥ 2 aerial images) red,
//! single-aerial control points orange — and the adjusted recording centres blue. The integer property
//! `source` carries the same classes ([`PLY_SOURCE_TIE`] …) for filtering.

use crate::adjustment::{AdjustmentRun, PointKind};
use crate::campaign::{write_ply, PlyPoint};
use std::io;
use std::path::Path;

pub const PLY_SOURCE_TIE: i32 = 0;
pub const PLY_SOURCE_CONTROL: i32 = 1;
pub const PLY_SOURCE_SINGLE_AERIAL: i32 = 2;
pub const PLY_SOURCE_RECORDING: i32 = 3;

/// Colour of each source class.
pub fn source_colour(source: i32) -> [u8; 3] {
    match source {
        PLY_SOURCE_CONTROL => [220, 30, 30],
        PLY_SOURCE_SINGLE_AERIAL => [250, 150, 0],
        PLY_SOURCE_RECORDING => [30, 90, 230],
        _ => [170, 170, 170],
    }
}

/// The vertices: determined tie points (in block order), then the adjusted recording centres.
pub fn ply_points(run: &AdjustmentRun) -> Vec<PlyPoint> {
    let mut out = Vec::with_capacity(run.points.len() + run.recordings.len());
    for p in run.points.iter().filter(|p| p.determined) {
        let source = match p.point.kind {
            PointKind::Tie => PLY_SOURCE_TIE,
            PointKind::Control => PLY_SOURCE_CONTROL,
            PointKind::SingleAerial => PLY_SOURCE_SINGLE_AERIAL,
        };
        out.push(PlyPoint {
            xyz_world: p.position_world,
            rgb: source_colour(source),
            source,
        });
    }
    for r in &run.recordings {
        out.push(PlyPoint {
            xyz_world: r.adjusted_world,
            rgb: source_colour(PLY_SOURCE_RECORDING),
            source: PLY_SOURCE_RECORDING,
        });
    }
    out
}

/// Writes `tie_points.ply` (atomically).
pub fn write_tie_points_ply(path: &Path, run: &AdjustmentRun) -> io::Result<()> {
    write_ply(path, &ply_points(run))
}
