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
//! The oblique chain is searched again the same way, for every recording: its patches are predicted from the
//! sparse cloud and façades of the recordings' poses, so a recording farther off than the patch search radius
//! (or a pose error that lets a façade patch slide to a wrong place near the prediction) is registered again
//! from the adjusted trajectory ([`trajectory_shift`], horizontal and vertical: a façade patch depends on the
//! height too). The matches' panorama and oblique pixels do not depend on the pose they were predicted from,
//! so the second adjustment reads them with the recorded positions as its priors, like the first.
//!
//! The pass is a graph construction of the pipeline; this module holds its pure parts: the shift of one
//! recording ([`pass_shift`], [`trajectory_shift`]), the translated inputs, and the counts of the two passes
//! ([`RegistrationPasses`]).

use super::from_correspondences::RunRecording;
use crate::campaign::Recording;
use crate::nadir::{MmWindowMatch, OrthoImage, RecordingControl};
use crate::params::StageId;
use serde::{Deserialize, Serialize};

/// The identity of the node that derives a recording's shift from the first adjustment.
pub const PRIOR_STAGE: StageId = StageId::new("pass_prior", "2");
/// The identity of the node that derives a recording's shift for the oblique chain's second pass.
pub const TRAJECTORY_PRIOR_STAGE: StageId = StageId::new("pass_trajectory", "1");
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
    /// Vertical shift, m (zero for the nadir chain, whose ortho images depend only on the position relative
    /// to the camera).
    pub shift_z_m: f64,
}

impl PassShift {
    /// No shift: the recording is searched where the first pass searched it.
    pub fn zero(recording_id: &str) -> Self {
        Self {
            recording_id: recording_id.to_string(),
            shift_world: [0.0, 0.0],
            shift_z_m: 0.0,
        }
    }

    /// Whether the recording is searched anywhere else than in the first pass.
    pub fn moves(&self) -> bool {
        self.shift_world != [0.0, 0.0] || self.shift_z_m != 0.0
    }
}

/// Where the first adjustment lists a recording: its `image_id` and a hint of its position in the
/// adjustment's list (the recording's position in the campaign; the adjustment lists the campaign's
/// recordings in order, without the rows dropped as bad input, so the recording is at the hint or a few
/// places before it). The lookup goes backwards from the hint, then forwards, so a city-size campaign's
/// shifts cost O(n · dropped rows), not O(n²); a wrong hint only costs time.
#[derive(Clone, Copy, Debug)]
pub struct RecordingRef<'a> {
    pub image_id: &'a str,
    pub index_hint: usize,
}

impl RecordingRef<'_> {
    fn find<'r>(&self, adjusted: &'r [RunRecording]) -> Option<&'r RunRecording> {
        let start = self.index_hint.min(adjusted.len().saturating_sub(1));
        let (before, after) = adjusted.split_at(adjusted.len().min(start + 1));
        before
            .iter()
            .rev()
            .chain(after)
            .find(|r| r.image_id == self.image_id)
    }
}

/// The first adjustment's correction (adjusted − recorded) of `recording`, world, m; `None` for a recording
/// the adjustment does not know or whose correction is not finite.
fn correction(recording: RecordingRef<'_>, adjusted: &[RunRecording]) -> Option<[f64; 3]> {
    let rec = recording.find(adjusted)?;
    let d: [f64; 3] = std::array::from_fn(|i| rec.adjusted_world[i] - rec.recorded_world[i]);
    d.iter().all(|v| v.is_finite()).then_some(d)
}

/// Whether a recording's own control (its window's points located in aerial images) registered it.
pub fn registered(control: Option<&RecordingControl>) -> bool {
    control.is_some_and(|c| !c.points.is_empty())
}

/// The shift of `recording` for the second pass: the first adjustment's horizontal correction
/// (adjusted − recorded) when the first pass did not register the recording (`registered_first = false`) and
/// the adjustment was delivered (`delivered`: it corrected something and the check points did not get worse);
/// zero otherwise, and for a recording the adjustment does not know or whose correction is not finite.
pub fn pass_shift(
    recording: RecordingRef<'_>,
    adjusted: &[RunRecording],
    registered_first: bool,
    delivered: bool,
) -> PassShift {
    match correction(recording, adjusted) {
        Some(d) if delivered && !registered_first => PassShift {
            shift_world: [d[0], d[1]],
            ..PassShift::zero(recording.image_id)
        },
        _ => PassShift::zero(recording.image_id),
    }
}

/// The shift of `recording` for the oblique chain's second pass: the first adjustment's
/// correction, horizontal and vertical, for every recording when the adjustment was delivered (`delivered`);
/// zero otherwise, and for a recording the adjustment does not know or whose correction is not finite.
pub fn trajectory_shift(
    recording: RecordingRef<'_>,
    adjusted: &[RunRecording],
    delivered: bool,
) -> PassShift {
    match correction(recording, adjusted) {
        Some(d) if delivered => PassShift {
            shift_world: [d[0], d[1]],
            shift_z_m: d[2],
            ..PassShift::zero(recording.image_id)
        },
        _ => PassShift::zero(recording.image_id),
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

/// A recording's row moved by `shift` (its recorded position translated).
impl Shiftable for Recording {
    const STAGE: StageId = SHIFT_ROW_STAGE;
    fn shifted(&self, shift: &PassShift) -> Self {
        let mut out = self.clone();
        out.x += shift.shift_world[0];
        out.y += shift.shift_world[1];
        out.z += shift.shift_z_m;
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

    /// `id` with a hint that is wrong for every recording but the second, so the lookup runs both ways.
    fn at(id: &str) -> RecordingRef<'_> {
        RecordingRef {
            image_id: id,
            index_hint: 1,
        }
    }

    #[test]
    fn a_recording_is_found_whatever_its_hint() {
        let run: Vec<_> = (0..6)
            .map(|i| recording(&format!("r{i}"), [0.0; 3], [f64::from(i), 0.0, 0.0]))
            .collect();
        for hint in [0, 2, 5, 6, 100] {
            for i in 0..6 {
                let id = format!("r{i}");
                let r = RecordingRef {
                    image_id: &id,
                    index_hint: hint,
                };
                assert_eq!(r.find(&run).map(|r| r.image_id.as_str()), Some(id.as_str()));
            }
            let missing = RecordingRef {
                image_id: "r9",
                index_hint: hint,
            };
            assert!(missing.find(&run).is_none());
        }
        assert!(at("r0").find(&[]).is_none());
    }

    fn recording(id: &str, recorded: [f64; 3], adjusted: [f64; 3]) -> RunRecording {
        RunRecording {
            image_id: id.into(),
            recorded_world: recorded,
            adjusted_world: adjusted,
            yaw_correction_deg: 0.0,
            sigma_m: [0.01; 3],
            sigma_yaw_deg: 0.0,
            sigma_is_a_posteriori: true,
            held: Default::default(),
        }
    }

    #[test]
    fn an_unregistered_recording_is_shifted_by_its_correction_and_a_registered_one_is_not() {
        let run = [
            recording("a", [100.0, 200.0, 3.0], [101.5, 199.0, 2.0]),
            recording("b", [110.0, 200.0, 3.0], [110.0, 200.0, 3.0]),
        ];
        let s = pass_shift(at("a"), &run, false, true);
        assert_eq!(s.shift_world, [1.5, -1.0]);
        assert!(s.moves());
        assert!(!pass_shift(at("a"), &run, true, true).moves());
        assert!(!pass_shift(at("a"), &run, false, false).moves());
        assert!(!pass_shift(at("unknown"), &run, false, true).moves());
        assert!(!pass_shift(at("b"), &run, false, true).moves());
        assert_eq!(pass_shift(at("a"), &run, false, true).shift_z_m, 0.0);
    }

    #[test]
    fn the_oblique_pass_shifts_every_recording_by_its_whole_correction() {
        let run = [
            recording("a", [100.0, 200.0, 3.0], [101.5, 199.0, 2.5]),
            recording("b", [110.0, 200.0, 3.0], [110.0, 200.0, 3.0]),
            recording("c", [120.0, 200.0, 3.0], [f64::NAN, 200.0, 3.0]),
        ];
        let s = trajectory_shift(at("a"), &run, true);
        assert_eq!((s.shift_world, s.shift_z_m), ([1.5, -1.0], -0.5));
        let row = Recording {
            x: 100.0,
            y: 200.0,
            z: 3.0,
            ..Recording::default()
        }
        .shifted(&s);
        assert_eq!([row.x, row.y, row.z], [101.5, 199.0, 2.5]);
        assert!(!trajectory_shift(at("a"), &run, false).moves());
        assert!(!trajectory_shift(at("b"), &run, true).moves());
        assert!(!trajectory_shift(at("c"), &run, true).moves());
        assert!(!trajectory_shift(at("unknown"), &run, true).moves());
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
            shift_z_m: 0.0,
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
            shift_z_m: 0.0,
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
            ray_ground: None,
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
            shift_z_m: 0.0,
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
