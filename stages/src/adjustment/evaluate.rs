//! Check-point evaluation (thesis 3.5.3): check points are triangulated from their panorama observations with
//! given poses (recorded or adjusted) and compared with their surveyed coordinates; RMSE per axis, 2-D and 3-D
//! (Tables 3-3…3-5, 5-2…5-9). Two view selections as in 3.5.3: the two recordings nearest to the check point,
//! and all recordings within a radius (15 m). Check points are never used as control.

use crate::geometry::{triangulate_rays, PanoramaCamera};
use nalgebra::Vector3;

/// Default radius of the multi-view selection, metres (thesis 3.5.3).
pub const MULTI_VIEW_RADIUS_M: f64 = 15.0;

/// A panorama observation of check point `check_point` in recording `recording`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CheckObservation {
    pub check_point: usize,
    pub recording: usize,
    pub u_px: f64,
    pub v_px: f64,
}

/// Which observations of a check point are triangulated.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum ViewSelection {
    /// The two recordings whose centres are nearest to the surveyed point.
    TwoNearest,
    /// All recordings whose centres lie within `radius_m` of the surveyed point.
    WithinRadius { radius_m: f64 },
}

/// The error of one triangulated check point.
#[derive(Clone, Debug, PartialEq)]
pub struct CheckPointError {
    pub check_point: usize,
    /// Recordings used.
    pub views: usize,
    pub estimated_world: Vector3<f64>,
    /// Estimated − surveyed, metres (X, Y, Z).
    pub error_m: Vector3<f64>,
}

/// Root-mean-square errors, metres (thesis Tables 3-3…3-5, 5-2…5-9).
#[derive(Clone, Copy, Debug, PartialEq, Default, serde::Serialize, serde::Deserialize)]
pub struct RmseSummary {
    pub x: f64,
    pub y: f64,
    pub z: f64,
    pub d2: f64,
    pub d3: f64,
    /// Points included.
    pub count: usize,
}

/// Per-point errors, points that could not be triangulated (with the reason) and the RMSE.
#[derive(Clone, Debug, PartialEq)]
pub struct CheckPointEvaluation {
    pub points: Vec<CheckPointError>,
    pub failed: Vec<(usize, String)>,
    pub rmse: RmseSummary,
}

impl RmseSummary {
    /// RMSE of a set of error vectors (all zeros for an empty set).
    pub fn from_errors<'a>(errors: impl IntoIterator<Item = &'a Vector3<f64>>) -> Self {
        let (mut sx, mut sy, mut sz, mut n) = (0.0, 0.0, 0.0, 0usize);
        for e in errors {
            sx += e.x * e.x;
            sy += e.y * e.y;
            sz += e.z * e.z;
            n += 1;
        }
        if n == 0 {
            return Self::default();
        }
        let nf = n as f64;
        Self {
            x: (sx / nf).sqrt(),
            y: (sy / nf).sqrt(),
            z: (sz / nf).sqrt(),
            d2: ((sx + sy) / nf).sqrt(),
            d3: ((sx + sy + sz) / nf).sqrt(),
            count: n,
        }
    }
}

/// Triangulates every check point (`surveyed_world[i]`) from its observations in `cameras` (indexed by
/// `CheckObservation::recording`) with the given selection; `sigma_px` weights the rays.
pub fn evaluate_checkpoints(
    cameras: &[PanoramaCamera],
    surveyed_world: &[Vector3<f64>],
    observations: &[CheckObservation],
    selection: ViewSelection,
    sigma_px: f64,
) -> CheckPointEvaluation {
    let mut per_point: Vec<Vec<&CheckObservation>> = vec![Vec::new(); surveyed_world.len()];
    let mut failed = Vec::new();
    for o in observations {
        if o.check_point < surveyed_world.len() && o.recording < cameras.len() {
            per_point[o.check_point].push(o);
        }
    }
    let mut points = Vec::new();
    let mut rays = Vec::new();
    let mut sigmas = Vec::new();
    for (cp, obs) in per_point.iter_mut().enumerate() {
        let truth = surveyed_world[cp];
        let distance = |o: &CheckObservation| (cameras[o.recording].center_world - truth).norm();
        // Stable order: by distance, then recording index.
        obs.sort_by(|a, b| {
            distance(a)
                .total_cmp(&distance(b))
                .then(a.recording.cmp(&b.recording))
        });
        let chosen: Vec<&CheckObservation> = match selection {
            ViewSelection::TwoNearest => obs.iter().take(2).copied().collect(),
            ViewSelection::WithinRadius { radius_m } => obs
                .iter()
                .filter(|o| distance(o) <= radius_m)
                .copied()
                .collect(),
        };
        rays.clear();
        sigmas.clear();
        for o in &chosen {
            let cam = &cameras[o.recording];
            rays.push(cam.pixel_ray(o.u_px, o.v_px));
            sigmas.push(cam.angular_sigma_rad(sigma_px));
        }
        match triangulate_rays(&rays, &sigmas) {
            Ok(t) => points.push(CheckPointError {
                check_point: cp,
                views: chosen.len(),
                estimated_world: t.point_world,
                error_m: t.point_world - truth,
            }),
            Err(e) => failed.push((cp, e.to_string())),
        }
    }
    let rmse = RmseSummary::from_errors(points.iter().map(|p| &p.error_m));
    CheckPointEvaluation {
        points,
        failed,
        rmse,
    }
}
