//! Profile `aerial`: errors of the aerial exterior orientation. An aerial triangulation leaves each frame's
//! projection centre and attitude a few centimetres and a few millidegrees off, and the two errors are strongly
//! correlated (for a long focal length a tilt and a shift of the centre move the ground footprint alike, so
//! the adjustment trades one against the other): what the ground sees is a footprint shifted by a few
//! centimetres, not the decimetres a millidegree tilt from 4.5 km would make alone. The images are rendered
//! with the true poses; `aerial/*/cameras.csv` get the erroneous ones and `truth/aerial_{nadir,oblique}.csv`
//! the true ones.
//!
//! Per frame: the attitude is rotated by N(0, σ_att) about each camera axis; with `correlated` the centre is
//! moved so that the camera turns about the ground point of its principal ray (that point keeps its pixel),
//! then the whole frame is shifted by a block shift (one per block: nadir, oblique) plus N(0, σ) per frame.

use super::Tables;
use crate::campaign::{AerialImage, Recording};
use crate::geometry::{matrix_to_opk, opk_to_matrix, rot_x, rot_y, rot_z, FrameCamera};
use crate::synth::rng::{hash_str, Stream};
use nalgebra::Vector3;

crate::params! {
    /// Parameters of the `aerial` component (`[synth.aerial]`).
    pub struct AerialEoParams {
        /// SD of the attitude error about each camera axis (0.003° = 3 millidegrees).
        attitude_sigma_deg: f64 = 0.003, unit "deg", min 0.0;
        /// SD of the shift of each frame per horizontal axis.
        shift_sigma_m: f64 = 0.03, unit "m", min 0.0;
        /// SD of the vertical shift of each frame.
        z_shift_sigma_m: f64 = 0.05, unit "m", min 0.0;
        /// SD of the shift shared by all frames of a block per axis.
        block_shift_sigma_m: f64 = 0.02, unit "m", min 0.0;
        /// Turn each camera about the ground point of its principal ray (the correlation of an aerial
        /// triangulation); `false` leaves the centre where it is (a tilt from 4.5 km then moves the ground by
        /// decimetres).
        correlated: bool = true;
    }
}

/// Ground height (m) below the principal ray of `img`: the road height of the true recording nearest to where
/// the ray meets the median road height of all recordings.
fn ground_z_below(img: &AerialImage, recordings: &[Recording], median_ground_z: f64) -> f64 {
    let cam = FrameCamera::from_aerial(img);
    let d = cam.viewing_direction_world();
    let at = |z: f64| {
        let t = if d.z.abs() > 1e-9 {
            (z - img.z) / d.z
        } else {
            0.0
        };
        (img.x + t * d.x, img.y + t * d.y)
    };
    let (gx, gy) = at(median_ground_z);
    recordings
        .iter()
        .min_by(|a, b| {
            let da = (a.x - gx).hypot(a.y - gy);
            let db = (b.x - gx).hypot(b.y - gy);
            da.total_cmp(&db)
        })
        .map_or(median_ground_z, |r| r.z - r.camera_height_m)
}

impl AerialEoParams {
    /// The erroneous pose of one frame (true pose `img`, ground height `ground_z`, block shift `block`).
    fn perturb(
        &self,
        seed: u64,
        img: &AerialImage,
        ground_z: f64,
        block: &Vector3<f64>,
    ) -> AerialImage {
        let mut s = Stream::new(&[seed, hash_str("aerial-eo"), hash_str(&img.image_id)]);
        let a = self.attitude_sigma_deg.to_radians();
        let tilt = rot_x(a * s.normal()) * rot_y(a * s.normal()) * rot_z(a * s.normal());
        let r_true = opk_to_matrix(img.omega_deg, img.phi_deg, img.kappa_deg);
        let r = r_true * tilt;
        let c_true = Vector3::new(img.x, img.y, img.z);
        let mut c = c_true;
        if self.correlated {
            let d = r_true * Vector3::new(0.0, 0.0, -1.0);
            let t = if d.z.abs() > 1e-9 {
                (ground_z - img.z) / d.z
            } else {
                0.0
            };
            let g = c_true + d * t;
            // The ray to g keeps its direction in the camera frame: C' = g − R' Rᵀ (g − C).
            c = g - r * r_true.transpose() * (g - c_true);
        }
        let shift = Vector3::new(
            self.shift_sigma_m * s.normal(),
            self.shift_sigma_m * s.normal(),
            self.z_shift_sigma_m * s.normal(),
        );
        c += shift + block;
        let (omega_deg, phi_deg, kappa_deg) = matrix_to_opk(&r);
        AerialImage {
            x: c.x,
            y: c.y,
            z: c.z,
            omega_deg,
            phi_deg,
            kappa_deg,
            ..img.clone()
        }
    }

    /// Replace the recorded aerial poses by erroneous ones; returns the README lines.
    pub fn apply(&self, seed: u64, truth: &Tables, out: &mut Tables) -> Vec<String> {
        let mut grounds: Vec<f64> = truth
            .recordings
            .iter()
            .map(|r| r.z - r.camera_height_m)
            .collect();
        grounds.sort_by(f64::total_cmp);
        let median = grounds.get(grounds.len() / 2).copied().unwrap_or(0.0);
        let mut notes = Vec::new();
        for (block, true_rows, rows) in [
            ("nadir", &truth.nadir, &mut out.nadir),
            ("oblique", &truth.oblique, &mut out.oblique),
        ] {
            let mut s = Stream::new(&[seed, hash_str("aerial-block"), hash_str(block)]);
            let b = Vector3::new(s.normal(), s.normal(), s.normal()) * self.block_shift_sigma_m;
            for (t, r) in true_rows.iter().zip(rows.iter_mut()) {
                let ground_z = ground_z_below(t, &truth.recordings, median);
                *r = self.perturb(seed, t, ground_z, &b);
            }
            if !true_rows.is_empty() {
                notes.push(format!(
                    "`aerial` {block}: every frame's attitude turned by N(0, {:.1} mdeg) about each camera axis{}, \
                     then shifted by the block shift ({:+.3}, {:+.3}, {:+.3}) m plus N(0, {:.3} m) per \
                     horizontal axis and N(0, {:.3} m) vertically; true poses in `truth/aerial_{block}.csv`;",
                    self.attitude_sigma_deg * 1e3,
                    if self.correlated {
                        " about the ground point of its principal ray (correlated as in an aerial triangulation)"
                    } else {
                        ""
                    },
                    b.x,
                    b.y,
                    b.z,
                    self.shift_sigma_m,
                    self.z_shift_sigma_m
                ));
            }
        }
        notes
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn nadir() -> AerialImage {
        AerialImage::ideal(
            "n1",
            [1000.0, 2000.0, 4471.0],
            [0.1, -0.2, -90.0],
            44_700.0,
            [1600, 1200],
        )
    }

    #[test]
    fn a_correlated_tilt_keeps_the_ground_point_of_the_principal_ray() {
        let p = AerialEoParams {
            attitude_sigma_deg: 0.020,
            shift_sigma_m: 0.0,
            z_shift_sigma_m: 0.0,
            block_shift_sigma_m: 0.0,
            correlated: true,
        };
        let img = nadir();
        let out = p.perturb(5, &img, 1.0, &Vector3::zeros());
        let (cam, cam2) = (
            FrameCamera::from_aerial(&img),
            FrameCamera::from_aerial(&out),
        );
        let d = cam.viewing_direction_world();
        let g = cam.center_world + d * ((1.0 - img.z) / d.z);
        let (u, v) = cam2.project_world(&g).unwrap();
        assert!(
            (u - 800.0).abs() < 1e-6 && (v - 600.0).abs() < 1e-6,
            "{u} {v}"
        );
        // The centre moved by the tilt times the flying height (20 mdeg ≈ 3.5e-4 rad ⇒ ≈ 1.6 m), the
        // attitude changed.
        let moved = (cam2.center_world - cam.center_world).norm();
        assert!(moved > 0.1 && moved < 5.0, "{moved}");
        assert!((out.omega_deg - img.omega_deg).abs() > 1e-4);
        // Uncorrelated: the centre stays.
        let un = AerialEoParams {
            correlated: false,
            ..p
        }
        .perturb(5, &img, 1.0, &Vector3::zeros());
        assert_eq!((un.x, un.y, un.z), (img.x, img.y, img.z));
    }
}
