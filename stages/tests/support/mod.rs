//! Fixtures shared by the integration tests of `skytie-stages`: a straight street of recordings driving east
//! and oblique cameras aimed at known points (each test file uses what it needs).

#![allow(dead_code)]

use nalgebra::Vector3;
use skytie_stages::campaign::{AerialImage, Recording};
use skytie_stages::crs::{CoordinateFrame, MapFrame, MapFrameSpec};
use skytie_stages::geometry::{look_at_matrix, matrix_to_opk};
use std::path::{Path, PathBuf};

pub mod adjusted;
pub mod campaign_files;
pub mod ortho_pair;
pub mod texture;
pub mod tiny;

/// Easting of the street's first recording, metres.
pub const E0: f64 = 500_000.0;
/// Northing of the street, metres.
pub const N0: f64 = 5_400_000.0;

/// Recording `i` of the street: 5 m and 1 s apart driving east (heading 90°) from (E0, N0), projection centre
/// at height `z_m`, camera 2.5 m above the road.
pub fn street_recording(id: &str, i: usize, z_m: f64) -> Recording {
    Recording::new(id, i as f64, [E0 + 5.0 * i as f64, N0, z_m], 90.0, 2.5)
}

/// The tangent frame of a campaign declared `projected` in `crs`, with its origin near `site_map` (map
/// coordinates, metres).
pub fn projected_map_frame(crs: &str, site_map: Vector3<f64>) -> MapFrame {
    let (spec, note) = MapFrameSpec::for_campaign(
        CoordinateFrame::Projected,
        crs,
        Some([site_map.x, site_map.y, site_map.z]),
    );
    assert!(note.is_none(), "{note:?}");
    MapFrame::from_spec(&spec).unwrap()
}

/// The demo campaign folder that `SKYTIE_DEMO` names, for the ignored tests that measure on it; `None` (and
/// a line saying so) when it is not set.
pub fn demo_campaign_dir() -> Option<PathBuf> {
    let dir = std::env::var("SKYTIE_DEMO").ok();
    if dir.is_none() {
        println!("SKYTIE_DEMO not set (the demo campaign folder); nothing to do");
    }
    dir.map(PathBuf::from)
}

/// The data rows of the CSV file at `path`, after checking that its header row is `header`.
pub fn csv_records(path: &Path, header: &[&str]) -> Vec<csv::StringRecord> {
    let mut reader = csv::Reader::from_path(path).unwrap();
    assert_eq!(reader.headers().unwrap().iter().collect::<Vec<_>>(), header);
    reader.records().map(Result::unwrap).collect()
}

/// An ideal oblique camera at `centre` looking at `target` (world frame, metres), 4000×3000 px, f = 8000 px.
pub fn oblique_looking_at(id: &str, centre: Vector3<f64>, target: Vector3<f64>) -> AerialImage {
    let (omega_deg, phi_deg, kappa_deg) = matrix_to_opk(&look_at_matrix(&centre, &target));
    AerialImage::ideal(
        id,
        [centre.x, centre.y, centre.z],
        [omega_deg, phi_deg, kappa_deg],
        8000.0,
        [4000, 3000],
    )
}
