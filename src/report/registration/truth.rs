//! Correct / wrong marks for the registration views, by truth (evaluation only, never the pipeline): the
//! panorama observations of a control point are triangulated with the **true** recording poses
//! (`truth/recordings.csv`) — one observation only: intersected with the horizontal plane at the true
//! ground height below the camera — and the point is projected into the aerial image with its pose (aerial
//! poses of synthetic campaigns are true). An aerial observation is correct when it lies within
//! [`TOLERANCE_PX`] of that projection (the README's truth grading rule: 1 aerial pixel).
//!
//! Oblique observations are graded by the oblique pipeline's own rule ([`oblique_verdict`], i.e.
//! `skytie_stages::oblique::grading::observation_errors`): against the surface the true panorama ray sees when
//! the campaign has `truth/scene.toml`, with non-matchable correspondences told apart, so a view's marks agree
//! with `oblique.*` in metrics.json.

// `!(x > t)` on purpose: it also rejects NaN, which `x <= t` would let through.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

use nalgebra::Vector3;
use skytie_stages::campaign::{AerialImage, Recording};
use skytie_stages::correspondence::PanoObservation;
use skytie_stages::geometry::{triangulate_rays, FrameCamera, PanoramaCamera, Ray};
use skytie_stages::oblique::grading::{
    observation_errors, SceneOracle, Truth, Verdict as ObliqueVerdict,
};

/// Largest distance, aerial pixels, between an observation and the truth projection for "correct".
pub const TOLERANCE_PX: f64 = 1.0;

/// The truth verdict of one aerial observation.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Verdict {
    Correct,
    Wrong,
    /// No truth available (or the point could not be reconstructed).
    Ungraded,
    /// Oblique, with the campaign's scene (`truth/scene.toml`): the panorama observation's surface point is sky,
    /// hidden from the oblique camera or outside its image (thesis 4.4.3; the README's oblique grading rule).
    NonMatchable,
}

/// One panorama observation: the true pose of its recording, the panorama size, the pixel.
pub struct TruePanoObservation<'a> {
    pub truth: &'a Recording,
    pub size_px: (u32, u32),
    pub u_px: f64,
    pub v_px: f64,
}

/// The control point's true object point from its panorama observations (see the module documentation).
pub fn true_point(obs: &[TruePanoObservation<'_>]) -> Option<Vector3<f64>> {
    let rays: Vec<Ray> = obs
        .iter()
        .map(|o| {
            PanoramaCamera::from_recording(o.truth, o.size_px.0, o.size_px.1)
                .pixel_ray(o.u_px, o.v_px)
        })
        .collect();
    match rays.len() {
        0 => None,
        1 => {
            let r = &rays[0];
            let ground_z = obs[0].truth.z - obs[0].truth.camera_height_m;
            ground_intersection(r, ground_z)
        }
        n => triangulate_rays(&rays, &vec![1e-3; n])
            .ok()
            .map(|t| t.point_world),
    }
}

/// Where a ray meets the horizontal plane z = `ground_z` (None if it points up or is parallel).
pub fn ground_intersection(r: &Ray, ground_z: f64) -> Option<Vector3<f64>> {
    let dz = r.dir_world.z;
    if !(dz < -1e-9) {
        return None;
    }
    let t = (ground_z - r.origin_world.z) / dz;
    (t > 0.0).then(|| r.at(t))
}

/// The verdict of an observation (u, v) in `aerial` of the true point `x`.
pub fn verdict(x: Option<&Vector3<f64>>, aerial: &AerialImage, u_px: f64, v_px: f64) -> Verdict {
    let Some(x) = x else {
        return Verdict::Ungraded;
    };
    match FrameCamera::from_aerial(aerial).project_world(x) {
        Some((u, v)) if (u - u_px).hypot(v - v_px) <= TOLERANCE_PX => Verdict::Correct,
        Some(_) => Verdict::Wrong,
        None => Verdict::Ungraded,
    }
}

/// What the oblique rule needs: the true poses and, when the campaign has one, its scene.
pub struct ObliqueTruth {
    pub truth: Truth,
    pub scene: Option<SceneOracle>,
}

/// The verdict of the oblique observation `oblique_px` in `oblique_id` of the panorama observation `mm`, whose
/// control point has the panorama observations `tie` (the oblique grading rule; see the module documentation).
pub fn oblique_verdict(
    t: &ObliqueTruth,
    tie: &[PanoObservation],
    mm: &PanoObservation,
    oblique_id: &str,
    oblique_px: [f64; 2],
) -> Verdict {
    match observation_errors(
        &t.truth,
        t.scene.as_ref(),
        Some(tie),
        mm,
        oblique_id,
        oblique_px,
    )
    .map(|e| e.verdict())
    {
        Some(ObliqueVerdict::Correct) => Verdict::Correct,
        Some(ObliqueVerdict::Wrong) => Verdict::Wrong,
        Some(ObliqueVerdict::NonMatchable) => Verdict::NonMatchable,
        None => Verdict::Ungraded,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn recording(x: f64, y: f64) -> Recording {
        Recording::new("r", 0.0, [x, y, 2.0], 30.0, 2.0)
    }

    fn nadir_camera() -> AerialImage {
        AerialImage::ideal("n", [5.0, 5.0, 500.0], [0.0; 3], 5000.0, [1000, 1000])
    }

    #[test]
    fn triangulated_point_grades_its_exact_projection_correct_and_a_shift_wrong() {
        let x_true = Vector3::new(4.0, 6.0, 0.0);
        let recs = [recording(0.0, 0.0), recording(8.0, 1.0)];
        let obs: Vec<TruePanoObservation> = recs
            .iter()
            .map(|r| {
                let cam = PanoramaCamera::from_recording(r, 2000, 1000);
                let (u, v) = cam.project_world(&x_true).unwrap();
                TruePanoObservation {
                    truth: r,
                    size_px: (2000, 1000),
                    u_px: u,
                    v_px: v,
                }
            })
            .collect();
        let x = true_point(&obs).unwrap();
        assert!((x - x_true).norm() < 1e-6, "{x}");
        let a = nadir_camera();
        let (u, v) = FrameCamera::from_aerial(&a).project_world(&x_true).unwrap();
        assert_eq!(verdict(Some(&x), &a, u + 0.5, v), Verdict::Correct);
        assert_eq!(verdict(Some(&x), &a, u + 3.0, v), Verdict::Wrong);
        assert_eq!(verdict(None, &a, u, v), Verdict::Ungraded);
        // One observation: the ground-plane intersection gives the same point (it lies on the ground).
        let one = true_point(&obs[..1]).unwrap();
        assert!((one - x_true).norm() < 1e-6, "{one}");
    }

    #[test]
    fn oblique_views_use_the_oblique_grading_rule() {
        // A façade point seen by two panoramas and by a camera looking at it obliquely (45°, from the south).
        let x_true = Vector3::new(4.0, 6.0, 3.0);
        let mut r0 = recording(0.0, 0.0);
        r0.image_id = "r0".into();
        let mut r1 = recording(8.0, 1.0);
        r1.image_id = "r1".into();
        let mut obl = nadir_camera();
        obl.image_id = "o".into();
        obl.y = x_true.y - 300.0;
        obl.z = x_true.z + 300.0;
        obl.x = x_true.x;
        obl.omega_deg = 45.0;
        let cam = FrameCamera::from_aerial(&obl);
        let (u, v) = cam
            .project_world(&x_true)
            .expect("in front of the oblique camera");
        assert!(cam.contains(u, v), "{u} {v}");
        let obs: Vec<PanoObservation> = [&r0, &r1]
            .iter()
            .map(|r| {
                let (pu, pv) = PanoramaCamera::from_recording(r, 2000, 1000)
                    .project_world(&x_true)
                    .unwrap();
                PanoObservation {
                    image_id: r.image_id.clone(),
                    u_px: pu,
                    v_px: pv,
                }
            })
            .collect();
        let t = ObliqueTruth {
            truth: Truth {
                recordings: [(&r0, "r0"), (&r1, "r1")]
                    .into_iter()
                    .map(|(r, id)| (id.to_string(), (r.clone(), 2000, 1000)))
                    .collect(),
                aerial: [("o".to_string(), obl.clone())].into_iter().collect(),
            },
            scene: None,
        };
        // Without a scene the reference is the triangulated point: 1 px off is within the rule's 1.5 px.
        assert_eq!(
            oblique_verdict(&t, &obs, &obs[0], "o", [u + 1.0, v]),
            Verdict::Correct
        );
        assert_eq!(
            oblique_verdict(&t, &obs, &obs[0], "o", [u + 4.0, v]),
            Verdict::Wrong
        );
        assert_eq!(
            oblique_verdict(&t, &obs, &obs[0], "x", [u, v]),
            Verdict::Ungraded
        );
    }
}
