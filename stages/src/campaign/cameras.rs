//! The cameras of a campaign's rows: an aerial frame image's [`FrameCamera`] and a recording's
//! [`PanoramaCamera`] at its recorded pose (campaign-format.md's conventions turned into geometry).

use super::{AerialImage, Recording};
use crate::geometry::{BrownDistortion, FrameCamera, PanoramaCamera};
use nalgebra::Vector3;

impl FrameCamera {
    /// The camera of one `aerial/*/cameras.csv` row.
    pub fn from_aerial(img: &AerialImage) -> Self {
        Self::from_opk(
            Vector3::new(img.x, img.y, img.z),
            img.omega_deg,
            img.phi_deg,
            img.kappa_deg,
            img.focal_px,
            img.cx_px,
            img.cy_px,
            img.width_px,
            img.height_px,
            BrownDistortion {
                k1: img.k1,
                k2: img.k2,
                k3: img.k3,
                k4: img.k4,
                p1: img.p1,
                p2: img.p2,
                a1: img.b1 / img.focal_px,
                a2: img.b2 / img.focal_px,
            },
        )
    }
}

impl PanoramaCamera {
    /// The camera of one `mm/recordings.csv` row (its recorded pose) for an image of the given size.
    pub fn from_recording(rec: &Recording, width_px: u32, height_px: u32) -> Self {
        Self::new(
            width_px,
            height_px,
            Vector3::new(rec.x, rec.y, rec.z),
            rec.yaw_deg,
            rec.pitch_deg,
            rec.roll_deg,
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn from_aerial_matches_from_opk() {
        let img = AerialImage {
            file: "n1.tif".into(),
            cx_px: 1_503.5,
            cy_px: 997.75,
            k1: -0.1,
            k2: 0.02,
            p1: 1e-3,
            p2: -1e-3,
            ..AerialImage::ideal(
                "n1",
                [92_000.0, 437_000.0, 1_000.0],
                [1.0, -2.0, 93.0],
                3_000.0,
                [3_000, 2_000],
            )
        };
        let cam = FrameCamera::from_aerial(&img);
        let expected = FrameCamera::from_opk(
            Vector3::new(92_000.0, 437_000.0, 1_000.0),
            1.0,
            -2.0,
            93.0,
            3_000.0,
            1_503.5,
            997.75,
            3_000,
            2_000,
            BrownDistortion {
                k1: -0.1,
                k2: 0.02,
                p1: 1e-3,
                p2: -1e-3,
                ..BrownDistortion::NONE
            },
        );
        assert_eq!(cam, expected);
    }

    #[test]
    fn from_recording_uses_pose_and_rotation() {
        let rec = Recording {
            time: "2019-06-14T10:31:07.250Z".into(),
            yaw_deg: 1.0,
            pitch_deg: 2.0,
            roll_deg: 3.0,
            ..Recording::new("p1", 0.0, [92_000.0, 437_000.0, 4.0], 90.0, 2.5)
        };
        let cam = PanoramaCamera::from_recording(&rec, 4_800, 2_400);
        assert_eq!(
            cam,
            PanoramaCamera::new(
                4_800,
                2_400,
                Vector3::new(92_000.0, 437_000.0, 4.0),
                1.0,
                2.0,
                3.0
            )
        );
        assert!((cam.pixel_angle_rad() - 0.075f64.to_radians()).abs() < 1e-15);
    }
}
