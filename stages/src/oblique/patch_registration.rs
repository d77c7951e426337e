//! Patch registration between one panorama (a triplet centre) and one oblique image (thesis 4.4.5–4.4.7):
//! for every thinned inlier of a façade plane that sees the oblique image, an MM patch (the fixed image) and an
//! oblique patch (the moving image) are built in the plane frame and the translation between them is found.
//!
//! Hierarchical (default, Table 4-1): a coarse level on larger patches (`coarse_extent_m`) sampled at
//! `coarse_spacing_factor` × the theoretical resolution searches the full ±`search_radius_m` (NCC exhaustively,
//! or MI by an integer scan + ES); the set's coarse shifts go through the 2-D median consensus (4.4.7: shifts
//! farther than `coarse_consensus_threshold_m` from the median are `rejected_coarse` and skip the fine level);
//! the fine level rebuilds the oblique patch around the coarse shift (`fine_extent_m`, theoretical resolution)
//! and refines within ±`fine_window_m` (MI by the (1+1)-ES from the coarse shift, or NCC). Non-hierarchical:
//! one level with the `fine` similarity on `single_extent_m` patches over ±`search_radius_m`; MI then scans the
//! integer shifts at `mi_scan_step_px` and refines the best by the ES within ± one step. A full-radius search
//! whose best shift lies on the border of the window found no peak (the similarity still grows outwards, e.g.
//! towards the next window bay of a periodic façade): the registration counts as `failed` (`search` module).
//!
//! Shift sign: a patch translation (dx, dy) px means the MM patch content at patch pixel x appears in the
//! oblique patch at x + (dx, dy); it converts to the plane shift (dx·s, −dy·s) along (`axis_u`, `axis_v`)
//! (`patch` module doc), the `PatchMatch::shift_plane_m` convention.
//!
//! Both images are read through their pyramids ([`inputs`]): the oblique image as one window at the level
//! whose resolution on the façade does not exceed `registration_resolution_m` (the theoretical resolution of
//! the patches is that level's), the panorama as the bands its patches sample. Measurements are in the
//! full-resolution images' pixels. Deterministic: every registration seeds its ES and MI sampling from `seed`,
//! the point id and the oblique image id; points run in parallel with an ordered collect.

pub mod inputs;
mod params;
pub mod search;

pub use params::{PatchParams, Similarity};

use crate::campaign::{AerialImage, Recording};
use crate::correspondence::PanoObservation;
use crate::estimators::median_consensus::median_consensus;
use crate::estimators::mix_seed;
use crate::estimators::one_plus_one::OnePlusOneParams;
use crate::geometry::frame::FrameCamera;
use crate::geometry::panorama::PanoramaCamera;
use crate::imaging::equirect::PanoramaLevels;
use crate::imaging::pyramid::{PyramidError, ScaledWindow, TileSource};
use crate::imaging::GrayImage;
use crate::oblique::patch::{
    fill_from_frame, fill_from_panorama, real_resolution_ratio, PatchGrid,
};
use crate::oblique::types::{
    FacadePlane, ObliqueView, PatchMatch, PatchRegistrationSet, PatchStats, SparseCloud,
    SparsePoint, TripletFacades,
};
use crate::params::StageId;
use crate::rng::stable_hash_parts;
use nalgebra::Vector3;
use rayon::prelude::*;
use search::{mi_search, ncc_search, Found};

/// The stage's identity in cache keys; bump the version whenever its output for the same inputs and parameters
/// changes.
pub const STAGE: StageId = StageId::new("patches", "8");

/// One patch centre offered to the registration.
struct Candidate<'a> {
    plane: &'a FacadePlane,
    view: &'a ObliqueView,
    point: Option<&'a SparsePoint>,
}

/// What the first level made of a candidate.
enum FirstLevel {
    /// The thinned index does not exist in the cloud, or the registration found nothing.
    Failed,
    Outside,
    LowResolution,
    Matched {
        shift_plane_m: [f64; 2],
        score: f64,
        ratio: f64,
    },
}

/// Everything the levels share.
struct Context<'a> {
    pano_cam: PanoramaCamera,
    pano: &'a PanoramaLevels,
    frame_cam: FrameCamera,
    oblique: &'a ScaledWindow,
    oblique_id: &'a str,
    p: &'a PatchParams,
}

impl Context<'_> {
    /// Grid spacing for a patch of `extent_m` at `spacing_m`, coarsened to respect `max_patch_px`.
    fn spacing(&self, extent_m: f64, spacing_m: f64) -> f64 {
        spacing_m.max(extent_m / self.p.max_patch_px as f64)
    }

    fn grid(
        &self,
        c: &Candidate,
        centre: [f64; 3],
        extent_m: f64,
        spacing_m: f64,
    ) -> Option<PatchGrid> {
        PatchGrid::new(
            centre,
            c.plane.axis_u_world,
            c.plane.axis_v_world,
            extent_m,
            self.spacing(extent_m, spacing_m),
        )
    }

    fn es(&self, spacing_m: f64, seed: u64) -> OnePlusOneParams {
        OnePlusOneParams {
            max_iterations: self.p.es_max_iterations,
            epsilon: self.p.es_epsilon_m / spacing_m,
            initial_radius: self.p.es_initial_radius_m / spacing_m,
            seed,
            ..OnePlusOneParams::default()
        }
    }

    fn seed(&self, point_id: &str, level: &str) -> u64 {
        mix_seed(
            self.p.seed,
            stable_hash_parts(&[point_id, self.oblique_id, level]),
        )
    }

    /// Both patches of `grid` (the oblique one on `grid` moved by `oblique_offset_m`), or `None` when either
    /// has too little data.
    fn patches(
        &self,
        grid: &PatchGrid,
        oblique_offset_m: [f64; 2],
    ) -> Option<(GrayImage, GrayImage)> {
        let fixed = fill_from_panorama(grid, &self.pano_cam, self.pano);
        let moving = fill_from_frame(
            &grid.shifted(oblique_offset_m),
            &self.frame_cam,
            self.oblique,
        );
        let fixed_valid =
            fixed.data.iter().filter(|v| v.is_finite()).count() as f64 / fixed.data.len() as f64;
        (fixed_valid >= self.p.min_valid_fraction
            && moving.valid_fraction() >= self.p.min_valid_fraction)
            .then_some((fixed, moving.image))
    }

    /// Full-radius search of one level with `similarity`; the shift in plane metres.
    fn search_full(
        &self,
        similarity: Similarity,
        grid: &PatchGrid,
        fixed: &GrayImage,
        moving: &GrayImage,
        seed: u64,
    ) -> Option<([f64; 2], f64)> {
        let radius_px = self.p.search_radius_m / grid.spacing_m;
        let found: Found = match similarity {
            Similarity::Ncc => ncc_search(
                fixed,
                moving,
                [0, 0],
                radius_px.ceil() as usize,
                self.min_overlap(grid),
            )?,
            Similarity::Mi => mi_search(
                fixed,
                moving,
                self.p.mi_bins,
                self.p.mi_samples,
                [0.0, 0.0],
                radius_px,
                (self.p.mi_scan_step_px > 0).then_some(self.p.mi_scan_step_px),
                &self.es(grid.spacing_m, seed),
            )
            .ok()?
            .into(),
        };
        Some((grid.shift_px_to_plane_m(found.shift_px), found.score))
    }

    fn min_overlap(&self, grid: &PatchGrid) -> usize {
        ((grid.size_px * grid.size_px) as f64 * self.p.min_valid_fraction * 0.5) as usize
    }

    /// The first level (coarse, or the single level): resolution and coverage checks, then the search.
    fn first_level(&self, c: &Candidate) -> FirstLevel {
        let Some(point) = c.point else {
            return FirstLevel::Failed;
        };
        let p = self.p;
        let centre = point.tie.point_world;
        // The theoretical resolution at the level the oblique image is read at.
        let s = c.view.resolution_m * self.oblique.scale();
        // thesis 4.4.5: the real-resolution ratio at the theoretical resolution, on the final level's extent.
        let ratio_extent = if p.hierarchical {
            p.fine_extent_m
        } else {
            p.single_extent_m
        };
        let Some(ratio_grid) = self.grid(c, centre, ratio_extent, s) else {
            return FirstLevel::Outside;
        };
        let (ratio, inside) = real_resolution_ratio(&ratio_grid, &self.frame_cam, self.oblique);
        if inside < p.min_valid_fraction {
            return FirstLevel::Outside;
        }
        if ratio < p.min_real_resolution_ratio {
            return FirstLevel::LowResolution;
        }
        let (extent, spacing, similarity) = if p.hierarchical {
            (p.coarse_extent_m, s * p.coarse_spacing_factor, p.coarse)
        } else {
            (p.single_extent_m, s, p.fine)
        };
        let Some(grid) = self.grid(c, centre, extent, spacing) else {
            return FirstLevel::Outside;
        };
        let Some((fixed, moving)) = self.patches(&grid, [0.0, 0.0]) else {
            return FirstLevel::Outside;
        };
        match self.search_full(
            similarity,
            &grid,
            &fixed,
            &moving,
            self.seed(&point.tie.id, "first"),
        ) {
            Some((shift_plane_m, score)) => FirstLevel::Matched {
                shift_plane_m,
                score,
                ratio,
            },
            None => FirstLevel::Failed,
        }
    }

    /// The fine level around the coarse shift: the final shift (plane metres) and score.
    fn fine_level(
        &self,
        c: &Candidate,
        point: &SparsePoint,
        coarse_m: [f64; 2],
    ) -> Option<([f64; 2], f64)> {
        let p = self.p;
        let grid = self.grid(
            c,
            point.tie.point_world,
            p.fine_extent_m,
            c.view.resolution_m * self.oblique.scale(),
        )?;
        let (fixed, moving) = self.patches(&grid, coarse_m)?;
        let window_px = p.fine_window_m / grid.spacing_m;
        let found: Found = match p.fine {
            Similarity::Mi => mi_search(
                &fixed,
                &moving,
                p.mi_bins,
                p.mi_samples,
                [0.0, 0.0],
                window_px,
                None,
                &self.es(grid.spacing_m, self.seed(&point.tie.id, "fine")),
            )
            .ok()?
            .into(),
            Similarity::Ncc => ncc_search(
                &fixed,
                &moving,
                [0, 0],
                window_px.ceil() as usize,
                self.min_overlap(&grid),
            )?,
        };
        let fine_m = grid.shift_px_to_plane_m(found.shift_px);
        Some((
            [coarse_m[0] + fine_m[0], coarse_m[1] + fine_m[1]],
            found.score,
        ))
    }

    /// The centre panorama's observation of the point: from the tie point, else projected.
    fn mm_observation(&self, point: &SparsePoint, recording_id: &str) -> Option<PanoObservation> {
        if let Some(o) = point
            .tie
            .observations
            .iter()
            .find(|o| o.image_id == recording_id)
        {
            return Some(o.clone());
        }
        let (u, v) = self
            .pano_cam
            .project_world(&Vector3::from(point.tie.point_world))?;
        Some(PanoObservation {
            image_id: recording_id.to_string(),
            u_px: u,
            v_px: v,
        })
    }
}

/// Register every thinned façade point of `facades` whose plane sees `oblique` against the panorama `pano` of
/// `recording` (the triplet centre), both read through their pyramids ([`inputs`]). See the module doc for
/// the levels; every candidate ends in exactly one of the `PatchStats` counters (`matches` includes
/// `rejected_coarse`). `Err` only when an image cannot be read.
pub fn register_patches(
    recording: &Recording,
    pano: &dyn TileSource,
    oblique: &AerialImage,
    oblique_img: &dyn TileSource,
    cloud: &SparseCloud,
    facades: &TripletFacades,
    p: &PatchParams,
) -> Result<PatchRegistrationSet, PyramidError> {
    let candidates = candidates(facades, cloud, &oblique.image_id);
    let frame_cam = FrameCamera::from_aerial(oblique);
    let pano_layout = pano.layout();
    let pano_cam = PanoramaCamera::from_recording(
        recording,
        pano_layout.width as u32,
        pano_layout.height as u32,
    );
    let points: Vec<inputs::PointInPlane> = candidates
        .iter()
        .filter_map(|c| {
            Some(inputs::PointInPlane {
                plane: c.plane,
                view: c.view,
                point: c.point?,
            })
        })
        .collect();
    let level = inputs::oblique_level(&points, p, oblique_img.layout());
    let window = inputs::oblique_window(oblique_img, &frame_cam, &points, p, level)?;
    let Some(window) = window else {
        let mut stats = PatchStats {
            candidates: candidates.len(),
            ..PatchStats::default()
        };
        stats.rejected_outside = candidates.len();
        return Ok(PatchRegistrationSet {
            recording: recording.image_id.clone(),
            oblique_image_id: oblique.image_id.clone(),
            matches: Vec::new(),
            stats,
        });
    };
    let bands = inputs::panorama_bands(pano, &pano_cam, &points, p, window.scale())?;
    let ctx = Context {
        pano_cam,
        pano: &bands,
        frame_cam,
        oblique: &window,
        oblique_id: &oblique.image_id,
        p,
    };
    Ok(register_with(&ctx, recording, oblique, &candidates))
}

/// The thinned points of the planes that see oblique image `oblique_id`, plane by plane.
fn candidates<'a>(
    facades: &'a TripletFacades,
    cloud: &'a SparseCloud,
    oblique_id: &str,
) -> Vec<Candidate<'a>> {
    facades
        .planes
        .iter()
        .filter_map(|plane| {
            plane
                .views
                .iter()
                .find(|v| v.image_id == oblique_id)
                .map(|view| (plane, view))
        })
        .flat_map(|(plane, view)| {
            plane.thinned.iter().map(move |&i| Candidate {
                plane,
                view,
                point: cloud.points.get(i),
            })
        })
        .collect()
}

/// The registration of `candidates` once the images are read.
fn register_with(
    ctx: &Context,
    recording: &Recording,
    oblique: &AerialImage,
    candidates: &[Candidate],
) -> PatchRegistrationSet {
    let p = ctx.p;
    let mut stats = PatchStats {
        candidates: candidates.len(),
        ..PatchStats::default()
    };
    let degenerate = ctx.oblique.image.width == 0 || ctx.oblique.image.height == 0;
    let first: Vec<FirstLevel> = if degenerate {
        candidates.iter().map(|_| FirstLevel::Outside).collect()
    } else {
        candidates.par_iter().map(|c| ctx.first_level(c)).collect()
    };
    // thesis 4.4.7, 2-D case: median consensus over the set's coarse shifts.
    let matched_idx: Vec<usize> = (0..first.len())
        .filter(|&k| matches!(first[k], FirstLevel::Matched { .. }))
        .collect();
    let mut rejected = vec![false; first.len()];
    if p.hierarchical {
        let shifts: Vec<[f64; 2]> = matched_idx
            .iter()
            .map(|&k| match first[k] {
                FirstLevel::Matched { shift_plane_m, .. } => shift_plane_m,
                _ => unreachable!("filtered to Matched above"),
            })
            .collect();
        if let Some(consensus) = median_consensus(&shifts, p.coarse_consensus_threshold_m) {
            for (j, &k) in matched_idx.iter().enumerate() {
                rejected[k] = !consensus.inliers[j];
            }
        }
    }
    let results: Vec<Option<PatchMatch>> = (0..candidates.len())
        .into_par_iter()
        .map(|k| {
            let FirstLevel::Matched {
                shift_plane_m: first_m,
                score: first_score,
                ratio,
            } = first[k]
            else {
                return None;
            };
            let c = &candidates[k];
            let point = c.point?;
            let (shift, score, coarse) = if !p.hierarchical {
                (first_m, first_score, None)
            } else if rejected[k] {
                (first_m, first_score, Some(first_m))
            } else {
                let (s, sc) = ctx.fine_level(c, point, first_m)?;
                (s, sc, Some(first_m))
            };
            let axis_u = Vector3::from(c.plane.axis_u_world);
            let axis_v = Vector3::from(c.plane.axis_v_world);
            let matched =
                Vector3::from(point.tie.point_world) + axis_u * shift[0] + axis_v * shift[1];
            let (ou, ov) = ctx.frame_cam.project_world(&matched)?;
            Some(PatchMatch {
                point_id: point.tie.id.clone(),
                side: c.plane.side,
                object_point_world: point.tie.point_world,
                mm: ctx.mm_observation(point, &recording.image_id)?,
                oblique_image_id: oblique.image_id.clone(),
                shift_plane_m: shift,
                coarse_shift_plane_m: coarse,
                matched_point_world: [matched.x, matched.y, matched.z],
                oblique_px: [ou, ov],
                score,
                real_resolution_ratio: ratio,
                rejected_coarse: rejected[k],
                level: ctx.oblique.level,
            })
        })
        .collect();
    let mut matches = Vec::new();
    for (k, r) in results.into_iter().enumerate() {
        match (&first[k], r) {
            (FirstLevel::Outside, _) => stats.rejected_outside += 1,
            (FirstLevel::LowResolution, _) => stats.rejected_resolution += 1,
            (FirstLevel::Failed, _) | (FirstLevel::Matched { .. }, None) => stats.failed += 1,
            (FirstLevel::Matched { .. }, Some(m)) => {
                stats.rejected_coarse += usize::from(m.rejected_coarse);
                matches.push(m);
            }
        }
    }
    stats.matches = matches.len();
    PatchRegistrationSet {
        recording: recording.image_id.clone(),
        oblique_image_id: oblique.image_id.clone(),
        matches,
        stats,
    }
}
