//! Synthetic adjustment blocks with known answers: a 5 m-spaced trajectory of panoramas, tie points seen by
//! 2–4 consecutive panoramas, aerial control points, check points, and recorded poses deteriorated like
//! thesis 5.7 (a systematic horizontal offset plus a random offset of bounded size), optionally with a yaw
//! error, pixel noise and injected gross outliers whose indices are returned.
//!
//! Observations are generated with the true poses; the block's recordings carry the deteriorated (recorded)
//! poses, which are the adjustment's initial values and priors; initial tie points are triangulated with the
//! recorded poses (as the pipeline would). Deterministic for a given seed.

use super::evaluate::CheckObservation;
use super::problem::{Block, BlockRecording, ControlPoint, PanoObservation, RelativeConstraint};
use crate::geometry::{triangulate_rays, PanoramaCamera};
use crate::rng::SplitMix64;
use nalgebra::Vector3;
use std::f64::consts::TAU;

/// Camera height above the road, metres.
const CAMERA_HEIGHT_M: f64 = 2.5;

/// Parameters of a synthetic block.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SyntheticBlockSpec {
    pub recordings: usize,
    pub spacing_m: f64,
    /// Target panorama observations per recording (each tie point is seen 3 times on average).
    pub observations_per_recording: usize,
    pub control_points: usize,
    /// Length of the systematic horizontal offset of the recorded positions, metres (azimuth from the seed).
    pub systematic_offset_m: f64,
    /// Largest random horizontal offset per recording, metres (uniform in a disc).
    pub random_offset_m: f64,
    /// Systematic vertical offset of the recorded positions, metres.
    pub z_offset_m: f64,
    /// Mean yaw error of the recorded poses, degrees (per recording: mean × U(0.5, 1.5)).
    pub yaw_error_deg: f64,
    pub prior_sigma_xy_m: f64,
    pub prior_sigma_z_m: f64,
    pub image_width_px: u32,
    /// Assumed pixel σ of the observations.
    pub sigma_px: f64,
    /// σ of the Gaussian noise actually added to the pixels (0 = exact).
    pub pixel_noise_px: f64,
    pub control_sigma_m: f64,
    /// σ of the Gaussian noise actually added to each control-point coordinate, metres (0 = exact).
    pub control_noise_m: f64,
    /// Fraction of panorama observations replaced by gross outliers.
    pub outlier_fraction: f64,
    pub outlier_min_px: f64,
    pub outlier_max_px: f64,
    /// Control points displaced horizontally by `control_outlier_m`.
    pub control_outliers: usize,
    pub control_outlier_m: f64,
    /// One check point every this many recordings.
    pub check_point_every: usize,
    pub seed: u64,
}

impl Default for SyntheticBlockSpec {
    fn default() -> Self {
        Self {
            recordings: 40,
            spacing_m: 5.0,
            observations_per_recording: 20,
            control_points: 15,
            systematic_offset_m: 0.8,
            random_offset_m: 0.1,
            z_offset_m: 0.0,
            yaw_error_deg: 0.0,
            prior_sigma_xy_m: 100.0,
            prior_sigma_z_m: 100.0,
            image_width_px: 4800,
            sigma_px: 1.0,
            pixel_noise_px: 0.0,
            control_sigma_m: 0.10,
            control_noise_m: 0.0,
            outlier_fraction: 0.0,
            outlier_min_px: 20.0,
            outlier_max_px: 50.0,
            control_outliers: 0,
            control_outlier_m: 2.0,
            check_point_every: 6,
            seed: 1,
        }
    }
}

/// A block with its truth.
#[derive(Clone, Debug)]
pub struct SyntheticBlock {
    pub block: Block,
    pub true_centers_world: Vec<Vector3<f64>>,
    /// True yaw minus recorded yaw, degrees (what a yaw adjustment should recover).
    pub true_yaw_correction_deg: Vec<f64>,
    pub true_points_world: Vec<Vector3<f64>>,
    /// Indices of panorama observations replaced by outliers, ascending.
    pub outlier_observations: Vec<usize>,
    /// Indices of displaced control points, ascending.
    pub outlier_controls: Vec<usize>,
    pub check_points_world: Vec<Vector3<f64>>,
    /// Check-point observations made with the true poses (same noise as the tie points).
    pub check_observations: Vec<CheckObservation>,
    /// The true cameras.
    pub true_cameras: Vec<PanoramaCamera>,
    /// Recorded (yaw, pitch, roll) of each recording, degrees (the recorded camera's attitude).
    pub recorded_attitude_deg: Vec<[f64; 3]>,
}

impl SyntheticBlockSpec {
    /// The observed pixel of the true projection (u, v): Gaussian noise of σ `pixel_noise_px` drawn from
    /// `rng` for u, then for v, and u wrapped into the panorama's width.
    fn observed_pixel(&self, u: f64, v: f64, rng: &mut SplitMix64) -> (f64, f64) {
        let u_px = (u + self.pixel_noise_px * rng.next_gaussian())
            .rem_euclid(f64::from(self.image_width_px));
        let v_px = v + self.pixel_noise_px * rng.next_gaussian();
        (u_px, v_px)
    }

    /// Generates the block.
    pub fn generate(&self) -> SyntheticBlock {
        let mut rng = SplitMix64::new(self.seed);
        let n = self.recordings.max(2);
        let width = self.image_width_px;
        let height = width / 2;
        // Trajectory: a gentle curve, rising 2 %.
        let mut true_centers = Vec::with_capacity(n);
        let mut c = Vector3::new(250_000.0, 5_600_000.0, 100.0 + CAMERA_HEIGHT_M);
        for i in 0..n {
            true_centers.push(c);
            let heading = 0.3 + 0.004 * i as f64;
            c += Vector3::new(heading.cos(), heading.sin(), 0.02) * self.spacing_m;
        }
        let sys_az = rng.next_f64() * TAU;
        let systematic = Vector3::new(sys_az.cos(), sys_az.sin(), 0.0) * self.systematic_offset_m
            + Vector3::new(0.0, 0.0, self.z_offset_m);
        let mut recordings = Vec::with_capacity(n);
        let mut true_cameras = Vec::with_capacity(n);
        let mut yaw_corr = Vec::with_capacity(n);
        let mut recorded_attitude_deg = Vec::with_capacity(n);
        for center in &true_centers {
            let recorded_yaw = (rng.next_f64() - 0.5) * 1.0;
            let pitch = (rng.next_f64() - 0.5) * 0.6;
            let roll = (rng.next_f64() - 0.5) * 0.6;
            let err = self.yaw_error_deg * (0.5 + rng.next_f64());
            let radius = self.random_offset_m * rng.next_f64().sqrt();
            let az = rng.next_f64() * TAU;
            let recorded = center + systematic + Vector3::new(az.cos(), az.sin(), 0.0) * radius;
            true_cameras.push(PanoramaCamera::new(
                width,
                height,
                *center,
                recorded_yaw + err,
                pitch,
                roll,
            ));
            yaw_corr.push(err);
            recorded_attitude_deg.push([recorded_yaw, pitch, roll]);
            recordings.push(BlockRecording {
                camera: PanoramaCamera::new(width, height, recorded, recorded_yaw, pitch, roll),
                prior_sigma_xy_m: Some(self.prior_sigma_xy_m),
                prior_sigma_z_m: Some(self.prior_sigma_z_m),
                height_observation: None,
            });
        }
        // Tie points anchored at each recording, seen by 2–4 consecutive recordings.
        let per_anchor = self.observations_per_recording as f64 / 3.0;
        let mut true_points = Vec::new();
        let mut views: Vec<(usize, usize)> = Vec::new();
        for i in 0..n {
            let count = per_anchor.floor() as usize
                + usize::from(rng.next_f64() < per_anchor - per_anchor.floor());
            for _ in 0..count {
                let v = (2 + rng.below(3) as usize).min(n);
                let s = i.min(n - v);
                let (first, last) = (true_centers[s], true_centers[s + v - 1]);
                let mid = (first + last) * 0.5;
                let mut dir = last - first;
                dir.z = 0.0;
                let dir = dir.normalize();
                let normal = Vector3::new(-dir.y, dir.x, 0.0);
                let side = if rng.next_f64() < 0.5 { -1.0 } else { 1.0 };
                let lateral = side * (4.0 + 8.0 * rng.next_f64());
                let along = (rng.next_f64() - 0.5) * self.spacing_m;
                let up = rng.next_f64() * 6.0;
                let p = mid
                    + normal * lateral
                    + dir * along
                    + Vector3::new(0.0, 0.0, up - CAMERA_HEIGHT_M);
                true_points.push(p);
                views.push((s, v));
            }
        }
        let mut observations = Vec::new();
        let mut point_obs: Vec<Vec<usize>> = vec![Vec::new(); true_points.len()];
        for (p, &(s, v)) in views.iter().enumerate() {
            for (r, cam) in true_cameras.iter().enumerate().skip(s).take(v) {
                let (u, vv) = cam
                    .project_world(&true_points[p])
                    .expect("point off centre");
                point_obs[p].push(observations.len());
                let (u_px, v_px) = self.observed_pixel(u, vv, &mut rng);
                observations.push(PanoObservation {
                    recording: r,
                    point: p,
                    u_px,
                    v_px,
                    sigma_px: self.sigma_px,
                });
            }
        }
        // Control points spread evenly over the tie points.
        let n_pts = true_points.len();
        let n_ctrl = self.control_points.min(n_pts);
        let mut is_control = vec![false; n_pts];
        let mut control_points = Vec::with_capacity(n_ctrl);
        for j in 0..n_ctrl {
            let p = (j * n_pts + n_pts / 2) / n_ctrl.max(1);
            let p = p.min(n_pts - 1);
            if is_control[p] {
                continue;
            }
            is_control[p] = true;
            control_points.push(surveyed_control(
                p,
                true_points[p],
                self.control_noise_m,
                self.control_sigma_m,
                &mut rng,
            ));
        }
        let mut outlier_controls = Vec::new();
        let n_ctrl_out = self.control_outliers.min(control_points.len());
        for j in 0..n_ctrl_out {
            let idx = (j * control_points.len() + control_points.len() / 3) / n_ctrl_out.max(1);
            let az = rng.next_f64() * TAU;
            control_points[idx].position_world +=
                Vector3::new(az.cos(), az.sin(), 0.0) * self.control_outlier_m;
            outlier_controls.push(idx);
        }
        outlier_controls.sort_unstable();
        outlier_controls.dedup();
        // Gross outliers: at most one per point, only on points with 4 rays that are not control points. The
        // recordings are nearly collinear, so all rays of a point lie in about one plane: in that plane 3 rays
        // leave a single redundancy and a faulty ray is detectable but cannot be located; 4 rays can.
        let mut candidates: Vec<usize> = (0..n_pts)
            .filter(|&p| point_obs[p].len() >= 4 && !is_control[p])
            .collect();
        let wanted = ((self.outlier_fraction * observations.len() as f64).round() as usize)
            .min(candidates.len());
        let mut outlier_observations = Vec::with_capacity(wanted);
        for k in 0..wanted {
            let pick = k + rng.below((candidates.len() - k) as u64) as usize;
            candidates.swap(k, pick);
            let p = candidates[k];
            let o = point_obs[p][rng.below(point_obs[p].len() as u64) as usize];
            let magnitude =
                self.outlier_min_px + (self.outlier_max_px - self.outlier_min_px) * rng.next_f64();
            let dir = rng.next_f64() * TAU;
            let obs = &mut observations[o];
            obs.u_px = (obs.u_px + magnitude * dir.cos()).rem_euclid(f64::from(width));
            obs.v_px += magnitude * dir.sin();
            outlier_observations.push(o);
        }
        outlier_observations.sort_unstable();
        // Initial tie points: triangulated with the recorded poses.
        let mut points_initial = Vec::with_capacity(n_pts);
        for (p, obs) in point_obs.iter().enumerate() {
            let views: Vec<(usize, f64, f64)> = obs
                .iter()
                .map(|&o| {
                    let ob = &observations[o];
                    (ob.recording, ob.u_px, ob.v_px)
                })
                .collect();
            points_initial.push(
                triangulate_recorded(&recordings, &views, self.sigma_px)
                    .unwrap_or_else(|| true_points[p] + systematic),
            );
        }
        // Check points: on the road edge, seen by every recording within 20 m.
        let mut check_points = Vec::new();
        let mut check_observations = Vec::new();
        let every = self.check_point_every.max(1);
        // Cameras by centre, so each check point visits only the nearby ones (in recording order, as a scan
        // over all cameras would; the index's radius is a little larger than the exact test's).
        let centres = rstar::RTree::bulk_load(
            true_cameras
                .iter()
                .enumerate()
                .map(|(r, cam)| {
                    let c = cam.center_world;
                    rstar::primitives::GeomWithData::new([c.x, c.y, c.z], r)
                })
                .collect(),
        );
        for i in (every / 2..n).step_by(every) {
            let cp = true_centers[i] + Vector3::new(-0.3, 5.0, -CAMERA_HEIGHT_M);
            let id = check_points.len();
            let mut near: Vec<usize> = centres
                .locate_within_distance([cp.x, cp.y, cp.z], 21.0 * 21.0)
                .map(|e| e.data)
                .collect();
            near.sort_unstable();
            for r in near {
                let cam = &true_cameras[r];
                if (cam.center_world - cp).norm() <= 20.0 {
                    let (u, v) = cam.project_world(&cp).expect("check point off centre");
                    let (u_px, v_px) = self.observed_pixel(u, v, &mut rng);
                    check_observations.push(CheckObservation {
                        check_point: id,
                        recording: r,
                        u_px,
                        v_px,
                    });
                }
            }
            check_points.push(cp);
        }
        SyntheticBlock {
            block: Block {
                recordings,
                points_initial_world: points_initial,
                pano_observations: observations,
                control_points,
                relative_constraints: Vec::new(),
                aerial_cameras: Vec::new(),
                aerial_observations: Vec::new(),
                point_heights: Vec::new(),
            },
            true_centers_world: true_centers,
            true_yaw_correction_deg: yaw_corr,
            true_points_world: true_points,
            outlier_observations,
            outlier_controls,
            check_points_world: check_points,
            check_observations,
            true_cameras,
            recorded_attitude_deg,
        }
    }
}

/// An aerial control point on tie point `p` at `true_world` surveyed with Gaussian noise of σ `noise_m` per
/// coordinate (drawn from `rng` for x, y, z in turn), stated with the isotropic σ `sigma_m`.
pub(crate) fn surveyed_control(
    p: usize,
    true_world: Vector3<f64>,
    noise_m: f64,
    sigma_m: f64,
    rng: &mut SplitMix64,
) -> ControlPoint {
    let noise = Vector3::new(
        rng.next_gaussian(),
        rng.next_gaussian(),
        rng.next_gaussian(),
    ) * noise_m;
    ControlPoint::isotropic(p, true_world + noise, sigma_m)
}

/// A tie point triangulated from its observations (recording, u_px, v_px) with the recorded poses of
/// `recordings`, each ray weighted by `sigma_px` (the pipeline's initial tie points); `None` where that fails
/// (too few rays, degenerate geometry).
pub(crate) fn triangulate_recorded(
    recordings: &[BlockRecording],
    views: &[(usize, f64, f64)],
    sigma_px: f64,
) -> Option<Vector3<f64>> {
    let rays: Vec<_> = views
        .iter()
        .map(|&(r, u, v)| recordings[r].camera.pixel_ray(u, v))
        .collect();
    let sigmas: Vec<f64> = views
        .iter()
        .map(|&(r, _, _)| recordings[r].camera.angular_sigma_rad(sigma_px))
        .collect();
    triangulate_rays(&rays, &sigmas).ok().map(|t| t.point_world)
}

/// Relative constraints of σ `sigma_m` between each of `n` recordings and the next, in order (a trajectory
/// without gaps).
pub fn consecutive_constraints(n: usize, sigma_m: f64) -> Vec<RelativeConstraint> {
    (1..n)
        .map(|i| RelativeConstraint::new(i - 1, i, sigma_m))
        .collect()
}
