//! Types that flow between the oblique pipeline's stages (thesis ch. 4): the sparse cloud of a panorama
//! triplet (4.4.1), the façade planes found in it with their candidate oblique images (4.4.2–4.4.4), the patch
//! registrations per (panorama × oblique image) (4.4.5–4.4.6) and the consensus result (4.4.7).
//!
//! Conventions: world coordinates f64 metres; panorama and oblique pixels are continuous pixels of the
//! *original* images (campaign-format.md: first pixel centre at (0.5, 0.5)). Items are identified by the
//! `image_id`s of the campaign, so grown campaigns re-run little.

use crate::correspondence::{AerialControlPoint, MmTiePoint, PanoObservation};
use serde::{Deserialize, Serialize};

/// Side of the trajectory, seen in the driving direction (`heading` of the recording).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, Deserialize)]
pub enum StreetSide {
    Left,
    Right,
}

impl StreetSide {
    pub const BOTH: [StreetSide; 2] = [StreetSide::Left, StreetSide::Right];

    pub fn label(self) -> &'static str {
        match self {
            StreetSide::Left => "left",
            StreetSide::Right => "right",
        }
    }
}

/// One point of the sparse cloud: an MM tie point (observations in 2–3 panoramas of the triplet, triangulated
/// in the original equirectangular geometry, thesis 4.4.1 last paragraph) and the side it was matched on.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct SparsePoint {
    pub side: StreetSide,
    /// `tie.id` is `<centre image_id>#<side>#<index>`; `tie.observations` are in trajectory order.
    pub tie: MmTiePoint,
}

/// Counts of one triplet's sparse-cloud computation (for metrics; every drop is counted).
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct SparseCloudStats {
    /// Perspective views rendered (6 for a full triplet: 3 per side).
    pub views: usize,
    /// AGAST corners summed over the views.
    pub corners: usize,
    /// Descriptor matches views 1–2 and 2–3 (summed over both sides).
    pub matches_12: usize,
    pub matches_23: usize,
    /// Three-view tracks linked through view 2.
    pub tracks: usize,
    /// Tracks rejected by trifocal point transfer.
    pub rejected_trifocal: usize,
    /// Tracks rejected at triangulation (rays behind a camera, too small an angle, too far, residual).
    pub rejected_triangulation: usize,
    /// Points kept (`SparseCloud::points.len()`).
    pub points: usize,
    /// Tracks of the wide first matching that measured the relative positions (both sides).
    pub pose_tracks: usize,
    /// 1 when the measured relative positions were used, 0 when the recorded ones were kept.
    pub pose_corrected: usize,
    /// The position corrections of the three recordings (world x, y, z, metres; the centre's is zero, and all
    /// are zero when the recorded positions were kept).
    pub pose_corrections_m: [[f64; 3]; 3],
}

/// The sparse cloud of one panorama triplet (thesis 4.4.1): recordings i−1, i, i+1 along the trajectory.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct SparseCloud {
    /// `image_id`s of views 1, 2, 3 (trajectory order); view 2 is the triplet's centre.
    pub recordings: [String; 3],
    pub points: Vec<SparsePoint>,
    pub stats: SparseCloudStats,
}

impl SparseCloudStats {
    /// The larger of the two outer recordings' position corrections, metres.
    pub fn pose_correction_m(&self) -> f64 {
        self.pose_corrections_m
            .iter()
            .map(|c| c[0].hypot(c[1]).hypot(c[2]))
            .fold(0.0, f64::max)
    }
}

impl SparseCloud {
    pub fn centre(&self) -> &str {
        &self.recordings[1]
    }

    /// The neighbourhood cloud of a triplet for plane fitting (thesis 4.4.2 fits façades to the points along
    /// the trajectory; one triplet alone sees a façade stretch of a few metres with too few points for a
    /// plane): `self`'s points followed by those of `neighbours` (other triplets along the same street), with
    /// `self`'s recordings. Point order is input order, so plane inlier indices are reproducible; the stats
    /// are `self`'s, except `points`.
    pub fn with_neighbours<'a>(
        &self,
        neighbours: impl IntoIterator<Item = &'a SparseCloud>,
    ) -> Self {
        let mut merged = self.clone();
        for n in neighbours {
            merged.points.extend(n.points.iter().cloned());
        }
        merged.stats.points = merged.points.len();
        merged
    }
}

/// An oblique image that passed the visibility hypothesis for a façade plane (thesis 4.4.3).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ObliqueView {
    /// `image_id` in `aerial/oblique/cameras.csv`.
    pub image_id: String,
    /// Eq. 4/5 and 4/6, degrees (both ≤ the threshold, default 70°).
    pub theta_deg: f64,
    pub phi_deg: f64,
    /// Theoretical resolution at the plane centroid (pixel footprint on the plane), metres.
    pub resolution_m: f64,
    /// The centroid back-projected into the oblique image (continuous pixels; inside the image).
    pub centroid_px: [f64; 2],
}

/// A façade plane found in a triplet's sparse cloud (thesis 4.4.2–4.4.4).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct FacadePlane {
    pub side: StreetSide,
    /// Unit normal, world frame, pointing from the façade towards the street (the centre recording).
    pub normal_world: [f64; 3],
    /// Centroid of the inliers (p_avg), world, m.
    pub centroid_world: [f64; 3],
    /// In-plane axes of the local patch frame (eq. 4/7: covariance eigenvectors projected into the plane,
    /// orthonormal, `axis_u × axis_v = normal`): `axis_u_world` roughly horizontal along the façade,
    /// `axis_v_world` roughly up.
    pub axis_u_world: [f64; 3],
    pub axis_v_world: [f64; 3],
    /// Indices into `SparseCloud::points` of the plane's inliers (within the distance threshold).
    pub inliers: Vec<usize>,
    /// Subset of `inliers` kept by box-grid thinning (4.4.4): the patch centres.
    pub thinned: Vec<usize>,
    /// Sparse points between the plane and the centre recording (occlusion test, 4.4.2).
    pub occluding_points: usize,
    /// Oblique images that passed the visibility hypothesis (4.4.3), ordered by `image_id`.
    pub views: Vec<ObliqueView>,
}

/// Counts of one triplet's façade search (for metrics).
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct FacadeStats {
    /// Sparse points considered per side (after the side split).
    pub candidate_points: usize,
    /// Planes accepted (not occluded, enough inliers, collinearity and angle criteria met).
    pub planes: usize,
    /// Sides where no plane met the criteria (angle, minimum points, collinearity).
    pub sides_without_plane: usize,
    /// Planes rejected as occluded.
    pub occluded: usize,
    /// Inliers before / after thinning, summed over the accepted planes.
    pub inliers: usize,
    pub thinned: usize,
    /// (plane × oblique image) pairs that passed / failed the visibility hypothesis.
    pub visible_views: usize,
    pub rejected_views: usize,
}

/// The façades of one triplet: up to one plane per side (thesis 4.4.2 fits per side).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct TripletFacades {
    /// The triplet's centre recording (`SparseCloud::centre`), whose panorama gives the MM patches.
    pub recording: String,
    pub planes: Vec<FacadePlane>,
    pub stats: FacadeStats,
}

/// One patch registration (thesis 4.4.5–4.4.6): an inlier object point of a façade plane, its patch from the
/// centre panorama and from one oblique image, and the translation found between them.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct PatchMatch {
    /// `MmTiePoint::id` of the sparse point at the patch centre.
    pub point_id: String,
    pub side: StreetSide,
    /// The sparse point (patch centre), world, m (triangulated from the recorded, possibly wrong, MM poses).
    pub object_point_world: [f64; 3],
    /// The centre panorama's observation of the point (the MM patch centre).
    pub mm: PanoObservation,
    /// The oblique image of this registration.
    pub oblique_image_id: String,
    /// Translation of the patch content in the plane frame (`axis_u`, `axis_v`), metres: the content at the
    /// MM patch centre appears in the oblique patch at `object_point + shift_u·axis_u + shift_v·axis_v`.
    /// Final (fine, or single-level) result.
    pub shift_plane_m: [f64; 2],
    /// The coarse level's shift when hierarchical matching ran.
    pub coarse_shift_plane_m: Option<[f64; 2]>,
    /// `object_point + shift` (world, m): where the oblique image sees the MM patch centre's content.
    pub matched_point_world: [f64; 3],
    /// `matched_point_world` projected into the oblique image: the oblique observation (continuous px).
    pub oblique_px: [f64; 2],
    /// Similarity at the optimum (MI in nats for MI, correlation for NCC; higher is better).
    pub score: f64,
    /// Real-resolution ratio of the oblique patch (4.4.5; ≥ the threshold, default 0.6).
    pub real_resolution_ratio: f64,
    /// Rejected by the 2-D median consensus after the coarse level (4.4.7); such matches skip the fine level.
    pub rejected_coarse: bool,
    /// The pyramid level of the oblique image the patches were made at (its pixels are 2^level full
    /// pixels): the observation's precision is the image's `sigma_px` in pixels of this level.
    #[serde(default)]
    pub level: usize,
}

/// Counts of one (panorama × oblique image) registration set (for metrics).
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct PatchStats {
    /// Patch centres offered (thinned inliers of planes that see this oblique image).
    pub candidates: usize,
    /// Rejected for a low real-resolution ratio, or because the patch left the image / the panorama.
    pub rejected_resolution: usize,
    pub rejected_outside: usize,
    /// Registrations that failed to converge or had no valid overlap.
    pub failed: usize,
    /// Rejected by the coarse 2-D consensus.
    pub rejected_coarse: usize,
    /// Matches produced (including `rejected_coarse` ones).
    pub matches: usize,
}

/// All patch registrations between one panorama (a triplet centre) and one oblique image.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct PatchRegistrationSet {
    pub recording: String,
    pub oblique_image_id: String,
    pub matches: Vec<PatchMatch>,
    pub stats: PatchStats,
}

/// A patch match after the 3-D median consensus (thesis 4.4.7).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ObliqueCorrespondence {
    pub matched: PatchMatch,
    /// Recording of the registration set (the panorama).
    pub recording: String,
    /// Distance of this match's 3-D translation from its set's median translation, m.
    pub deviation_from_median_m: f64,
    /// Kept by the consensus (not an outlier).
    pub kept: bool,
}

/// Counts of the consensus (for metrics).
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct ConsensusStats {
    /// Matches that entered (not rejected at the coarse level).
    pub correspondences: usize,
    pub kept: usize,
    pub rejected: usize,
    /// Sets (panorama × oblique image) with too few matches for a median (kept unchanged or dropped,
    /// as the params say; counted here).
    pub small_sets: usize,
    /// Recordings with at least one kept correspondence.
    pub recordings_with_correspondences: usize,
    /// Control points with ≥ 2 oblique observations (triangulated) and with exactly one.
    pub control_points: usize,
    pub single_image_points: usize,
}

/// The oblique pipeline's output for one variant: every correspondence with its consensus flag, the sparse
/// cloud tie points that the adjustment uses as MM–MM observations, and the oblique control points (aerial
/// observations of kind `Oblique`; `point_world` triangulated when seen in ≥ 2 oblique images).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ObliqueResult {
    pub correspondences: Vec<ObliqueCorrespondence>,
    pub control: Vec<AerialControlPoint>,
    pub stats: ConsensusStats,
}
