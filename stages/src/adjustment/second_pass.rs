//! A second registration pass around the adjusted trajectory: the recordings that found no aerial control in
//! the first pass are searched again in the aerial images around where the first adjustment put them.
//!
//! A recording drifted farther than the nadir search windows (`overlap_margin_m`, `max_localisation_error_m`)
//! cannot be registered around its recorded position; once its registered neighbours are corrected, the
//! adjusted trajectory carries their correction to it (tie points and relative constraints), and its search
//! can start there with the normal windows. Moving a recording horizontally by `shift_world` moves its ortho
//! image's ground plane by the same vector and leaves its pixels unchanged (the projection depends only on the
//! position relative to the camera), so the second pass reuses the first pass's ortho images and tie points,
//! translated ([`Shiftable`]): the tie points' panorama observations, the
//! only thing the adjustment reads of them, are unchanged. The neighbours' ortho images that the refinement's
//! parallax check reads stay the first pass's, with the window's untranslated neighbour views.
//!
//! The pass is a graph construction of the pipeline; this module holds its pure parts: the shift of one
//! recording ([`pass_shift`]), the translated inputs, and the counts of the two passes
//! ([`RegistrationPasses`]).

use super::from_correspondences::RunRecording;
use crate::campaign::Recording;
use crate::nadir::{MmWindowMatch, OrthoImage, RecordingControl};
use crate::params::StageId;
use serde::{Deserialize, Serialize};

/// The identity of the node that derives a recording's shift from the first adjustment.
pub const PRIOR_STAGE: StageId = StageId::new("pass_prior", "1");
/// The identity of the node that translates a recording's tie-point window by its shift.
pub const SHIFT_WINDOW_STAGE: StageId = StageId::new("pass_window", "1");
/// The identity of the node that translates a recording's row by its shift.
pub const SHIFT_ROW_STAGE: StageId = StageId::new("pass_row", "1");
/// The identity of the node that translates a recording's aerial-oriented ortho image by its shift.
pub const SHIFT_ORTHO_STAGE: StageId = StageId::new("pass_ortho", "1");
/// The identity of the node that counts the registered recordings of both passes.
pub const PASSES_STAGE: StageId = StageId::new("registration_passes", "1");

/// Where the second pass searches one recording: its horizontal shift from the recorded position, world, m.
/// Zero for a recording the first pass registered (its second pass is its first, and cached as such).
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct PassShift {
    pub recording_id: String,
    pub shift_world: [f64; 2],
}

impl PassShift {
    /// Whether the recording is searched anywhere else than in the first pass.
    pub fn moves(&self) -> bool {
        self.shift_world != [0.0, 0.0]
    }
}

/// Whether a recording's own control (its window's points located in aerial images) registered it.
pub fn registered(control: Option<&RecordingControl>) -> bool {
    control.is_some_and(|c| !c.points.is_empty())
}

/// The shift of recording `recording_id` for the second pass: the first adjustment's horizontal correction
/// (adjusted − recorded) when the first pass did not register the recording (`registered_first = false`) and
/// the adjustment was delivered (`delivered`: it corrected something and the check points did not get worse);
/// zero otherwise, and for a recording the adjustment does not know or whose correction is not finite.
pub fn pass_shift(
    recording_id: &str,
    adjusted: &[RunRecording],
    registered_first: bool,
    delivered: bool,
) -> PassShift {
    let zero = PassShift {
        recording_id: recording_id.to_string(),
        shift_world: [0.0, 0.0],
    };
    if registered_first || !delivered {
        return zero;
    }
    let Some(rec) = adjusted.iter().find(|r| r.image_id == recording_id) else {
        return zero;
    };
    let shift = [
        rec.adjusted_world[0] - rec.recorded_world[0],
        rec.adjusted_world[1] - rec.recorded_world[1],
    ];
    if !(shift[0].is_finite() && shift[1].is_finite()) {
        return zero;
    }
    PassShift {
        shift_world: shift,
        ..zero
    }
}

/// An input of the registration that the second pass translates by a recording's shift. Each kind is its own
/// stage ([`Shiftable::STAGE`]), so its nodes keep their own cache identity.
pub trait Shiftable: Clone {
    /// The identity of the node that translates this kind.
    const STAGE: StageId;
    /// `self` moved horizontally by `shift`.
    fn shifted(&self, shift: &PassShift) -> Self;
}

/// The ortho image of a recording moved by `shift`: the same pixels on a ground plane translated by it.
impl Shiftable for OrthoImage {
    const STAGE: StageId = SHIFT_ORTHO_STAGE;
    fn shifted(&self, shift: &PassShift) -> Self {
        let mut out = self.clone();
        out.georef.foot_world[0] += shift.shift_world[0];
        out.georef.foot_world[1] += shift.shift_world[1];
        out
    }
}

/// The tie-point window of a recording moved by `shift`: the corners on the recording's own ground plane
/// (where the aerial stages look for them) are translated; the neighbours' views of them stay where the
/// neighbours' own (untranslated) ortho images show them, for the parallax check; the tie points themselves,
/// whose panorama observations the adjustment reads, are unchanged.
impl Shiftable for MmWindowMatch {
    const STAGE: StageId = SHIFT_WINDOW_STAGE;
    fn shifted(&self, shift: &PassShift) -> Self {
        let [dx, dy] = shift.shift_world;
        let mut out = self.clone();
        for g in &mut out.ground_world {
            g[0] += dx;
            g[1] += dy;
        }
        out
    }
}

/// A recording's row moved by `shift` (its recorded position translated horizontally).
impl Shiftable for Recording {
    const STAGE: StageId = SHIFT_ROW_STAGE;
    fn shifted(&self, shift: &PassShift) -> Self {
        let mut out = self.clone();
        out.x += shift.shift_world[0];
        out.y += shift.shift_world[1];
        out
    }
}

/// How many recordings each pass registered (own aerial control), and how many the second pass searched again
/// around a shifted position (`metrics.json` `registration_passes`).
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct RegistrationPasses {
    /// Recordings with a tie-point window (the ones that can be registered at all).
    pub recordings: usize,
    pub registered_first_pass: usize,
    /// After the second pass (the first pass's registrations included).
    pub registered_second_pass: usize,
    /// Recordings searched again around a shifted position.
    pub searched_again: usize,
}

impl RegistrationPasses {
    /// Count the passes from each recording's control in the first and second pass (parallel lists, `None`
    /// for a failed node) and their shifts.
    pub fn count(
        first: &[Option<&RecordingControl>],
        second: &[Option<&RecordingControl>],
        shifts: &[Option<&PassShift>],
    ) -> Self {
        RegistrationPasses {
            recordings: first.len(),
            registered_first_pass: first.iter().filter(|c| registered(**c)).count(),
            registered_second_pass: second.iter().filter(|c| registered(**c)).count(),
            searched_again: shifts
                .iter()
                .filter(|s| s.is_some_and(PassShift::moves))
                .count(),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::correspondence::AerialControlPoint;
    use crate::imaging::GrayImage;
    use crate::nadir::{OrthoGeoref, OrthoParams};
    use nalgebra::Vector3;

    fn recording(id: &str, recorded: [f64; 3], adjusted: [f64; 3]) -> RunRecording {
        RunRecording {
            image_id: id.into(),
            recorded_world: recorded,
            adjusted_world: adjusted,
            yaw_correction_deg: 0.0,
            sigma_m: [0.01; 3],
            sigma_yaw_deg: 0.0,
            sigma_is_a_posteriori: true,
        }
    }

    #[test]
    fn an_unregistered_recording_is_shifted_by_its_correction_and_a_registered_one_is_not() {
        let run = [
            recording("a", [100.0, 200.0, 3.0], [101.5, 199.0, 2.0]),
            recording("b", [110.0, 200.0, 3.0], [110.0, 200.0, 3.0]),
        ];
        let s = pass_shift("a", &run, false, true);
        assert_eq!(s.shift_world, [1.5, -1.0]);
        assert!(s.moves());
        assert!(!pass_shift("a", &run, true, true).moves());
        assert!(!pass_shift("a", &run, false, false).moves());
        assert!(!pass_shift("unknown", &run, false, true).moves());
        assert!(!pass_shift("b", &run, false, true).moves());
    }

    #[test]
    fn a_shifted_ortho_maps_the_shifted_world_point_to_the_same_pixel() {
        let params = OrthoParams {
            gsd_m: 0.1,
            diagonal_m: 20.0,
            rotation_deg: 33.0,
            ..OrthoParams::default()
        };
        let georef = OrthoGeoref::new([1000.0, 2000.0, 50.0], &params);
        let n = georef.width_px;
        let ortho = OrthoImage {
            image: GrayImage::filled(n, n, 0.5),
            valid: vec![1; n * n],
            georef,
        };
        let shift = PassShift {
            recording_id: "a".into(),
            shift_world: [1.7, -2.3],
        };
        let moved = ortho.shifted(&shift);
        let p = Vector3::new(1003.2, 1998.1, 50.0);
        let q = Vector3::new(p.x + 1.7, p.y - 2.3, p.z);
        let (u0, v0) = ortho.georef.world_to_pixel(&p);
        let (u1, v1) = moved.georef.world_to_pixel(&q);
        assert!((u0 - u1).abs() < 1e-9 && (v0 - v1).abs() < 1e-9);
        assert_eq!(moved.image, ortho.image);
    }

    #[test]
    fn a_shifted_window_moves_only_the_recordings_own_corners() {
        let window = MmWindowMatch {
            recording_id: "a".into(),
            pairs: Vec::new(),
            corners_detected: 1,
            tie_points: Vec::new(),
            ground_world: vec![[1.0, 2.0, 3.0]],
            neighbour_ground_world: vec![vec![crate::nadir::ViewGround {
                recording_id: "b".into(),
                ground_world: [1.1, 2.1, 3.0],
            }]],
        };
        let shift = PassShift {
            recording_id: "a".into(),
            shift_world: [0.5, -0.25],
        };
        let moved = window.shifted(&shift);
        assert_eq!(moved.ground_world, vec![[1.5, 1.75, 3.0]]);
        assert_eq!(moved.neighbour_ground_world, window.neighbour_ground_world);
        assert_eq!(moved.tie_points, window.tie_points);
    }

    #[test]
    fn the_passes_count_registered_recordings_and_shifts() {
        let point = AerialControlPoint {
            tie_point_id: "t".into(),
            mm: Vec::new(),
            aerial: Vec::new(),
            point_world: None,
            covariance_m2: None,
            map: None,
        };
        let with = RecordingControl {
            recording_id: "a".into(),
            points: vec![point],
        };
        let without = RecordingControl {
            recording_id: "b".into(),
            points: Vec::new(),
        };
        let moved = PassShift {
            recording_id: "b".into(),
            shift_world: [1.0, 0.0],
        };
        let still = PassShift::default();
        let counts = RegistrationPasses::count(
            &[Some(&with), Some(&without), None],
            &[Some(&with), Some(&with), None],
            &[Some(&still), Some(&moved), None],
        );
        assert_eq!(
            counts,
            RegistrationPasses {
                recordings: 3,
                registered_first_pass: 1,
                registered_second_pass: 2,
                searched_again: 1,
            }
        );
    }
}
