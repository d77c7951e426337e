//! The adjustment in the campaign's Cartesian frame ([`MapFrame`]): a block in map coordinates taken into the
//! tangent frame of the campaign's projected CRS, and the adjustment's results taken back into map
//! coordinates.
//!
//! Why: an aerial image observation in the bundle is a ray of hundreds of metres from a fixed aerial camera.
//! Projected in map coordinates as if they were Cartesian, it carries the map projection's scale error and the
//! earth's curvature (`crate::crs::error_budget`: centimetres at 500–1000 m flying height); projected in the
//! tangent frame, it does not. Everything else the block holds converts with it — recording centres and
//! attitudes (turned by the meridian convergence), initial tie points, control points and their covariances,
//! the fixed aerial cameras, observed heights — so the panorama observations, priors and relative constraints
//! mean the same in both frames. Priors keep their σ: horizontal σ are the same in every horizontal direction, and the tangent
//! frame's vertical tilts from the local vertical by distance/earth radius (1.6·10⁻⁴ rad at 1 km).
//!
//! Back in map coordinates, a posterior σ vector (x, y, z) is turned as the diagonal of a covariance
//! `R·diag(σ²)·Rᵀ`; its off-diagonal terms are not kept (the adjustment reports σ per axis only).

use super::adjust::Adjustment;
use super::error::AdjustError;
use super::problem::{Block, BlockRecording, ControlPoint, HeightObservation, PointHeight};
use crate::crs::{FrameError, MapFrame};
use nalgebra::{Matrix3, Vector3};

fn frame_error(e: FrameError) -> AdjustError {
    AdjustError::InvalidInput {
        item: "campaign frame".to_string(),
        problem: format!(
            "{e}; check the campaign's crs, or declare frame = \"cartesian\" in campaign.toml if its \
             coordinates already are a Cartesian frame"
        ),
    }
}

/// Every item of `items` taken into the frame by `to_local`, in order; the first failure ends it.
fn all_to_local<T, U>(
    items: &[T],
    to_local: impl FnMut(&T) -> Result<U, FrameError>,
) -> Result<Vec<U>, AdjustError> {
    items
        .iter()
        .map(to_local)
        .collect::<Result<Vec<_>, _>>()
        .map_err(frame_error)
}

/// `block` (map coordinates) in `frame`.
pub fn block_to_local(block: &Block, frame: &MapFrame) -> Result<Block, AdjustError> {
    let recordings = all_to_local(&block.recordings, |r| {
        // An observed height is the frame's Z of the point at that height above the recorded position.
        let height_observation = match r.height_observation {
            Some(h) => {
                let mut p = r.camera.center_world;
                p.z = h.z_world;
                Some(HeightObservation {
                    z_world: frame.point_to_local(&p)?.z,
                    ..h
                })
            }
            None => None,
        };
        Ok(BlockRecording {
            camera: frame.panorama_to_local(&r.camera)?,
            height_observation,
            ..r.clone()
        })
    })?;
    // An observed point height is the frame's Z of the point at that height above its initial position.
    let point_heights = all_to_local(&block.point_heights, |h| {
        let mut p = block.points_initial_world[h.point];
        p.z = h.z_world;
        Ok(PointHeight {
            z_world: frame.point_to_local(&p)?.z,
            ..*h
        })
    })?;
    let points_initial_world =
        all_to_local(&block.points_initial_world, |p| frame.point_to_local(p))?;
    let control_points = all_to_local(&block.control_points, |c| {
        Ok(ControlPoint {
            position_world: frame.point_to_local(&c.position_world)?,
            covariance_m2: frame.covariance_to_local(&c.position_world, &c.covariance_m2)?,
            ..*c
        })
    })?;
    let aerial_cameras = all_to_local(&block.aerial_cameras, |c| frame.camera_to_local(c))?;
    Ok(Block {
        recordings,
        points_initial_world,
        pano_observations: block.pano_observations.clone(),
        control_points,
        relative_constraints: block.relative_constraints.clone(),
        aerial_cameras,
        aerial_observations: block.aerial_observations.clone(),
        point_heights,
    })
}

/// σ per axis (m) of a point of `frame` at `p_map`, in the map's axes (see the module doc).
fn sigma_to_map(
    frame: &MapFrame,
    p_map: &Vector3<f64>,
    sigma_local_m: &Vector3<f64>,
) -> Result<Vector3<f64>, FrameError> {
    let cov = Matrix3::from_diagonal(&sigma_local_m.component_mul(sigma_local_m));
    let turned = frame.covariance_to_map(p_map, &cov)?;
    Ok(turned.diagonal().map(|v| v.max(0.0).sqrt()))
}

/// An adjustment computed in `frame`, in map coordinates: positions of recordings and points, and the
/// recordings' σ. Yaw corrections stay as they are (a rotation about the frame's vertical is one about the
/// map's vertical to within the tilt of the module doc).
pub fn adjustment_to_map(mut adj: Adjustment, frame: &MapFrame) -> Result<Adjustment, AdjustError> {
    for r in &mut adj.recordings {
        let p_map = frame.point_to_map(&r.position_world).map_err(frame_error)?;
        r.sigma_a_priori_m =
            sigma_to_map(frame, &p_map, &r.sigma_a_priori_m).map_err(frame_error)?;
        if let Some(s) = r.sigma_a_posteriori_m {
            r.sigma_a_posteriori_m = Some(sigma_to_map(frame, &p_map, &s).map_err(frame_error)?);
        }
        r.position_world = p_map;
    }
    for p in &mut adj.points_world {
        *p = frame.point_to_map(p).map_err(frame_error)?;
    }
    Ok(adj)
}
