//! Image-free synthetic street-network blocks for the adjustment at city scale (benchmarks, known-answer
//! tests): recordings every few metres along a grid of streets driven in both directions ([`route`]), tie
//! points beside the road and at crossings ([`points`]), aerial control points spread evenly over the tie
//! points, relative constraints between consecutive recordings, and recorded positions off by a slowly
//! varying GNSS bias. Shaped like the blocks the pipeline builds (thesis 5.4.3: MM tie points from
//! consecutive recordings, aerial control points with σ 0.10 m, weak priors) but of any size: 10⁶
//! recordings generate in seconds, in parallel, identically for any thread count.

pub mod points;
pub mod route;

use super::problem::{Block, BlockRecording, ControlPoint, PanoObservation, RelativeConstraint};
use super::synthetic_block::{surveyed_control, triangulate_recorded};
use crate::geometry::PanoramaCamera;
use crate::rng::{mix_seed, SplitMix64};
use nalgebra::Vector3;
use points::{crossing_points, observe, roadside_points, TiePoint};
use rayon::prelude::*;

/// Parameters of a street-network block.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct StreetBlockSpec {
    pub recordings: usize,
    /// Distance between parallel streets, metres.
    pub street_spacing_m: f64,
    /// Distance between consecutive recordings, metres.
    pub spacing_m: f64,
    /// Roadside panorama observations per recording (each point is seen 3 times on average).
    pub observations_per_recording: usize,
    /// Aerial control points per recording.
    pub control_per_recording: f64,
    /// Road-marking tie points per crossing passed more than once.
    pub crossing_points: usize,
    /// σ per horizontal axis of the slowly varying GNSS bias of the recorded positions, metres.
    pub drift_sigma_m: f64,
    /// Recordings between independent bias values.
    pub drift_length: usize,
    /// σ of the white horizontal noise of the recorded positions, metres.
    pub noise_m: f64,
    /// σ of the relative constraints between consecutive recordings (`None` = none), metres.
    pub relative_sigma_m: Option<f64>,
    pub prior_sigma_xy_m: f64,
    pub prior_sigma_z_m: f64,
    pub image_width_px: u32,
    /// Assumed pixel σ of the observations.
    pub sigma_px: f64,
    /// σ of the noise added to the pixels.
    pub pixel_noise_px: f64,
    pub control_sigma_m: f64,
    /// σ of the noise added to each control-point coordinate, metres.
    pub control_noise_m: f64,
    pub seed: u64,
}

impl Default for StreetBlockSpec {
    fn default() -> Self {
        Self {
            recordings: 2000,
            street_spacing_m: 100.0,
            spacing_m: 5.0,
            observations_per_recording: 20,
            control_per_recording: 0.375,
            crossing_points: 4,
            drift_sigma_m: 0.8,
            drift_length: 100,
            noise_m: 0.03,
            relative_sigma_m: Some(0.05),
            prior_sigma_xy_m: 2.0,
            prior_sigma_z_m: 2.0,
            image_width_px: 8000,
            sigma_px: 1.0,
            pixel_noise_px: 0.5,
            control_sigma_m: 0.10,
            control_noise_m: 0.05,
            seed: 1,
        }
    }
}

/// A street-network block with its truth.
#[derive(Clone, Debug)]
pub struct StreetBlock {
    pub block: Block,
    pub true_centers_world: Vec<Vector3<f64>>,
    pub true_points_world: Vec<Vector3<f64>>,
    /// Tie points at crossings (the last ones of the block's points).
    pub crossing_points: usize,
}

impl StreetBlockSpec {
    /// Generates the block.
    pub fn generate(&self) -> StreetBlock {
        let n = self.recordings.max(2);
        let (true_centers, headings) = route::drive(n, self.street_spacing_m, self.spacing_m);
        let recorded = route::recorded_positions(
            &true_centers,
            self.drift_sigma_m,
            self.drift_length,
            self.noise_m,
            self.seed,
        );
        let (width, height) = (self.image_width_px, self.image_width_px / 2);
        let attitude = |r: usize| {
            let mut rng = SplitMix64::new(mix_seed(self.seed ^ 0xA771_0000, r as u64));
            let pitch = (rng.next_f64() - 0.5) * 0.6;
            let roll = (rng.next_f64() - 0.5) * 0.6;
            (headings[r], pitch, roll)
        };
        let camera = |r: usize, center: Vector3<f64>| {
            let (yaw, pitch, roll) = attitude(r);
            PanoramaCamera::new(width, height, center, yaw, pitch, roll)
        };
        let true_cameras: Vec<PanoramaCamera> =
            (0..n).map(|r| camera(r, true_centers[r])).collect();
        let recordings: Vec<BlockRecording> = (0..n)
            .map(|r| BlockRecording {
                camera: camera(r, recorded[r]),
                prior_sigma_xy_m: Some(self.prior_sigma_xy_m),
                prior_sigma_z_m: Some(self.prior_sigma_z_m),
                height_observation: None,
            })
            .collect();
        let per_recording = self.observations_per_recording as f64 / 3.0;
        let mut points = roadside_points(&true_centers, per_recording, self.seed);
        let crossings = crossing_points(
            &true_centers,
            self.street_spacing_m,
            self.crossing_points,
            self.seed,
        );
        let crossing_count = crossings.len();
        points.extend(crossings);
        let observed = observe(&points, &true_cameras, self.pixel_noise_px, self.seed);
        drop(true_cameras);
        let mut block = Block {
            points_initial_world: initial_points(&recordings, &observed, &points, self.sigma_px),
            recordings,
            ..Block::default()
        };
        block.pano_observations = observed
            .iter()
            .enumerate()
            .flat_map(|(p, obs)| {
                obs.iter()
                    .map(move |&(recording, u_px, v_px)| PanoObservation {
                        recording,
                        point: p,
                        u_px,
                        v_px,
                        sigma_px: self.sigma_px,
                    })
            })
            .collect();
        drop(observed);
        block.control_points = self.control(&points, n);
        if let Some(sigma_m) = self.relative_sigma_m {
            block.relative_constraints = (1..n)
                .filter(|&r| (true_centers[r] - true_centers[r - 1]).norm() <= 2.0 * self.spacing_m)
                .map(|r| RelativeConstraint::new(r - 1, r, sigma_m))
                .collect();
        }
        StreetBlock {
            block,
            true_centers_world: true_centers,
            true_points_world: points.iter().map(|p| p.true_world).collect(),
            crossing_points: crossing_count,
        }
    }

    /// Control points spread evenly over the tie points, `control_per_recording` per recording.
    fn control(&self, points: &[TiePoint], recordings: usize) -> Vec<ControlPoint> {
        let wanted = (self.control_per_recording * recordings as f64).round() as usize;
        let n_pts = points.len();
        let wanted = wanted.min(n_pts);
        (0..wanted)
            .map(|j| {
                let p = ((j * n_pts + n_pts / 2) / wanted).min(n_pts - 1);
                let mut rng = SplitMix64::new(mix_seed(self.seed ^ 0xC0A7_0000, j as u64));
                surveyed_control(
                    p,
                    points[p].true_world,
                    self.control_noise_m,
                    self.control_sigma_m,
                    &mut rng,
                )
            })
            .collect()
    }
}

/// Initial tie-point coordinates: triangulated from the observations with the recorded poses, as the
/// pipeline does; the true point where that fails (too few rays).
fn initial_points(
    recordings: &[BlockRecording],
    observed: &[Vec<(usize, f64, f64)>],
    points: &[TiePoint],
    sigma_px: f64,
) -> Vec<Vector3<f64>> {
    observed
        .par_iter()
        .zip(points)
        .with_min_len(1024)
        .map(|(obs, point)| {
            triangulate_recorded(recordings, obs, sigma_px).unwrap_or(point.true_world)
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::adjustment::{adjust, AdjustOptions};

    #[test]
    fn a_street_block_adjusts_to_its_truth_identically_for_any_thread_count() {
        let spec = StreetBlockSpec {
            recordings: 600,
            ..StreetBlockSpec::default()
        };
        let run = |threads| {
            rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap()
                .install(|| {
                    let s = spec.generate();
                    let adj = adjust(&s.block, &AdjustOptions::default()).unwrap();
                    (s, adj)
                })
        };
        let (s, adj) = run(2);
        assert!(s.crossing_points > 0);
        assert!(!s.block.relative_constraints.is_empty());
        let error = |positions: &mut dyn Iterator<Item = Vector3<f64>>| {
            let (sum, count) = positions
                .zip(&s.true_centers_world)
                .fold((0.0, 0), |(sum, n), (p, t)| {
                    (sum + (p - t).xy().norm_squared(), n + 1)
                });
            (sum / count as f64).sqrt()
        };
        let before = error(&mut s.block.recordings.iter().map(|r| r.camera.center_world));
        let after = error(&mut adj.recordings.iter().map(|r| r.position_world));
        println!("street block 600: RMS horizontal error {before:.3} m → {after:.4} m");
        assert!(before > 0.4, "{before}");
        assert!(after < 0.05, "{after}");
        let (s1, adj1) = run(1);
        assert_eq!(s1.block.pano_observations, s.block.pano_observations);
        assert_eq!(adj1, adj);
    }
}
