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
//! order of `cameras.csv`. [`NadirOverlap`] answers the question for every recording of a campaign through a
//! [`FootprintIndex`] (O(log n) per recording); [`overlapping_nadir`] tests every image (one recording).

use super::footprint_index::FootprintIndex;
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
    select(nadir, 0..nadir.len(), foot, margin_m)
}

/// The images among `candidates` whose frame contains the foot square, ordered by `image_id` then index.
fn select(
    nadir: &[AerialImage],
    candidates: impl IntoIterator<Item = usize>,
    foot: [f64; 3],
    margin_m: f64,
) -> Vec<usize> {
    let mut hits: Vec<usize> = candidates
        .into_iter()
        .filter(|&i| frame_contains_foot(&FrameCamera::from_aerial(&nadir[i]), foot, margin_m))
        .collect();
    hits.sort_by(|&a, &b| nadir[a].image_id.cmp(&nadir[b].image_id).then(a.cmp(&b)));
    hits
}

/// The nadir images of a campaign indexed by footprint at the recordings' foot heights: the same answer as
/// [`overlapping_nadir`] for each recording, without testing every image.
pub struct NadirOverlap<'a> {
    nadir: &'a [AerialImage],
    index: FootprintIndex,
}

impl<'a> NadirOverlap<'a> {
    /// Indexes `nadir` for the foot points of `recordings`.
    pub fn new(nadir: &'a [AerialImage], recordings: &[Recording]) -> Self {
        let z = FootprintIndex::height_range(recordings.iter().map(|r| foot_point_world(r)[2]));
        Self {
            nadir,
            index: FootprintIndex::new(nadir, z),
        }
    }

    /// [`overlapping_nadir`] of `rec`.
    pub fn overlapping(&self, rec: &Recording, margin_m: f64) -> Vec<usize> {
        let foot = foot_point_world(rec);
        if !foot.iter().all(|c| c.is_finite()) || !margin_m.is_finite() {
            return Vec::new();
        }
        // Every accepted image contains the centre of the square, so the centre alone narrows the search.
        let centre = [foot[0], foot[1]];
        let candidates = self.index.candidates(centre, centre, [foot[2], foot[2]]);
        select(self.nadir, candidates, foot, margin_m)
    }
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

    #[test]
    fn the_index_selects_what_testing_every_image_selects() {
        // A 10 × 10 grid of nadir images 40 m apart, some rotated; recordings along a diagonal street.
        let mut imgs = Vec::new();
        for i in 0..100 {
            let (gx, gy) = ((i % 10) as f64, (i / 10) as f64);
            let id = format!("n{:03}", (i * 37) % 100);
            imgs.push(nadir(
                &id,
                1000.0 + 40.0 * gx,
                2000.0 + 40.0 * gy,
                30.0 * (i % 4) as f64,
            ));
        }
        let recs: Vec<Recording> = (0..300)
            .map(|k| rec(990.0 + 1.37 * k as f64, 1995.0 + 1.21 * k as f64))
            .collect();
        let overlap = NadirOverlap::new(&imgs, &recs);
        let mut total = 0;
        for r in &recs {
            for margin in [0.0, 1.5, 5.0] {
                let want = overlapping_nadir(r, &imgs, margin);
                total += want.len();
                assert_eq!(overlap.overlapping(r, margin), want);
            }
        }
        assert!(total > 300, "{total}");
    }
}
