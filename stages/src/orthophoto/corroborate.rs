//! Which tie points located in the orthophoto are kept: the refinement's peak criterion relaxed where the
//! orthophoto's geometry corroborates the location. An orthophoto and the north-up ortho differ by a
//! translation only, so every correctly located tie point of one recording has the same correction (observed −
//! predicted) up to a fraction of a pixel, while a wrong peak falls anywhere in the ± `search_margin_px` search
//! window. A template partly hidden in the orthophoto (a tree crown over the road, a car parked in the
//! aerial epoch) correlates weaker than `min_peak` at its correct place; such a weak peak is kept when it lies
//! within `corroboration_px` of the recording's agreed correction and at least `min_corroborating` tie points
//! (weak or strong) agree there. A chance peak meets one given pixel disc of radius r in a (2m + 1)² window
//! with probability ≈ πr²/(2m + 1)² (0.5 % for r = 1, m = 12), so agreeing weak peaks are not chance.
//!
//! A tie point's correction is measured from where its triangulated position (the panoramas' ray intersection,
//! `MmTiePoint::point_world`) falls in the orthophoto through the recording's registration, not from its corner
//! on the ortho's ground plane: the plane lies `camera_height` below the camera, and a ground point Δh below
//! the plane at horizontal distance r shows in the ortho r·Δh/(h + Δh) nearer the camera (a road's camber and
//! the terrain's slope put Δh at several centimetres: on the demo scenes the tie points lie a median 4 cm and
//! up to 13 cm below the plane, 6.5 m out, which is 1–4 working pixels of 0.1 m). Corrections from the plane
//! therefore spread radially around the car by more than the corroboration radius even where every peak is
//! right; the triangulated positions carry no such parallax, so correct peaks agree to the triangulation's
//! own error.
//!
//! The agreed correction is the median of the strong peaks' corrections (≥ `min_peak`) when the recording has
//! any, else the median of all: weak peaks under the same crowns are displaced alike (the visible part of each
//! template pulls its peak the same way), so several of them can agree with each other a few pixels away from
//! the strong ones, and outnumber them. Strong peaks keep the refinement's own shift-consistency check.

use crate::estimators::median_consensus::median_consensus;
use crate::geometry::Similarity2;
use crate::nadir::{AerialMatch, MmWindowMatch, OrthoGeoref};
use nalgebra::{Vector2, Vector3};

/// Where each of `matches`' tie points (looked up by id in `window`) lies in the orthophoto, full pixels: its
/// triangulated position's vertical projection onto the ortho (`georef`), through the registration
/// `ortho_to_photo` (ortho px → full orthophoto px). A match whose tie point is not in the window keeps its
/// prediction.
pub fn triangulated_references(
    matches: &[AerialMatch],
    window: &MmWindowMatch,
    georef: &OrthoGeoref,
    ortho_to_photo: &Similarity2,
) -> Vec<[f64; 2]> {
    matches
        .iter()
        .map(|m| {
            let Some(tp) = window.tie_points.iter().find(|tp| tp.id == m.tie_point_id) else {
                return [m.predicted_u_px, m.predicted_v_px];
            };
            let [x, y, z] = tp.point_world;
            let (u, v) = georef.world_to_pixel(&Vector3::new(x, y, z));
            let r = ortho_to_photo.apply(&Vector2::new(u, v));
            [r.x, r.y]
        })
        .collect()
}

/// The correction (observed − `reference`, full pixels) of `m` in working pixels (`scale` full pixels per
/// working pixel).
fn correction(m: &AerialMatch, reference: [f64; 2], scale: f64) -> [f64; 2] {
    [
        (m.observation.u_px - reference[0]) / scale,
        (m.observation.v_px - reference[1]) / scale,
    ]
}

/// What [`corroborated`] kept and dropped.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Corroboration {
    pub kept: Vec<AerialMatch>,
    /// Weak peaks (below `min_peak`) kept because their correction agrees with the others'.
    pub weak_kept: usize,
    /// Weak peaks dropped: away from the agreed correction, or too few agreeing.
    pub weak_dropped: usize,
}

/// The matches to keep among `matches` (one recording, one orthophoto): every one with a peak ≥ `min_peak`,
/// and those with a weaker peak whose correction lies within `radius_px` (working pixels; `scale` full pixels
/// each) of the agreed correction — the median correction of the strong matches, or of all matches when none
/// is strong — when at least `min_agreeing` matches lie there. A match's correction is its observation minus
/// its entry of `references` (full orthophoto pixels: where its tie point's triangulated position falls, see
/// the module documentation); a match without one (`references` shorter) is measured from its prediction.
/// The order of `matches` is kept.
pub fn corroborated(
    matches: Vec<AerialMatch>,
    references: &[[f64; 2]],
    min_peak: f64,
    radius_px: f64,
    min_agreeing: usize,
    scale: f64,
) -> Corroboration {
    let strong = |m: &AerialMatch| m.observation.score >= min_peak;
    let n_weak = matches.iter().filter(|m| !strong(m)).count();
    let corrections: Vec<[f64; 2]> = matches
        .iter()
        .enumerate()
        .map(|(k, m)| {
            let r = references
                .get(k)
                .copied()
                .unwrap_or([m.predicted_u_px, m.predicted_v_px]);
            correction(m, r, scale)
        })
        .collect();
    let strong_corrections: Vec<[f64; 2]> = matches
        .iter()
        .zip(&corrections)
        .filter_map(|(m, c)| strong(m).then_some(*c))
        .collect();
    let anchor_set = if strong_corrections.is_empty() {
        &corrections
    } else {
        &strong_corrections
    };
    let agreeing: Option<Vec<bool>> = median_consensus(anchor_set, radius_px)
        .map(|c| {
            corrections
                .iter()
                .map(|v| (v[0] - c.median[0]).hypot(v[1] - c.median[1]) <= radius_px)
                .collect::<Vec<bool>>()
        })
        .filter(|a| a.iter().filter(|&&i| i).count() >= min_agreeing.max(1));
    let mut out = Corroboration::default();
    for (k, m) in matches.into_iter().enumerate() {
        let is_strong = strong(&m);
        let agrees = agreeing.as_ref().is_some_and(|a| a[k]);
        if is_strong || agrees {
            out.weak_kept += usize::from(!is_strong);
            out.kept.push(m);
        }
    }
    out.weak_dropped = n_weak - out.weak_kept;
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn located(id: &str, shift: (f64, f64), peak: f64) -> AerialMatch {
        AerialMatch::shifted(id, "ortho", (500.0, 700.0), shift, peak)
    }

    fn ids(c: &Corroboration) -> Vec<&str> {
        c.kept.iter().map(|m| m.tie_point_id.as_str()).collect()
    }

    /// Weak peaks at the agreed correction are kept and stray ones dropped; without enough agreement the weak
    /// ones are dropped and the strong ones kept. Per case: the matches, the ids kept, (weak kept, weak dropped).
    #[test]
    fn weak_peaks_are_kept_where_enough_peaks_agree_strong_ones_always() {
        let cases = [
            (
                vec![
                    located("weak_a", (2.1, -0.4), 0.55),
                    located("strong", (2.3, -0.5), 0.9),
                    located("weak_b", (1.8, -0.2), 0.62),
                    located("stray", (-7.0, 5.0), 0.58),
                    located("weak_c", (2.4, -0.6), 0.51),
                ],
                vec!["weak_a", "strong", "weak_b", "weak_c"],
                (3, 1),
            ),
            (
                vec![
                    located("weak_a", (2.0, 0.0), 0.6),
                    located("strong", (9.0, 3.0), 0.8),
                    located("weak_b", (-4.0, 6.0), 0.6),
                ],
                vec!["strong"],
                (0, 2),
            ),
        ];
        for (m, kept, weak) in cases {
            let c = corroborated(m, &[], 0.75, 1.0, 3, 1.0);
            assert_eq!(ids(&c), kept);
            assert_eq!((c.weak_kept, c.weak_dropped), weak);
        }
    }

    #[test]
    fn the_radius_is_in_working_pixels() {
        // At pyramid level 1 (2 full pixels per working pixel) 1.2 full pixels from the median are 0.6 working
        // pixels: all three agree; at level 0 only the median one does, too few.
        let m = vec![
            located("a", (0.0, 0.0), 0.6),
            located("b", (2.4, 0.0), 0.6),
            located("c", (1.2, 0.0), 0.6),
        ];
        assert_eq!(
            corroborated(m.clone(), &[], 0.75, 1.0, 3, 2.0).kept.len(),
            3
        );
        assert!(corroborated(m, &[], 0.75, 1.0, 3, 1.0).kept.is_empty());
    }

    /// A camera h = 2.2 m above the ortho's plane, at the origin (north-up, 0.1 m pixels: pixel = 10 × metre,
    /// v southwards); the road falls away from the car, so a ground point r metres out (r = 4 … 9 m, six
    /// directions) lies Δh = 0.01·r m below the plane and the ortho shows it r·h/(h + Δh) from the camera —
    /// its corner on the plane, 0.7–3.5 px nearer the car. The orthophoto shows it at its true place shifted
    /// by the recording's offset (3, −2) px; the triangulated position is the true one.
    fn radial_scene() -> (Vec<AerialMatch>, Vec<[f64; 2]>) {
        let h = 2.2;
        let mut matches = Vec::new();
        let mut references = Vec::new();
        for (k, deg) in [0.0f64, 60.0, 120.0, 180.0, 240.0, 300.0]
            .iter()
            .enumerate()
        {
            let r = 4.0 + k as f64;
            let (s, c) = deg.to_radians().sin_cos();
            let true_xy = [r * s, r * c];
            let dh = 0.01 * r;
            let plane = [true_xy[0] * h / (h + dh), true_xy[1] * h / (h + dh)];
            let px = |p: [f64; 2]| [500.0 + 10.0 * p[0], 700.0 - 10.0 * p[1]];
            let (t, pl) = (px(true_xy), px(plane));
            let mut m = located(&format!("tp{k}"), (0.0, 0.0), 0.6);
            m.observation.u_px = t[0] + 3.0;
            m.observation.v_px = t[1] - 2.0;
            m.predicted_u_px = pl[0];
            m.predicted_v_px = pl[1];
            matches.push(m);
            references.push(t);
        }
        (matches, references)
    }

    #[test]
    fn references_are_the_triangulated_positions_through_the_registration() {
        use crate::correspondence::{MmTiePoint, PanoObservation};
        // A 200 × 200 px north-up ortho of 0.1 m pixels centred at (1000, 2000); the orthophoto pixel of an
        // ortho pixel is (u + 50, v − 30) (a pure translation, as the registration finds it).
        let georef = OrthoGeoref {
            foot_world: [1000.0, 2000.0, 10.0],
            gsd_m: 0.1,
            rotation_deg: 0.0,
            width_px: 200,
            height_px: 200,
        };
        let tf = Similarity2::new(1.0, 0.0, 50.0, -30.0);
        let obs = PanoObservation {
            image_id: "r1".into(),
            u_px: 1.0,
            v_px: 2.0,
        };
        let tie_point = MmTiePoint {
            id: "r1#4".into(),
            observations: vec![obs.clone(), obs],
            // 3 m east and 2 m north of the foot, 0.2 m below the plane: its height plays no part.
            point_world: [1003.0, 2002.0, 9.8],
            covariance_m2: [[0.0; 3]; 3],
            max_angle_deg: 10.0,
        };
        let window = MmWindowMatch {
            recording_id: "r1".into(),
            pairs: Vec::new(),
            corners_detected: 1,
            tie_points: vec![tie_point],
            ground_world: vec![[1002.9, 2001.9, 10.0]],
            neighbour_ground_world: vec![Vec::new()],
        };
        let m = vec![
            located("r1#4", (0.0, 0.0), 0.6),
            located("elsewhere", (0.0, 0.0), 0.6),
        ];
        let refs = triangulated_references(&m, &window, &georef, &tf);
        // Ortho pixel (100 + 30, 100 − 20) → orthophoto (180, 50); the unknown tie point keeps its prediction.
        assert!(
            (refs[0][0] - 180.0).abs() < 1e-9 && (refs[0][1] - 50.0).abs() < 1e-9,
            "{refs:?}"
        );
        assert_eq!(refs[1], [500.0, 700.0]);
    }

    #[test]
    fn corrections_from_the_triangulated_positions_agree_where_the_ground_plane_spreads_them() {
        let (m, refs) = radial_scene();
        // From the ground plane the six corrections spread radially by 0.7–3.5 px around (3, −2): one lies
        // within 1 px of their median, too few, so every weak peak is dropped.
        let from_plane = corroborated(m.clone(), &[], 0.75, 1.0, 3, 1.0);
        assert!(from_plane.kept.is_empty(), "{:?}", ids(&from_plane));
        // From the triangulated positions all six agree on (3, −2) exactly.
        let c = corroborated(m, &refs, 0.75, 1.0, 3, 1.0);
        assert_eq!(ids(&c), ["tp0", "tp1", "tp2", "tp3", "tp4", "tp5"]);
        assert_eq!((c.weak_kept, c.weak_dropped), (6, 0));
    }

    #[test]
    fn weak_peaks_that_outnumber_the_strong_ones_are_held_to_the_strong_ones_correction() {
        // Four weak peaks agree on (2, 0); the two strong ones on (0, 0). The median of all six is (2, 0), but
        // the strong peaks set the correction: the weak ones 2 px away are dropped, the one at (0.3, 0.2) kept.
        let m = vec![
            located("strong_a", (0.1, -0.1), 0.85),
            located("weak_a", (2.0, 0.1), 0.6),
            located("weak_b", (2.1, -0.1), 0.62),
            located("weak_c", (1.9, 0.0), 0.58),
            located("weak_d", (2.0, 0.0), 0.55),
            located("strong_b", (-0.1, 0.1), 0.8),
            located("weak_e", (0.3, 0.2), 0.6),
        ];
        let c = corroborated(m, &[], 0.75, 1.0, 3, 1.0);
        assert_eq!(ids(&c), ["strong_a", "strong_b", "weak_e"]);
        assert_eq!((c.weak_kept, c.weak_dropped), (1, 4));
    }
}
