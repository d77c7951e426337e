//! Which aerial nadir images overlap a recording (thesis 3.4.5.1: "MM image recording locations are projected in
//! every overlapping aerial image").
//!
//! Rule: a nadir image overlaps a recording when the recording's ortho footprint centre — the foot point
//! `(x, y, z − camera_height)` below the recorded projection centre — grown to a horizontal square of half-side
//! `margin_m` (the expected maximum localisation error, so that the *true* foot point is seen even when the recorded
//! one is off by up to that much), projects entirely inside the image frame: the centre and all four corners of the
//! square must fall in `0 ≤ u < W`, `0 ≤ v < H` and lie in front of the camera. The rest of the 30 m ortho footprint
//! may leave the frame; the aerial patch is then clipped to the image ([`super::aerial_patch::extract_patch`]).
//!
//! The result lists indices into `nadir`, ordered by `image_id` (ties by index), so it does not depend on the row
//! order of `cameras.csv`.

use crate::campaign::{AerialImage, Recording};
use crate::geometry::FrameCamera;
use nalgebra::Vector3;

/// The ortho footprint centre (foot point) of a recording: `(x, y, z − camera_height)`, world frame, metres.
pub fn foot_point_world(rec: &Recording) -> [f64; 3] {
    [rec.x, rec.y, rec.z - rec.camera_height_m]
}

/// True if the horizontal square of half-side `margin_m` around `foot_world` projects entirely inside the frame of
/// `cam` (centre and four corners; see the module documentation).
pub fn frame_contains_foot(cam: &FrameCamera, foot_world: [f64; 3], margin_m: f64) -> bool {
    let m = margin_m.max(0.0);
    let offsets = [(0.0, 0.0), (-m, -m), (m, -m), (m, m), (-m, m)];
    offsets.iter().all(|&(dx, dy)| {
        let p = Vector3::new(foot_world[0] + dx, foot_world[1] + dy, foot_world[2]);
        cam.project_world(&p)
            .is_some_and(|(u, v)| cam.contains(u, v))
    })
}

/// Indices into `nadir` of the images whose frame contains `rec`'s foot point grown by `margin_m` (module
/// documentation), ordered by `image_id`. A non-finite recording position gives no images.
pub fn overlapping_nadir(rec: &Recording, nadir: &[AerialImage], margin_m: f64) -> Vec<usize> {
    let foot = foot_point_world(rec);
    if !foot.iter().all(|c| c.is_finite()) || !margin_m.is_finite() {
        return Vec::new();
    }
    let mut hits: Vec<usize> = nadir
        .iter()
        .enumerate()
        .filter(|(_, img)| frame_contains_foot(&FrameCamera::from_aerial(img), foot, margin_m))
        .map(|(i, _)| i)
        .collect();
    hits.sort_by(|&a, &b| nadir[a].image_id.cmp(&nadir[b].image_id).then(a.cmp(&b)));
    hits
}

#[cfg(test)]
mod tests {
    use super::*;

    fn nadir(id: &str, x: f64, y: f64, kappa_deg: f64) -> AerialImage {
        AerialImage::ideal(
            id,
            [x, y, 4470.0],
            [0.0, 0.0, kappa_deg],
            44_700.0,
            [512, 384],
        )
    }

    fn rec(x: f64, y: f64) -> Recording {
        Recording {
            time: "2020-01-01T00:00:00Z".into(),
            ..Recording::new("r", 0.0, [x, y, 2.2], 0.0, 2.2)
        }
    }

    #[test]
    fn selects_by_foot_point_with_margin_and_sorts_by_id() {
        // 512 × 384 px at 0.1 m: κ = 0 covers x ± 25.6 m, y ± 19.2 m around the centre.
        let imgs = vec![
            nadir("c", 1000.0, 2000.0, 0.0),
            nadir("a", 1030.0, 2000.0, 0.0),
            nadir("b", 1000.0, 2000.0, 90.0),
        ];
        // Foot 18 m north of "c": inside with margin 1.0 (19 < 19.2), outside with 1.5; "b" is rotated (±25.6 m
        // north-south) and contains it either way; "a" is 30 m east: outside.
        assert_eq!(
            overlapping_nadir(&rec(1000.0, 2018.0), &imgs, 1.0),
            vec![2, 0]
        );
        assert_eq!(overlapping_nadir(&rec(1000.0, 2018.0), &imgs, 1.5), vec![2]);
        // Halfway between "c" and "a": both (sorted by id: a, b, c).
        assert_eq!(
            overlapping_nadir(&rec(1015.0, 2000.0), &imgs, 1.5),
            vec![1, 2, 0]
        );
        assert!(overlapping_nadir(&rec(f64::NAN, 2000.0), &imgs, 1.5).is_empty());
    }
}
