//! Accurate registration of MM corner points in one aerial nadir image by phase correlation (thesis 3.4.5.3).
//!
//! Input: the MM tie points of one recording window (their corners on the detecting recording's ground plane),
//! that recording's MM ortho image at about the aerial GSD, and the initial similarity `ortho px → aerial px`
//! of thesis 3.4.5.2. For every tie point:
//! 1. ground point → MM ortho pixel (`OrthoGeoref::world_to_pixel`) → predicted aerial pixel (the transform);
//! 2. MM template: `template_px²` ortho pixels around the corner; skipped if it leaves the ortho image, touches a
//!    pixel masked by the vehicle, or is nearly flat (phase correlation of a flat patch is noise) — unless a
//!    template moved off centre by up to `template_offset_px` is usable (the corner stays inside it);
//!    It is also compared with the neighbouring recordings' views of the same corner (`parallax_check`): a
//!    template showing content at another height than the corner (a kerb) is left out;
//! 3. aerial window: the aerial image is **resampled onto the MM ortho grid** (bicubic, through the transform)
//!    over the template region enlarged by `search_margin_px` on every side. Resampling the aerial side keeps the
//!    MM template exactly as ortho-projected, and both images then share orientation and pixel size, so only a
//!    translation is left (the thesis: "only the translation elements are identified");
//! 4. phase correlation on the normalised cross-power spectrum (windowed, eq. 3/1) → integer peak → sub-pixel
//!    peak by a second-order fit (`matching::phase_correlation::locate_template`); then once more with the aerial
//!    window re-sampled around the content found, so the final estimate is a near-zero shift (the tapers bias
//!    large shifts by up to ~0.1 px);
//! 5. weak peaks (below `min_peak`) and shifts beyond the margin are rejected; the corner, moved by the found
//!    shift on the ortho grid, is mapped by the transform to an observation in ORIGINAL aerial pixel coordinates.
//!
//! Then, per aerial image: the tie points' corrections (observed − predicted) must agree within
//! `max_shift_spread_px` of their median (a periodic template that locked onto the neighbouring zebra stripe
//! stands out here; see [`RefineParams::max_shift_spread_px`]), and fewer than `min_located` located tie points
//! keep none.
//!
//! Optional checks (off by the stage default): the **tie-point consistency** (`point_sigma_px`; on in
//! `default.toml`) drops a corner whose aerial location minus its tie point's MM object point departs from the
//! image's median of that difference by more than `point_k_sigma` σ (`consistent_residuals`); the **view
//! check** (`view_sigma_px`) locates the corner again with re-centred templates and the neighbouring recordings'
//! templates and drops a location that one of them contradicts.

use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use super::aerial_patch::AerialWindow;
use super::ortho::OrthoImage;
use super::parallax_check::{parallax_share, ParallaxScratch};
use super::registration::{AerialMatch, AerialRefinement, InitialTransform, MmWindowMatch};
use crate::campaign::{AerialImage, AerialKind};
use crate::correspondence::AerialObservation;
use crate::estimators::median_consensus::{median_consensus, median_in_place};
use crate::geometry::Similarity2;
use crate::imaging::border::Border;
use crate::imaging::pyramid::{PyramidError, TileSource};
use crate::imaging::sample::sample_bicubic;
use crate::imaging::window::WindowKind;
use crate::imaging::GrayImage;
use crate::matching::phase_correlation::{locate_template, PhaseCorrelationParams};
use crate::matching::subpixel::PeakFit;
use crate::params::{Params, StageId};
use nalgebra::{Vector2, Vector3};

/// The stage's identity in cache keys; bump the version whenever its output for the same inputs and parameters
/// changes.
pub const STAGE: StageId = StageId::new("refine", "12");

/// Taper applied before the Fourier transform (serialisable mirror of [`WindowKind`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum TaperWindow {
    Hann,
    Blackman,
    Rectangular,
}

impl TaperWindow {
    pub fn kind(self) -> WindowKind {
        match self {
            TaperWindow::Hann => WindowKind::Hann,
            TaperWindow::Blackman => WindowKind::Blackman,
            TaperWindow::Rectangular => WindowKind::Rectangular,
        }
    }
}

crate::params! {
    /// Parameters of [`refine_in_aerial`]; lengths in MM ortho pixels (≈ aerial pixels).
    pub struct RefineParams {
        /// Side of the square MM template (FFT-friendly sizes are fastest).
        template_px: usize = 32, unit "px", min 8, max 256;
        /// The aerial window extends the template by this much on each side: the largest correction of the
        /// initial transform that can be found (larger shifts are rejected).
        search_margin_px: usize = 12, unit "px", min 1, max 128;
        /// Taper of template and window before the FFT.
        window: TaperWindow = TaperWindow::Hann;
        /// σ of the Gaussian low-pass on the cross-power spectrum; 0 = none.
        lowpass_sigma_px: f64 = 1.5, unit "px", min 0.0, max 10.0;
        /// Re-estimations with the window re-centred on the content found (removes the fixed-window bias).
        refinements: usize = 3, max 10;
        /// Smallest accepted correlation peak (1 = identical images).
        min_peak: f64 = 0.75, min 0.0, below 1.0;
        /// Smallest standard deviation of the template grey values (0..1 scale); flatter templates are skipped.
        min_template_std: f64 = 0.01, min 0.0;
        /// When the template centred on the corner touches a pixel masked by the vehicle or leaves the ortho
        /// image, it may be moved off centre by up to this much per axis (at most a quarter of `template_px`;
        /// nearest usable position first) so that it lies on valid pixels; the corner stays inside it and
        /// moves with the shift found. Corners next to the vehicle (lane lines beside the car) are then located
        /// instead of skipped. 0 = centred only (the thesis).
        template_offset_px: usize = 0, unit "px", max 128;
        /// Parallax check (`nadir::parallax_check`): a corner is not located when a neighbouring recording that
        /// saw it shows more than this share of the template's structure differently. 1 = no check.
        max_parallax_share: f64 = 0.25, min 0.0, max 1.0;
        /// Fewest tie points that must be located in one aerial image for any of them to be kept (1 = keep lone
        /// ones).
        min_located: usize = 2, min 1, max 100;
        /// Shift consistency within one aerial image: a tie point whose correction differs from the median of
        /// the image's corrections by more than this is dropped (with two located, both are dropped when they
        /// differ by more); 0 = no check.
        max_shift_spread_px: f64 = 5.0, unit "px", min 0.0;
        /// View check: σ of one phase-correlation location (working-level px). The corner is located again
        /// with the template re-centred a quarter off in four directions and from each neighbouring
        /// recording's view of it; two locations of one corner differ by √2·σ per axis, and a location that
        /// another template contradicts by more than `view_k_sigma` of that is dropped. 0 = no check.
        view_sigma_px: f64 = 0.0, unit "px", min 0.0, max 10.0;
        /// Rejection bound of the view check in standard deviations of the 2-D disagreement (√χ²₂: 2.45 keeps
        /// 95 %, 3.03 keeps 99 % of correct locations).
        view_k_sigma: f64 = 3.03, min 1.0, max 100.0;
        /// Tie-point consistency (working-level px; 0 = no check): σ of one located corner. The corner located
        /// in the aerial image and the tie point's MM object point (triangulated from all its panoramas) must
        /// differ by the same offset for every tie point of the recording in the image — the recording's
        /// position error; a tie point whose difference departs from the image's median by more than
        /// `point_k_sigma` σ is dropped (with two located, both when they differ by more than √2 times that).
        /// The aerial tables' default `sigma_px` is 0.5.
        point_sigma_px: f64 = 0.0, unit "px", min 0.0, max 10.0;
        /// Rejection bound of the tie-point consistency in σ (√χ²₂: 2.45 keeps 95 % of correct corners).
        point_k_sigma: f64 = 2.45, min 1.0, max 100.0;
        /// Tie-point consistency with σ measured per aerial image: σ is the larger of `point_sigma_px` and the
        /// robust spread of the image's differences about their median (median distance / √(2 ln 2), the
        /// Rayleigh median); with fewer than three located corners there is no spread to measure and all are
        /// kept. Errors that do not shift every corner alike — a heading error, tie points triangulated from
        /// drifting neighbours, unknown lens distortion — widen the spread of correct corners, and the bound
        /// follows them instead of dropping them.
        point_sigma_estimated: bool = false;
    }
}

impl RefineParams {
    fn phase_params(&self) -> PhaseCorrelationParams {
        PhaseCorrelationParams {
            window: self.window.kind(),
            lowpass_sigma_px: self.lowpass_sigma_px,
            peak_fit: PeakFit::LogQuadratic,
            refinements: self.refinements,
        }
    }
}

/// Cut the `size × size` ortho template whose top-left pixel is (x0, y0) into `out`; `false` if it leaves the
/// ortho image or touches a masked pixel.
pub fn cut_ortho_template(
    ortho: &OrthoImage,
    x0: isize,
    y0: isize,
    size: usize,
    out: &mut GrayImage,
) -> bool {
    let (w, h) = (ortho.image.width as isize, ortho.image.height as isize);
    if x0 < 0 || y0 < 0 || x0 + size as isize > w || y0 + size as isize > h {
        return false;
    }
    out.width = size;
    out.height = size;
    out.data.clear();
    for row in y0 as usize..y0 as usize + size {
        let start = row * ortho.image.width + x0 as usize;
        if ortho.valid[start..start + size].contains(&0) {
            return false;
        }
        out.data
            .extend_from_slice(&ortho.image.data[start..start + size]);
    }
    true
}

/// Fill `out` (`width × height`) with `aerial` sampled (bicubic) on the ortho grid: pixel (c, r) takes the
/// aerial value at `ortho_to_aerial(x0 + c + 0.5, y0 + r + 0.5)`. `false` if any sample falls closer than 2 px
/// to the aerial image border (the window would be partly invented).
pub fn sample_aerial_on_ortho_grid(
    aerial: &GrayImage,
    ortho_to_aerial: &Similarity2,
    x0: f64,
    y0: f64,
    width: usize,
    height: usize,
    out: &mut GrayImage,
) -> bool {
    let (a, b) = ortho_to_aerial.ab();
    let map = |x: f64, y: f64| {
        (
            a * x - b * y + ortho_to_aerial.tx,
            b * x + a * y + ortho_to_aerial.ty,
        )
    };
    let (aw, ah) = (aerial.width as f64, aerial.height as f64);
    // The map is affine: the window is inside when its four corners are.
    for (cx, cy) in [
        (x0, y0),
        (x0 + width as f64, y0),
        (x0, y0 + height as f64),
        (x0 + width as f64, y0 + height as f64),
    ] {
        let (u, v) = map(cx, cy);
        if !(u >= 2.0 && v >= 2.0 && u <= aw - 2.0 && v <= ah - 2.0) {
            return false;
        }
    }
    out.width = width;
    out.height = height;
    out.data.clear();
    for r in 0..height {
        let y = y0 + r as f64 + 0.5;
        for c in 0..width {
            let (u, v) = map(x0 + c as f64 + 0.5, y);
            out.data.push(sample_bicubic(aerial, u, v, Border::Reflect));
        }
    }
    true
}

/// Standard deviation of the grey values of `img`.
pub fn grey_std(img: &GrayImage) -> f64 {
    img.mean_std().1
}

/// Reusable per-thread buffers of one tie point's matching.
struct Buffers {
    template: GrayImage,
    /// A neighbouring recording's template of the same corner (view check).
    view: GrayImage,
    search: GrayImage,
    parallax: ParallaxScratch,
}

fn new_buffers() -> Buffers {
    Buffers {
        template: GrayImage::filled(0, 0, 0.0),
        view: GrayImage::filled(0, 0, 0.0),
        search: GrayImage::filled(0, 0, 0.0),
        parallax: ParallaxScratch::default(),
    }
}

/// What happened to one tie point.
enum Outcome {
    /// Predicted outside the aerial image: not tried.
    Outside,
    /// Tried but not located: why.
    NotLocated(Miss),
    /// Tried, but left out before phase correlation: a neighbouring view shows the template's structure
    /// differently (parallax check).
    Parallax,
    /// Located, but a neighbouring recording's view of the corner lands elsewhere (view check).
    ViewInconsistent,
    Located(AerialMatch),
}

/// Why a tried tie point was not located in the aerial image.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Miss {
    /// The template leaves the ortho image, touches a masked pixel or is nearly flat.
    Template,
    /// The search window leaves the aerial image.
    Window,
    /// The content found lies beyond the search margin.
    Margin,
    /// The correlation peak is below `min_peak`.
    Peak,
}

/// Cut the template around the corner at ortho pixel (`u_o`, `v_o`) into `buf.template` (step 2 of the module
/// documentation); its top-left pixel, or nothing when the template is unusable at every offset of `offsets`
/// ([`template_offsets`]) from the centred position (it leaves the ortho image, touches a masked pixel or is
/// nearly flat). Offsets are tried in order, so the result is the centred template whenever that one is usable.
fn cut_template(
    ortho: &OrthoImage,
    (u_o, v_o): (f64, f64),
    offsets: &[(isize, isize)],
    p: &RefineParams,
    buf: &mut Buffers,
) -> Option<(f64, f64)> {
    let half = p.template_px as f64 / 2.0;
    let x0 = (u_o - half).round() as isize;
    let y0 = (v_o - half).round() as isize;
    offsets.iter().find_map(|&(ox, oy)| {
        let (x, y) = (x0 + ox, y0 + oy);
        (cut_ortho_template(ortho, x, y, p.template_px, &mut buf.template)
            && grey_std(&buf.template) >= p.min_template_std)
            .then_some((x as f64, y as f64))
    })
}

/// Template offsets (x, y) of `p.template_offset_px` at most per axis (and at most a quarter of the template, so
/// the corner stays well inside the taper), nearest first (by Chebyshev ring, then Euclidean distance, then a fixed order), in
/// steps of a quarter of that reach (at least 1 px); (0, 0) first.
fn template_offsets(p: &RefineParams) -> Vec<(isize, isize)> {
    let reach = p.template_offset_px.min(p.template_px / 4) as isize;
    let step = (reach / 4).max(1);
    let mut offsets: Vec<(isize, isize)> = (-reach..=reach)
        .step_by(step as usize)
        .flat_map(|ox| {
            (-reach..=reach)
                .step_by(step as usize)
                .map(move |oy| (ox, oy))
        })
        .collect();
    if !offsets.contains(&(0, 0)) {
        offsets.push((0, 0));
    }
    offsets.sort_by_key(|&(ox, oy)| (ox.abs().max(oy.abs()), ox * ox + oy * oy, oy, ox));
    offsets
}

/// Phase-correlation location of `template`, whose top-left pixel lies at (`x0`, `y0`) on the ortho grid
/// (continuous), in `aerial`, which `tf` maps from ortho pixels (steps 3–5); `search` is scratch. Returns the
/// shift of the template centre (ortho px) and the peak, or why not: the window leaves the aerial image, the
/// shift exceeds the margin or the peak is weak.
fn search_template(
    aerial: &GrayImage,
    tf: &Similarity2,
    template: &GrayImage,
    (x0, y0): (f64, f64),
    p: &RefineParams,
    phase: &PhaseCorrelationParams,
    search: &mut GrayImage,
) -> Result<(f64, f64, f64), Miss> {
    let half = p.template_px as f64 / 2.0;
    let margin = p.search_margin_px as f64;
    let side = p.template_px + 2 * p.search_margin_px;
    // Pass 1 searches around the prediction; pass 2 re-samples the aerial window centred on the content found
    // (sub-pixel), so the final estimate is a near-zero shift, where phase correlation is least biased by the
    // tapers.
    let (mut dx, mut dy, mut peak) = (0.0f64, 0.0f64, 0.0f64);
    for _pass in 0..2 {
        if !sample_aerial_on_ortho_grid(
            aerial,
            tf,
            x0 - margin + dx,
            y0 - margin + dy,
            side,
            side,
            search,
        ) {
            return Err(Miss::Window);
        }
        let loc = locate_template(template, search, phase).map_err(|_| Miss::Peak)?;
        // Template centre in ortho-grid coordinates, and where it was found.
        let step_x = (x0 - margin + dx + loc.u_px) - (x0 + half) - dx;
        let step_y = (y0 - margin + dy + loc.v_px) - (y0 + half) - dy;
        dx += step_x;
        dy += step_y;
        peak = loc.peak;
        if !(dx.abs() <= margin && dy.abs() <= margin) {
            return Err(Miss::Margin);
        }
        if step_x.hypot(step_y) < 0.02 {
            break;
        }
    }
    if peak >= p.min_peak {
        Ok((dx, dy, peak))
    } else {
        Err(Miss::Peak)
    }
}

/// The neighbour among `neighbours` that saw the corner of `view`, with that view's pixel in its ortho image.
fn neighbour_view<'n, 'a>(
    neighbours: &'n [NeighbourOrtho<'a>],
    view: &super::registration::ViewGround,
) -> Option<(&'n NeighbourOrtho<'a>, (f64, f64))> {
    let nb = neighbours
        .iter()
        .find(|n| n.recording_id == view.recording_id)?;
    let g = view.ground_world;
    let px = nb
        .ortho
        .georef
        .world_to_pixel(&Vector3::new(g[0], g[1], g[2]));
    Some((nb, px))
}

/// A neighbouring recording's ortho image for the same aerial image (same GSD and orientation as the
/// detecting recording's), for the parallax check.
pub struct NeighbourOrtho<'a> {
    pub recording_id: &'a str,
    pub ortho: &'a OrthoImage,
}

impl<'a> NeighbourOrtho<'a> {
    /// The neighbours of `window` with their orthos, given in the window's neighbour order (`window.pairs`).
    pub fn of_window<O: std::ops::Deref<Target = OrthoImage>>(
        window: &'a MmWindowMatch,
        orthos: &'a [O],
    ) -> Vec<Self> {
        window
            .pairs
            .iter()
            .zip(orthos)
            .map(|(pair, o)| NeighbourOrtho {
                recording_id: &pair.to_id,
                ortho: o,
            })
            .collect()
    }
}

/// Locate every tie point of `window` in one aerial nadir image by phase correlation (thesis 3.4.5.3).
///
/// `mm_ortho` must be the ortho image of the window's detecting recording (`window.recording_id`) at about the
/// aerial GSD (at the working level, `aerial_patch::working_level`); `t.ortho_to_aerial` maps its pixels to
/// full `aerial` pixels. The aerial image is read once, as the window of that level around the ortho's
/// footprint ([`AerialWindow`]). Matches keep the order of `window.tie_points`; the result is identical for
/// any thread count. An invalid transform (non-finite or zero scale) yields an empty refinement; `Err` only
/// when the image cannot be read.
///
/// **Parallax check** (`max_parallax_share` < 1, `nadir::parallax_check`): before a tie point is located, its
/// template is compared with each neighbouring recording in `neighbours` that saw the corner
/// (`window.neighbour_ground_world`); when any of them shows more than `max_parallax_share` of the template's
/// structure differently, the tie point is not located in this image (counted in `parallax_rejected`).
/// Neighbours without an ortho image here, or whose view of the template is mostly masked, give no verdict.
pub fn refine_in_aerial(
    mm_ortho: &OrthoImage,
    aerial: &dyn TileSource,
    aerial_row: &AerialImage,
    t: &InitialTransform,
    window: &MmWindowMatch,
    neighbours: &[NeighbourOrtho],
    p: &RefineParams,
) -> Result<AerialRefinement, PyramidError> {
    refine_in_image(
        mm_ortho,
        aerial,
        (&aerial_row.image_id, AerialKind::Nadir),
        t,
        window,
        neighbours,
        p,
    )
}

/// [`refine_in_aerial`] in any nadir raster that `t.ortho_to_aerial` maps the ortho into (an aerial frame or
/// an orthophoto); the observations carry `image` = (image id, kind).
pub fn refine_in_image(
    mm_ortho: &OrthoImage,
    aerial: &dyn TileSource,
    image: (&str, AerialKind),
    t: &InitialTransform,
    window: &MmWindowMatch,
    neighbours: &[NeighbourOrtho],
    p: &RefineParams,
) -> Result<AerialRefinement, PyramidError> {
    let (image_id, kind) = image;
    let mut result = AerialRefinement::empty(&t.recording_id, image_id);
    let tf = t.ortho_to_aerial;
    if !tf.is_usable() || p.validate().is_err() {
        return Ok(result);
    }
    // Search windows reach the template ± the margin, re-centred once by up to the margin (`search_template`),
    // plus the bicubic kernel's reach.
    let margin = 2.0 * p.search_margin_px as f64 + 4.0;
    let size = (mm_ortho.image.width, mm_ortho.image.height);
    let Some(aerial_window) = AerialWindow::read(aerial, size, &tf, margin)? else {
        return Ok(result);
    };
    let aerial_img = &aerial_window.window.image;
    let tf_window = aerial_window.ortho_to_window;
    let phase = p.phase_params();
    let offsets = template_offsets(p);
    let n = window.tie_points.len().min(window.ground_world.len());
    let outcomes: Vec<Outcome> = (0..n)
        .into_par_iter()
        .map_init(new_buffers, |buf, i| {
            let g = window.ground_world[i];
            let Some(((u_o, v_o), predicted)) = aerial_window.predict(&mm_ortho.georef, &tf, g)
            else {
                return Outcome::Outside;
            };
            let Some(corner) = cut_template(mm_ortho, (u_o, v_o), &offsets, p, buf) else {
                return Outcome::NotLocated(Miss::Template);
            };
            if p.max_parallax_share < 1.0 {
                let views = window.neighbour_ground_world.get(i).map_or(&[][..], |v| v);
                for view in views {
                    let Some((nb, (u_n, v_n))) = neighbour_view(neighbours, view) else {
                        continue;
                    };
                    // The template's top-left corner, placed relative to the corner as the neighbour saw it.
                    let (nx0, ny0) = (u_n - (u_o - corner.0), v_n - (v_o - corner.1));
                    if parallax_share(&buf.template, nb.ortho, nx0, ny0, &mut buf.parallax)
                        .is_some_and(|share| share > p.max_parallax_share)
                    {
                        return Outcome::Parallax;
                    }
                }
            }
            let found = search_template(
                aerial_img,
                &tf_window,
                &buf.template,
                corner,
                p,
                &phase,
                &mut buf.search,
            );
            let (dx, dy, peak) = match found {
                Ok(f) => f,
                Err(miss) => return Outcome::NotLocated(miss),
            };
            let views = window.neighbour_ground_world.get(i).map_or(&[][..], |v| v);
            let disagreement = (p.view_sigma_px > 0.0)
                .then(|| {
                    let found = ViewLocation {
                        corner_ortho_px: (u_o, v_o),
                        template_origin: corner,
                        shift_px: (dx, dy),
                    };
                    view_disagreement_px(
                        &found, views, mm_ortho, neighbours, aerial_img, &tf_window, p, &phase, buf,
                    )
                })
                .flatten();
            if disagreement.is_some_and(|d| d > view_bound_px(p)) {
                return Outcome::ViewInconsistent;
            }
            let observed = tf.apply(&Vector2::new(u_o + dx, v_o + dy));
            Outcome::Located(AerialMatch {
                tie_point_id: window.tie_points[i].id.clone(),
                observation: AerialObservation {
                    image_id: image_id.to_string(),
                    kind,
                    u_px: observed.x,
                    v_px: observed.y,
                    score: peak,
                    sigma_px: None,
                },
                predicted_u_px: predicted.x,
                predicted_v_px: predicted.y,
                level: aerial_window.window.level,
                view_disagreement_px: disagreement,
            })
        })
        .collect();
    for o in outcomes {
        match o {
            Outcome::Outside => {}
            Outcome::NotLocated(miss) => {
                result.tried += 1;
                match miss {
                    Miss::Template => result.misses.unusable_templates += 1,
                    Miss::Window | Miss::Margin => result.misses.beyond_search += 1,
                    Miss::Peak => result.misses.weak_peaks += 1,
                }
            }
            Outcome::Parallax => {
                result.tried += 1;
                result.misses.parallax_rejected += 1;
            }
            Outcome::ViewInconsistent => {
                result.tried += 1;
                result.misses.view_inconsistent += 1;
            }
            Outcome::Located(m) => {
                result.tried += 1;
                result.matches.push(m);
            }
        }
    }
    if p.point_sigma_px > 0.0 {
        let before = result.matches.len();
        let residuals = point_residuals_px(&result.matches, window, mm_ortho, &tf);
        // σ in working pixels; the residuals are in full-resolution pixels.
        let floor_px = p.point_sigma_px * aerial_window.window.scale();
        // With σ measured, fewer than three corners have no spread to measure: they are kept, as a lone one is.
        let sigma_px = if p.point_sigma_estimated {
            robust_spread_px(&residuals).map(|s| s.max(floor_px))
        } else {
            Some(floor_px)
        };
        if let Some(sigma_px) = sigma_px {
            let bound_px = p.point_k_sigma * sigma_px;
            result.matches =
                consistent_residuals(std::mem::take(&mut result.matches), &residuals, bound_px);
        }
        result.misses.point_inconsistent = before - result.matches.len();
    }
    if p.max_shift_spread_px > 0.0 {
        let before = result.matches.len();
        // The spread is in working pixels; corrections are in full-resolution pixels.
        let spread_px = p.max_shift_spread_px * aerial_window.window.scale();
        result.matches = consistent_shifts(std::mem::take(&mut result.matches), spread_px);
        result.misses.shift_inconsistent = before - result.matches.len();
    }
    if result.matches.len() < p.min_located {
        result.misses.unconfirmed = result.matches.len();
        result.matches.clear();
    }
    Ok(result)
}

/// Where the detecting recording's template found a corner: the corner on the ortho grid, the template's
/// top-left pixel and the shift of the template found in the aerial window (ortho px).
struct ViewLocation {
    corner_ortho_px: (f64, f64),
    template_origin: (f64, f64),
    shift_px: (f64, f64),
}

/// The largest disagreement (ortho px ≈ working-level aerial px) between `found` and the same corner located
/// by other templates (`None` when none of them could be cut or located):
/// - **re-centred**: templates of the same size cut from the detecting ortho with the corner a quarter
///   template off centre (four directions). They share most of the corner's content but not the border, so a
///   location that depends on what lies at one edge of the template (another height, a near-periodic pattern)
///   moves;
/// - **neighbours' views**: each neighbouring recording's template around the corner as that recording saw it
///   (`views`, their orthos in `neighbours`), placed on the detecting ortho grid so that its corner falls on
///   the detecting one — another rendering of the same corner (another blur, another parallax).
///
/// All of them show the same corner, so all must land on the same aerial position.
#[allow(clippy::too_many_arguments)]
fn view_disagreement_px(
    found: &ViewLocation,
    views: &[super::registration::ViewGround],
    ortho: &OrthoImage,
    neighbours: &[NeighbourOrtho],
    aerial: &GrayImage,
    tf: &Similarity2,
    p: &RefineParams,
    phase: &PhaseCorrelationParams,
    buf: &mut Buffers,
) -> Option<f64> {
    let (u_o, v_o) = found.corner_ortho_px;
    let (x0, y0) = found.template_origin;
    let mut worst: Option<f64> = None;
    let mut compare = |buf: &mut Buffers, origin: (f64, f64)| {
        if let Ok((dx, dy, _)) =
            search_template(aerial, tf, &buf.view, origin, p, phase, &mut buf.search)
        {
            // `dx, dy` move this template's centre; the corner moves with it.
            let d = (dx - found.shift_px.0).hypot(dy - found.shift_px.1);
            worst = Some(worst.map_or(d, |w: f64| w.max(d)));
        }
    };
    let quarter = (p.template_px / 4) as f64;
    for (ox, oy) in [
        (quarter, 0.0),
        (-quarter, 0.0),
        (0.0, quarter),
        (0.0, -quarter),
    ] {
        let (rx0, ry0) = (x0 + ox, y0 + oy);
        if cut_ortho_template(
            ortho,
            rx0 as isize,
            ry0 as isize,
            p.template_px,
            &mut buf.view,
        ) && grey_std(&buf.view) >= p.min_template_std
        {
            compare(buf, (rx0, ry0));
        }
    }
    for view in views {
        let Some((nb, (u_n, v_n))) = neighbour_view(neighbours, view) else {
            continue;
        };
        // The neighbour's template: its top-left pixel placed like the detecting one's relative to the corner.
        let (nx0, ny0) = (u_n - (u_o - x0), v_n - (v_o - y0));
        let (ix0, iy0) = (nx0.round(), ny0.round());
        if !cut_ortho_template(
            nb.ortho,
            ix0 as isize,
            iy0 as isize,
            p.template_px,
            &mut buf.view,
        ) {
            continue;
        }
        // On the detecting grid the neighbour's corner then lies on (u_o, v_o).
        compare(buf, (x0 + (ix0 - nx0), y0 + (iy0 - ny0)));
    }
    worst
}

/// The view check's bound on the disagreement of two locations, ortho px: `view_k_sigma` standard deviations
/// of the difference of two locations of σ = `view_sigma_px` each.
fn view_bound_px(p: &RefineParams) -> f64 {
    p.view_k_sigma * std::f64::consts::SQRT_2 * p.view_sigma_px
}

/// Per match: its observation minus the tie point's MM object point (`MmTiePoint::point_world`, from all its
/// panoramas) mapped into the aerial image through the ortho grid and `tf`, full aerial px. Correct
/// correspondences of one recording share this difference (the recording's position error, a few pixels); a
/// corner whose MM triangulation and aerial location disagree — a panorama match or an aerial location off by
/// a pixel or two — departs from it. Non-finite for a tie point not in the window.
fn point_residuals_px(
    matches: &[AerialMatch],
    window: &MmWindowMatch,
    mm_ortho: &OrthoImage,
    tf: &Similarity2,
) -> Vec<[f64; 2]> {
    let index = crate::positions::positions_by(&window.tie_points, |tp| tp.id.as_str());
    matches
        .iter()
        .map(|m| {
            let Some(&i) = index.get(m.tie_point_id.as_str()) else {
                return [f64::NAN, f64::NAN];
            };
            let x = Vector3::from(window.tie_points[i].point_world);
            let (u, v) = mm_ortho.georef.world_to_pixel(&x);
            let at = tf.apply(&Vector2::new(u, v));
            [m.observation.u_px - at.x, m.observation.v_px - at.y]
        })
        .collect()
}

/// Robust σ per axis of 2-D residuals about their component-wise median: the median distance to it divided by
/// √(2 ln 2) (the median of a Rayleigh distribution with that σ). `None` with fewer than three finite residuals
/// (no spread to measure beside a possible outlier).
fn robust_spread_px(residuals: &[[f64; 2]]) -> Option<f64> {
    let consensus = median_consensus(residuals, f64::INFINITY)?;
    let mut distances: Vec<f64> = consensus
        .deviations
        .into_iter()
        .filter(|d| d.is_finite())
        .collect();
    if distances.len() < 3 {
        return None;
    }
    let median = median_in_place(&mut distances)?;
    Some(median / (2.0 * std::f64::consts::LN_2).sqrt())
}

/// The matches whose residual (parallel to `matches`) lies within `bound_px` of the component-wise median
/// residual; with two, both if they differ by at most √2·`bound_px` (the difference of two observations), else
/// none; a single one is kept (nothing to compare it with).
fn consistent_residuals(
    matches: Vec<AerialMatch>,
    residuals: &[[f64; 2]],
    bound_px: f64,
) -> Vec<AerialMatch> {
    match matches.len() {
        0 | 1 => matches,
        2 => {
            let d = (residuals[0][0] - residuals[1][0]).hypot(residuals[0][1] - residuals[1][1]);
            if d <= std::f64::consts::SQRT_2 * bound_px {
                matches
            } else {
                Vec::new()
            }
        }
        _ => {
            let Some(consensus) = median_consensus(residuals, bound_px) else {
                return Vec::new();
            };
            matches
                .into_iter()
                .zip(consensus.inliers)
                .filter_map(|(m, inlier)| inlier.then_some(m))
                .collect()
        }
    }
}

/// The matches whose correction (observed − predicted, aerial px) lies within `spread_px` of the component-wise
/// median correction of all of them; with fewer than 3 matches, all of them if they agree within `spread_px`,
/// else none (there is no majority to tell which is wrong).
fn consistent_shifts(matches: Vec<AerialMatch>, spread_px: f64) -> Vec<AerialMatch> {
    let shift = |m: &AerialMatch| {
        (
            m.observation.u_px - m.predicted_u_px,
            m.observation.v_px - m.predicted_v_px,
        )
    };
    let far = |a: (f64, f64), b: (f64, f64)| !((a.0 - b.0).hypot(a.1 - b.1) <= spread_px);
    if matches.len() < 3 {
        let agree = matches
            .iter()
            .all(|m| matches.iter().all(|o| !far(shift(m), shift(o))));
        return if agree { matches } else { Vec::new() };
    }
    let shifts: Vec<[f64; 2]> = matches
        .iter()
        .map(|m| {
            let (du, dv) = shift(m);
            [du, dv]
        })
        .collect();
    let Some(consensus) = median_consensus(&shifts, spread_px) else {
        return Vec::new(); // no finite correction at all
    };
    matches
        .into_iter()
        .zip(consensus.inliers)
        .filter_map(|(m, inlier)| inlier.then_some(m))
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn located(id: &str, shift: (f64, f64)) -> AerialMatch {
        AerialMatch::shifted(id, "a", (1000.0, 2000.0), shift, 0.9)
    }

    fn ids(v: &[AerialMatch]) -> Vec<&str> {
        v.iter().map(|m| m.tie_point_id.as_str()).collect()
    }

    #[test]
    fn a_tie_point_one_stripe_off_the_others_is_dropped() {
        let m = vec![
            located("a", (1.5, -0.5)),
            located("b", (1.2, -0.2)),
            located("zebra", (11.4, -0.3)), // one 10-px period further
            located("c", (1.9, -0.8)),
        ];
        assert_eq!(ids(&consistent_shifts(m, 5.0)), ["a", "b", "c"]);
    }

    #[test]
    fn the_one_corner_whose_aerial_location_departs_from_its_mm_point_is_dropped() {
        // Four corners of one recording in one image: the recording is off by (2.3, −1.1) px, located with
        // ±0.3 px noise; corner "c" is located 1.6 px away from its MM point's offset (5.3 σ at σ = 0.3 px).
        let m = vec![
            located("a", (2.1, -1.0)),
            located("b", (2.5, -1.3)),
            located("c", (3.9, -1.0)),
            located("d", (2.2, -0.9)),
        ];
        let residuals: Vec<[f64; 2]> = [(2.1, -1.0), (2.5, -1.3), (3.9, -1.0), (2.2, -0.9)]
            .iter()
            .map(|&(u, v)| [u, v])
            .collect();
        let bound_px = 2.45 * 0.3;
        assert_eq!(
            ids(&consistent_residuals(m.clone(), &residuals, bound_px)),
            ["a", "b", "d"]
        );
        // Two that agree are kept, two that do not are both dropped, one alone is kept.
        assert_eq!(
            ids(&consistent_residuals(
                m[..2].to_vec(),
                &residuals[..2],
                bound_px
            )),
            ["a", "b"]
        );
        assert!(consistent_residuals(m[1..3].to_vec(), &residuals[1..3], bound_px).is_empty());
        assert_eq!(
            ids(&consistent_residuals(
                m[2..3].to_vec(),
                &residuals[2..3],
                bound_px
            )),
            ["c"]
        );
    }

    #[test]
    fn the_spread_of_gaussian_residuals_is_measured_and_an_outlier_barely_moves_it() {
        // 400 residuals about (3, −2) px with σ = 1.2 px per axis: the robust spread recovers σ within 10 %,
        // and 40 corners 8 px off (10 %) move it by less than 20 %.
        let mut rng = crate::synth::rng::Stream::new(&[7]);
        let mut residuals: Vec<[f64; 2]> = (0..400)
            .map(|_| [3.0 + 1.2 * rng.normal(), -2.0 + 1.2 * rng.normal()])
            .collect();
        let clean = robust_spread_px(&residuals).expect("400 residuals");
        assert!(
            (clean - 1.2).abs() < 0.12,
            "σ measured {clean} px, 1.2 expected"
        );
        residuals.extend((0..40).map(|k| [11.0, -2.0 + 0.1 * k as f64]));
        let with_outliers = robust_spread_px(&residuals).expect("440 residuals");
        assert!(with_outliers < 1.2 * 1.2, "{with_outliers} px");
        // Two residuals (or two finite ones) have no spread to measure beside a possible outlier.
        assert_eq!(robust_spread_px(&residuals[..2]), None);
        assert_eq!(
            robust_spread_px(&[[0.0, 0.0], [1.0, 1.0], [f64::NAN, 0.0]]),
            None
        );
    }

    #[test]
    fn a_measured_spread_keeps_corners_a_fixed_sigma_would_drop() {
        // A recording whose corners scatter by about 1 px (e.g. a heading error): at the fixed σ = 0.5 px three
        // correct corners fall outside 2.45 σ of the median; with the measured σ (1.19 px) only the 6-px outlier
        // does.
        let offsets = [
            (0.0, 0.0),
            (0.9, -0.4),
            (-1.0, 0.6),
            (1.4, 0.8),
            (-0.6, -1.3),
            (6.0, 0.0),
        ];
        let m: Vec<AerialMatch> = offsets
            .iter()
            .enumerate()
            .map(|(k, &o)| located(&format!("p{k}"), o))
            .collect();
        let residuals: Vec<[f64; 2]> = offsets.iter().map(|&(u, v)| [u, v]).collect();
        let fixed = consistent_residuals(m.clone(), &residuals, 2.45 * 0.5);
        assert_eq!(ids(&fixed), ["p0", "p1"]);
        let sigma_px = robust_spread_px(&residuals)
            .expect("six residuals")
            .max(0.5);
        let measured = consistent_residuals(m, &residuals, 2.45 * sigma_px);
        assert_eq!(ids(&measured), ["p0", "p1", "p2", "p3", "p4"]);
    }

    #[test]
    fn two_that_disagree_are_both_dropped_and_two_that_agree_are_kept() {
        let agree = vec![located("a", (0.5, 0.5)), located("b", (-1.0, 2.0))];
        assert_eq!(ids(&consistent_shifts(agree, 5.0)), ["a", "b"]);
        let disagree = vec![located("a", (0.5, 0.5)), located("b", (10.5, 0.5))];
        assert!(consistent_shifts(disagree, 5.0).is_empty());
        assert_eq!(
            ids(&consistent_shifts(vec![located("a", (9.0, 9.0))], 5.0)),
            ["a"]
        );
    }
}
