//! A synthetic block ([`super::synthetic_block`]) expressed as campaign rows and registration correspondences,
//! with nadir aerial frame cameras, for known-answer tests of [`super::from_correspondences`],
//! [`super::verify`] and the exports: `mm/recordings.csv` rows with the recorded (deteriorated) poses, MM tie
//! points, aerial control points whose aerial pixels are projections of the true points (plus noise) into
//! fixed nadir cameras (some control points deliberately seen in a single aerial image), check points and
//! their panorama observations. The truth (true centres and points) stays in [`SyntheticCampaign::truth`].

use super::synthetic_block::{SyntheticBlock, SyntheticBlockSpec};
use crate::campaign::{AerialImage, AerialKind, CheckPoint, Observation, Recording};
use crate::correspondence::{
    AerialControlPoint, AerialObservation, AerialRayGround, MmTiePoint,
    PanoObservation as CorrPanoObservation,
};
use crate::geometry::{matrix_to_opk, opk_to_matrix, triangulate_rays, FrameCamera};
use crate::rng::SplitMix64;
use nalgebra::Vector3;

/// Parameters of the aerial part of a synthetic campaign.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SyntheticCampaignSpec {
    pub block: SyntheticBlockSpec,
    /// Flying height above the trajectory, metres.
    pub aerial_height_m: f64,
    /// Ground sampling distance of the nadir images at the trajectory, metres per pixel.
    pub aerial_gsd_m: f64,
    /// One nadir image every this many recordings.
    pub aerial_every: usize,
    /// σ of the Gaussian noise added to aerial pixels (0 = exact).
    pub aerial_noise_px: f64,
    /// `sigma_px` of the aerial rows.
    pub aerial_sigma_px: f64,
    /// Every n-th control point keeps only one aerial observation (0 = none).
    pub single_aerial_every: usize,
}

impl Default for SyntheticCampaignSpec {
    fn default() -> Self {
        Self {
            block: SyntheticBlockSpec::default(),
            aerial_height_m: 500.0,
            aerial_gsd_m: 0.10,
            aerial_every: 8,
            aerial_noise_px: 0.0,
            aerial_sigma_px: 0.5,
            single_aerial_every: 4,
        }
    }
}

/// Campaign rows and correspondences of a synthetic block.
#[derive(Clone, Debug)]
pub struct SyntheticCampaign {
    pub recordings: Vec<Recording>,
    pub pano_size_px: Vec<(u32, u32)>,
    pub tie_points: Vec<MmTiePoint>,
    pub control: Vec<AerialControlPoint>,
    pub nadir: Vec<AerialImage>,
    pub checkpoints: Vec<CheckPoint>,
    pub observations: Vec<Observation>,
    /// The underlying block and its truth.
    pub truth: SyntheticBlock,
}

impl SyntheticCampaign {
    /// The adjustment's inputs: the recordings, their tie points and the nadir control (no oblique images).
    pub fn adjust_inputs(&self) -> super::AdjustInputs<'_> {
        super::AdjustInputs {
            recordings: &self.recordings,
            pano_size_px: &self.pano_size_px,
            pano_detail_level: &[],
            tie_points: &self.tie_points,
            control: &self.control,
            nadir: &self.nadir,
            oblique: &[],
            heights: None,
            tie_point_heights: None,
        }
    }

    /// The recordings (indices into `recordings`) that observe control point `k`.
    pub fn control_observed_from(&self, k: usize) -> Vec<usize> {
        self.control[k]
            .mm
            .iter()
            .filter_map(|o| {
                self.recordings
                    .iter()
                    .position(|r| r.image_id == o.image_id)
            })
            .collect()
    }

    /// Horizontal distance of each adjusted recording of `run` from its true position, metres.
    pub fn horizontal_errors_m(&self, run: &super::AdjustmentRun) -> Vec<f64> {
        run.recordings
            .iter()
            .zip(&self.truth.true_centers_world)
            .map(|(r, t)| (r.adjusted_world[0] - t.x).hypot(r.adjusted_world[1] - t.y))
            .collect()
    }
}

/// `image_id` of recording `r`.
pub fn recording_id(r: usize) -> String {
    format!("pano_{r:04}")
}

impl SyntheticCampaignSpec {
    /// Generates the campaign (deterministic for a given seed).
    pub fn generate(&self) -> SyntheticCampaign {
        let truth = self.block.generate();
        let mut rng = SplitMix64::new(self.block.seed ^ 0xA5A5_5A5A_0F0F_F0F0);
        let b = &truth.block;
        let n = b.recordings.len();
        let width = self.block.image_width_px;
        let height = width / 2;
        let recordings: Vec<Recording> = b
            .recordings
            .iter()
            .enumerate()
            .map(|(r, rec)| {
                let c = rec.camera.center_world;
                let next = truth.true_centers_world[(r + 1).min(n - 1)];
                let prev = truth.true_centers_world[r.saturating_sub(1)];
                let d = next - prev;
                let [yaw, pitch, roll] = truth.recorded_attitude_deg[r];
                Recording {
                    image_id: recording_id(r),
                    file: format!("{}.jpg", recording_id(r)),
                    time: String::new(),
                    time_s: 1_560_506_400.0 + 0.625 * r as f64,
                    x: c.x,
                    y: c.y,
                    z: c.z,
                    heading_deg: d.x.atan2(d.y).to_degrees().rem_euclid(360.0),
                    camera_height_m: 2.5,
                    sigma_xy_m: rec.prior_sigma_xy_m,
                    sigma_z_m: rec.prior_sigma_z_m,
                    yaw_deg: yaw,
                    pitch_deg: pitch,
                    roll_deg: roll,
                }
            })
            .collect();
        // Tie points with their panorama observations and a triangulation with the recorded poses.
        let mut per_point: Vec<Vec<usize>> = vec![Vec::new(); b.points_initial_world.len()];
        for (i, o) in b.pano_observations.iter().enumerate() {
            per_point[o.point].push(i);
        }
        let pano_obs = |p: usize| -> Vec<CorrPanoObservation> {
            per_point[p]
                .iter()
                .map(|&i| {
                    let o = &b.pano_observations[i];
                    CorrPanoObservation {
                        image_id: recording_id(o.recording),
                        u_px: o.u_px,
                        v_px: o.v_px,
                    }
                })
                .collect()
        };
        let tie_points: Vec<MmTiePoint> = (0..per_point.len())
            .map(|p| {
                let rays: Vec<_> = per_point[p]
                    .iter()
                    .map(|&i| {
                        let o = &b.pano_observations[i];
                        b.recordings[o.recording].camera.pixel_ray(o.u_px, o.v_px)
                    })
                    .collect();
                let sigmas: Vec<f64> = per_point[p]
                    .iter()
                    .map(|&i| {
                        let o = &b.pano_observations[i];
                        b.recordings[o.recording]
                            .camera
                            .angular_sigma_rad(o.sigma_px)
                    })
                    .collect();
                let (cov, angle) = match triangulate_rays(&rays, &sigmas) {
                    Ok(t) => (t.covariance_m2, t.max_angle_deg),
                    Err(_) => (nalgebra::Matrix3::identity() * 0.01, 0.0),
                };
                MmTiePoint {
                    id: format!("t{p}"),
                    observations: pano_obs(p),
                    point_world: b.points_initial_world[p].into(),
                    covariance_m2: [0, 1, 2].map(|i| [0, 1, 2].map(|j| cov[(i, j)])),
                    max_angle_deg: angle,
                }
            })
            .collect();
        // Nadir cameras above the trajectory, alternating sides and rotations, half with distortion.
        let focal_px = self.aerial_height_m / self.aerial_gsd_m;
        let (aw, ah) = (1600u32, 1200u32);
        let mut nadir = Vec::new();
        let mut cameras = Vec::new();
        for (k, i) in (0..n).step_by(self.aerial_every.max(1)).enumerate() {
            let t = truth.true_centers_world[i];
            let side = if k % 2 == 0 { 15.0 } else { -15.0 };
            let center = t + Vector3::new(0.0, side, self.aerial_height_m);
            let (omega, phi, kappa) = (
                0.3 * side.signum(),
                -0.2,
                if k % 2 == 0 { 0.0 } else { 90.0 },
            );
            let (omega, phi, kappa) = matrix_to_opk(&opk_to_matrix(omega, phi, kappa));
            let (k1, p1) = if k % 2 == 0 {
                (-0.03, 0.0002)
            } else {
                (0.0, 0.0)
            };
            let row = AerialImage {
                cx_px: f64::from(aw) / 2.0 + 3.5,
                cy_px: f64::from(ah) / 2.0 - 2.25,
                k1,
                p1,
                sigma_px: self.aerial_sigma_px,
                ..AerialImage::ideal(
                    &format!("nadir_{k:03}"),
                    [center.x, center.y, center.z],
                    [omega, phi, kappa],
                    focal_px,
                    [aw, ah],
                )
            };
            cameras.push(FrameCamera::from_aerial(&row));
            nadir.push(row);
        }
        // Aerial control points: the block's control points seen in the nadir images.
        let mut control = Vec::new();
        for (j, cp) in b.control_points.iter().enumerate() {
            let x = truth.true_points_world[cp.point];
            let mut aerial = Vec::new();
            for (cam, row) in cameras.iter().zip(&nadir) {
                if let Some((u, v)) = cam.project_world(&x) {
                    let u = u + self.aerial_noise_px * rng.next_gaussian();
                    let v = v + self.aerial_noise_px * rng.next_gaussian();
                    if cam.contains(u, v) {
                        aerial.push(AerialObservation {
                            image_id: row.image_id.clone(),
                            kind: AerialKind::Nadir,
                            u_px: u,
                            v_px: v,
                            score: 1.0,
                            sigma_px: None,
                        });
                    }
                }
            }
            let every = self.single_aerial_every;
            if every > 0 && j % every == every - 1 {
                aerial.truncate(1);
            }
            if aerial.is_empty() {
                continue;
            }
            let triangulated = (aerial.len() >= 2)
                .then(|| {
                    let rays: Vec<_> = aerial
                        .iter()
                        .map(|a| cameras[index_of(&nadir, &a.image_id)].pixel_ray(a.u_px, a.v_px))
                        .collect();
                    let sigmas = vec![self.aerial_sigma_px / focal_px; rays.len()];
                    triangulate_rays(&rays, &sigmas).ok()
                })
                .flatten();
            // A point in one image: its ray at the point's height, σ = σ_px × GSD.
            let ray_ground = match aerial.as_slice() {
                [a] => AerialRayGround::from_ray(
                    &cameras[index_of(&nadir, &a.image_id)].pixel_ray(a.u_px, a.v_px),
                    x.z,
                    self.aerial_sigma_px * self.aerial_gsd_m,
                ),
                _ => None,
            };
            control.push(AerialControlPoint {
                map: None,
                ray_ground,
                tie_point_id: format!("t{}", cp.point),
                mm: pano_obs(cp.point),
                aerial,
                point_world: triangulated.as_ref().map(|t| t.point_world.into()),
                covariance_m2: triangulated
                    .as_ref()
                    .map(|t| [0, 1, 2].map(|i| [0, 1, 2].map(|k| t.covariance_m2[(i, k)]))),
            });
        }
        let checkpoints = truth
            .check_points_world
            .iter()
            .enumerate()
            .map(|(i, c)| CheckPoint {
                point_id: format!("cp{i}"),
                x: c.x,
                y: c.y,
                z: c.z,
                sigma_xy_m: None,
                sigma_z_m: None,
            })
            .collect();
        let observations = truth
            .check_observations
            .iter()
            .map(|o| Observation {
                point_id: format!("cp{}", o.check_point),
                image_id: recording_id(o.recording),
                u_px: o.u_px,
                v_px: o.v_px,
            })
            .collect();
        SyntheticCampaign {
            recordings,
            pano_size_px: vec![(width, height); n],
            tie_points,
            control,
            nadir,
            checkpoints,
            observations,
            truth,
        }
    }
}

fn index_of(rows: &[AerialImage], image_id: &str) -> usize {
    rows.iter()
        .position(|r| r.image_id == image_id)
        .expect("observation of a generated camera")
}
