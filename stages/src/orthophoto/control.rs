//! Control points from the orthophoto (the orthophoto's counterpart of thesis 3.4.5.4): every tie point of a
//! recording's MM matching window located in the orthophoto by the phase-correlation refinement becomes a
//! control point. Its XY is the orthophoto pixel through the tile's geotransform; its Z is interpolated in the
//! DTM, or — without a DTM, or where the DTM has no value — the tie point's height triangulated from the
//! panoramas (flagged [`HeightSource::MmGround`] and counted). Its covariance is diagonal: σ_xy² = (stated
//! orthophoto accuracy)² + (matching σ · working pixel size)², the matching σ from the peak
//! ([`super::precision`]: `match_sigma_px` for a strong peak, more for a weak one), σ_z = the DTM's stated
//! accuracy or `mm_height_sigma_m`. The whole route of one recording — initial transform ([`super::register`]),
//! refinement with the parallax check against the window's neighbours (`nadir::refine`) and weak peaks kept
//! where the corrections agree ([`super::corroborate`]), control points — is
//! [`orthophoto_control`].

use super::corroborate::{corroborated, triangulated_references};
use super::dtm::Dtm;
use super::precision::{match_sigma_px, WeakPeakSigma};
use super::register::register_translation;
use super::OrthophotoParams;
use crate::campaign::orthophoto::RasterFile;
use crate::campaign::AerialKind;
use crate::correspondence::{AerialControlPoint, HeightSource, MapControl};
use crate::imaging::pyramid::{PyramidError, TileSource};
use crate::nadir::refine::{refine_in_image, NeighbourOrtho};
use crate::nadir::{
    AerialRefinement, InitialTransform, MmWindowMatch, OrthoImage, RecordingControl,
    TransformOutcome,
};
use serde::{Deserialize, Serialize};

/// Everything the orthophoto route found for one recording.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct OrthophotoControl {
    pub recording_id: String,
    /// The orthophoto tile used (as named in `campaign.toml`).
    pub orthophoto: String,
    pub transform: TransformOutcome,
    /// The tie points located in the orthophoto (empty when the transform was rejected).
    pub refinement: AerialRefinement,
    pub control: RecordingControl,
    /// Control points whose height came from the DTM / from the MM ground estimate.
    pub height_from_dtm: usize,
    pub height_from_mm: usize,
}

/// The orthophoto tile with its pixels and the accuracies that weight its control points.
pub struct OrthophotoInput<'a> {
    pub tile: &'a RasterFile,
    pub pixels: &'a dyn TileSource,
    /// Stated planimetric accuracy of the orthophoto, m.
    pub sigma_m: f64,
    /// The DTM and its stated height accuracy, m.
    pub dtm: Option<(&'a Dtm, f64)>,
}

/// The tie points of `window` located in the orthophoto: the refinement with its peak threshold lowered to
/// `corroborated_min_peak`, then the weak peaks kept only where the located corrections agree
/// ([`corroborated`]), then the refinement's `min_located` rule. Weak peaks dropped count as
/// `shift_inconsistent`.
fn refine_corroborated(
    ortho: &OrthoImage,
    photo: &OrthophotoInput,
    t: &InitialTransform,
    window: &MmWindowMatch,
    neighbours: &[NeighbourOrtho],
    p: &OrthophotoParams,
) -> Result<AerialRefinement, PyramidError> {
    let mut relaxed = p.refine.clone();
    relaxed.min_peak = p.corroborated_min_peak.min(p.refine.min_peak);
    relaxed.min_located = 1;
    let image = (photo.tile.file.as_str(), AerialKind::Nadir);
    let mut r = refine_in_image(ortho, photo.pixels, image, t, window, neighbours, &relaxed)?;
    let scale = r.matches.first().map_or(1.0, |m| (1u64 << m.level) as f64);
    let references = if p.corroborate_triangulated {
        triangulated_references(&r.matches, window, &ortho.georef, &t.ortho_to_aerial)
    } else {
        Vec::new()
    };
    let c = corroborated(
        std::mem::take(&mut r.matches),
        &references,
        p.refine.min_peak,
        p.corroboration_px,
        p.min_corroborating,
        scale,
    );
    r.misses.shift_inconsistent += c.weak_dropped;
    r.matches = c.kept;
    if r.matches.len() < p.refine.min_located {
        r.misses.unconfirmed = r.matches.len();
        r.matches.clear();
    }
    Ok(r)
}

/// The orthophoto route for the recording of `window`, whose ground ortho `ortho` was made north-up at the
/// orthophoto's working resolution; `neighbours` are the window's other recordings' orthos made the same way,
/// for the refinement's parallax check (`nadir::parallax_check`: a template whose structure a neighbour sees
/// differently shows content at another height than its corner, a kerb, and is not located). `Err` only when
/// the orthophoto cannot be read.
pub fn orthophoto_control(
    ortho: &OrthoImage,
    window: &MmWindowMatch,
    neighbours: &[NeighbourOrtho],
    photo: &OrthophotoInput,
    p: &OrthophotoParams,
) -> Result<OrthophotoControl, PyramidError> {
    let id = &window.recording_id;
    let file = &photo.tile.file;
    let transform = register_translation(
        ortho,
        id,
        photo.pixels,
        file,
        &photo.tile.header.transform,
        p,
    )?;
    let mut out = OrthophotoControl {
        recording_id: id.clone(),
        orthophoto: file.clone(),
        transform: transform.clone(),
        refinement: AerialRefinement::empty(id, file),
        control: RecordingControl {
            recording_id: id.clone(),
            points: Vec::new(),
        },
        height_from_dtm: 0,
        height_from_mm: 0,
    };
    let TransformOutcome::Accepted(t) = &transform else {
        return Ok(out);
    };
    out.refinement = refine_corroborated(ortho, photo, t, window, neighbours, p)?;
    let min_peak = p.refine.min_peak;
    let growth = WeakPeakSigma {
        min_peak,
        match_sigma_px: p.match_sigma_px,
        exponent: p.weak_sigma_exponent,
        correlated: p.weak_peaks_correlated,
    };
    let weak = out
        .refinement
        .matches
        .iter()
        .filter(|m| !(m.observation.score >= min_peak))
        .count();
    for m in &out.refinement.matches {
        let Some(k) = window
            .tie_points
            .iter()
            .position(|tp| tp.id == m.tie_point_id)
        else {
            continue;
        };
        let tp = &window.tie_points[k];
        let [x, y] = photo
            .tile
            .header
            .transform
            .pixel_to_world(m.observation.u_px, m.observation.v_px);
        let dtm_z = photo
            .dtm
            .and_then(|(d, s)| d.height_at(x, y).map(|z| (z, s)));
        let (z, sigma_z_m, height) = match dtm_z {
            Some((z, s)) => (z, s, HeightSource::Dtm),
            None => (
                tp.point_world[2],
                p.mm_height_sigma_m,
                HeightSource::MmGround,
            ),
        };
        match height {
            HeightSource::Dtm => out.height_from_dtm += 1,
            HeightSource::MmGround => out.height_from_mm += 1,
        }
        let sigma_px = match_sigma_px(m.observation.score, &growth, weak);
        let sigma_xy_m = photo.sigma_m.hypot(sigma_px * ortho.georef.gsd_m);
        let (vxy, vz) = (sigma_xy_m * sigma_xy_m, sigma_z_m * sigma_z_m);
        out.control.points.push(AerialControlPoint {
            tie_point_id: tp.id.clone(),
            mm: tp.observations.clone(),
            aerial: Vec::new(),
            point_world: Some([x, y, z]),
            covariance_m2: Some([[vxy, 0.0, 0.0], [0.0, vxy, 0.0], [0.0, 0.0, vz]]),
            map: Some(MapControl {
                orthophoto: file.clone(),
                u_px: m.observation.u_px,
                v_px: m.observation.v_px,
                score: m.observation.score,
                height,
            }),
            ray_ground: None,
        });
    }
    Ok(out)
}
