//! Which oblique images may see the façades of a recording's street, decided before any façade is found so the
//! per-(recording × oblique image) patch stage can be planned statically (the DAG is built before it runs).
//!
//! Rule: façades are looked for within `max_facade_distance_m` to the left and right of the recording, from
//! the street level up to `max_facade_height_m` (thesis 4.4.1: views pitched 30° up capture the façades). An
//! oblique image is a candidate when any probe point — the recording's foot point moved `d` metres to either
//! side (perpendicular to `heading`) for `d` in {`max_facade_distance_m`/2, `max_facade_distance_m`} and raised
//! to half and to the full façade height — projects inside the image frame. The patch stage itself then only
//! registers images that the visibility hypothesis (thesis 4.4.3) accepted for a fitted plane; a candidate
//! that sees no plane gives an empty registration set, never a wrong one. This is a superset by design.
//!
//! The result lists indices into `oblique`, ordered by `image_id` (ties by index), independent of the row order
//! of `cameras.csv`. [`ObliqueCandidates`] answers for every recording of a campaign through a
//! [`FootprintIndex`] (O(log n) per recording); [`candidate_oblique`] tests every image (one recording).

use crate::campaign::{AerialImage, Recording};
use crate::geometry::FrameCamera;
use crate::nadir::footprint_index::FootprintIndex;
use nalgebra::Vector3;

/// Probe points of a recording's street façades (see the module documentation), world frame, metres.
pub fn facade_probe_points(
    rec: &Recording,
    max_facade_distance_m: f64,
    max_facade_height_m: f64,
) -> Vec<Vector3<f64>> {
    let heading = rec.heading_deg.to_radians();
    // Unit vector to the right of the driving direction (heading clockwise from north; x east, y north).
    let right = Vector3::new(heading.cos(), -heading.sin(), 0.0);
    let ground_z = rec.z - rec.camera_height_m;
    let mut out = Vec::with_capacity(8);
    for side in [-1.0, 1.0] {
        for d in [0.5 * max_facade_distance_m, max_facade_distance_m] {
            for h in [0.5 * max_facade_height_m, max_facade_height_m] {
                out.push(Vector3::new(rec.x, rec.y, ground_z + h) + right * (side * d));
            }
        }
    }
    out
}

/// Indices into `oblique` of the candidate images for `rec` (module documentation), ordered by `image_id`.
/// A non-finite recording position gives no images.
pub fn candidate_oblique(
    rec: &Recording,
    oblique: &[AerialImage],
    max_facade_distance_m: f64,
    max_facade_height_m: f64,
) -> Vec<usize> {
    let probes = facade_probe_points(rec, max_facade_distance_m, max_facade_height_m);
    if !probes.iter().all(|p| p.iter().all(|c| c.is_finite())) {
        return Vec::new();
    }
    select(oblique, 0..oblique.len(), &probes)
}

/// The images among `candidates` in which any probe projects inside the frame, ordered by `image_id` then index.
fn select(
    oblique: &[AerialImage],
    candidates: impl IntoIterator<Item = usize>,
    probes: &[Vector3<f64>],
) -> Vec<usize> {
    let mut hits: Vec<usize> = candidates
        .into_iter()
        .filter(|&i| {
            let cam = FrameCamera::from_aerial(&oblique[i]);
            probes.iter().any(|p| {
                cam.project_world(p)
                    .is_some_and(|(u, v)| cam.contains(u, v))
            })
        })
        .collect();
    hits.sort_by(|&a, &b| {
        oblique[a]
            .image_id
            .cmp(&oblique[b].image_id)
            .then(a.cmp(&b))
    });
    hits
}

/// The oblique images of a campaign indexed by footprint at the heights of its recordings' façade probes:
/// the same answer as [`candidate_oblique`] for each recording, without testing every image.
pub struct ObliqueCandidates<'a> {
    oblique: &'a [AerialImage],
    index: FootprintIndex,
    max_facade_distance_m: f64,
    max_facade_height_m: f64,
}

impl<'a> ObliqueCandidates<'a> {
    /// Indexes `oblique` for the façade probes of `recordings`.
    pub fn new(
        oblique: &'a [AerialImage],
        recordings: &[Recording],
        max_facade_distance_m: f64,
        max_facade_height_m: f64,
    ) -> Self {
        let z = FootprintIndex::height_range(recordings.iter().flat_map(|r| {
            facade_probe_points(r, max_facade_distance_m, max_facade_height_m)
                .into_iter()
                .map(|p| p.z)
        }));
        Self {
            oblique,
            index: FootprintIndex::new(oblique, z),
            max_facade_distance_m,
            max_facade_height_m,
        }
    }

    /// [`candidate_oblique`] of `rec`.
    pub fn candidates(&self, rec: &Recording) -> Vec<usize> {
        let probes = facade_probe_points(rec, self.max_facade_distance_m, self.max_facade_height_m);
        if !probes.iter().all(|p| p.iter().all(|c| c.is_finite())) {
            return Vec::new();
        }
        let (mut lo, mut hi) = ([f64::INFINITY; 3], [f64::NEG_INFINITY; 3]);
        for p in &probes {
            for k in 0..3 {
                lo[k] = lo[k].min(p[k]);
                hi[k] = hi[k].max(p[k]);
            }
        }
        let near = self
            .index
            .candidates([lo[0], lo[1]], [hi[0], hi[1]], [lo[2], hi[2]]);
        select(self.oblique, near, &probes)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn recording() -> Recording {
        Recording {
            time: "2019-06-14T10:00:00Z".into(),
            ..Recording::new("r", 0.0, [1000.0, 2000.0, 2.2], 90.0, 2.2)
        }
    }

    /// An oblique camera 450 m up, looking north at 45° (ω = 45°: the image top tilts towards north), whose
    /// axis meets the ground at (x0, y0).
    fn looking_north_at(id: &str, x0: f64, y0: f64) -> AerialImage {
        AerialImage::ideal(
            id,
            [x0, y0 - 450.0, 450.0],
            [45.0, 0.0, 0.0],
            6000.0,
            [800, 600],
        )
    }

    #[test]
    fn probes_lie_left_and_right_of_the_driving_direction() {
        let r = recording();
        let p = facade_probe_points(&r, 10.0, 12.0);
        assert_eq!(p.len(), 8);
        // Heading east: left is north (+y), right is south (−y); x unchanged.
        for q in &p {
            assert!((q.x - r.x).abs() < 1e-9);
            assert!(
                ((q.y - r.y).abs() - 5.0).abs() < 1e-9 || ((q.y - r.y).abs() - 10.0).abs() < 1e-9
            );
            assert!(q.z > 0.0 && q.z <= 12.0 + 1e-9);
        }
    }

    #[test]
    fn an_image_aimed_at_the_street_is_a_candidate_and_one_far_away_is_not() {
        let r = recording();
        let near = looking_north_at("b_near", r.x, r.y);
        let far = looking_north_at("a_far", r.x + 500.0, r.y);
        let hits = candidate_oblique(&r, &[near, far], 10.0, 12.0);
        assert_eq!(hits, vec![0]);
    }

    #[test]
    fn the_index_selects_what_testing_every_image_selects() {
        // Obliques looking north along a 2 km street, one every 50 m; recordings every 7 m with varying heading.
        let imgs: Vec<AerialImage> = (0..40)
            .map(|i| {
                looking_north_at(
                    &format!("o{:02}", (i * 13) % 40),
                    1000.0 + 50.0 * i as f64,
                    2000.0,
                )
            })
            .collect();
        let recs: Vec<Recording> = (0..300)
            .map(|k| Recording {
                time: "2019-06-14T10:00:00Z".into(),
                ..Recording::new(
                    "r",
                    0.0,
                    [990.0 + 7.0 * k as f64, 2000.0, 2.2],
                    (k * 17 % 360) as f64,
                    2.2,
                )
            })
            .collect();
        let index = ObliqueCandidates::new(&imgs, &recs, 10.0, 12.0);
        let mut total = 0;
        for r in &recs {
            let want = candidate_oblique(r, &imgs, 10.0, 12.0);
            total += want.len();
            assert_eq!(index.candidates(r), want);
        }
        assert!(total > 300, "{total}");
    }
}
