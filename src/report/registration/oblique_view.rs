//! The oblique registration view (thesis Figs 4.9, 4.18): the panorama crop around the observations beside
//! the oblique image crop around them, and the oblique truth (per-observation verdicts, the scene oracle for
//! non-matchable observations) the lines are coloured by.

use super::{best_aerial, canvas, save, truth, Context, ControlPoint, CorrObs, ViewCounts};
use crate::report::image_cache::ImageCache;
use canvas::{crop_scaled, line, ring, side_by_side, Black};
use skytie_stages::campaign::{read_aerial_csv, AerialImage, Campaign, Recording};
use skytie_stages::correspondence::PanoObservation;
use skytie_stages::imaging::image::RgbImage;
use skytie_stages::imaging::pyramid::footprint_level;
use skytie_stages::imaging::pyramid::layout::MAX_LEVELS;
use skytie_stages::oblique::grading::Truth as StageTruth;
use skytie_stages::synth::scene_truth::{SceneOracle, SceneTruth, SCENE_TRUTH_FILE};
use std::collections::BTreeMap;
use std::path::Path;
use truth::{oblique_verdict, ObliqueTruth, Verdict};

/// The crop (x0, y0, w, h) of the image at `path` scaled by `scale` ([`crop_scaled`]), read at the pyramid
/// level matching an output pixel's footprint.
pub(super) fn crop_of(
    images: &ImageCache,
    path: &Path,
    (x0, y0, w, h): (f64, f64, f64, f64),
    scale: f64,
) -> Result<RgbImage, String> {
    let level = footprint_level(1.0, 1.0 / scale, MAX_LEVELS);
    let margin = 2.0 * (1u64 << level) as f64;
    let b = [x0 - margin, y0 - margin, x0 + w + margin, y0 + h + margin];
    Ok(match images.window(path, level, b)? {
        Some(window) => crop_scaled(window.as_ref(), x0, y0, w, h, scale),
        None => crop_scaled(&Black, x0, y0, w, h, scale),
    })
}

/// Bounding box (x0, y0, w, h) of observations, padded, at least `min` pixels wide and high.
pub(super) fn bbox(obs: &[(f64, f64)], pad: f64, min: f64) -> (f64, f64, f64, f64) {
    let (mut x0, mut y0, mut x1, mut y1) = (f64::MAX, f64::MAX, f64::MIN, f64::MIN);
    for &(u, v) in obs {
        x0 = x0.min(u);
        y0 = y0.min(v);
        x1 = x1.max(u);
        y1 = y1.max(v);
    }
    let (cx, cy) = ((x0 + x1) / 2.0, (y0 + y1) / 2.0);
    let w = (x1 - x0 + 2.0 * pad).max(min);
    let h = (y1 - y0 + 2.0 * pad).max(min);
    (cx - w / 2.0, cy - h / 2.0, w, h)
}

/// Panorama crop | oblique image crop around the observations, both scaled to 420 px high.
pub(super) fn oblique_view(
    ctx: &Context<'_>,
    rec: &Recording,
    points: &[&ControlPoint],
    out: &Path,
) -> Result<(String, ViewCounts), String> {
    const HEIGHT: f64 = 420.0;
    let aerial_id = best_aerial(points, "oblique").ok_or("no oblique observation")?;
    let aerial = ctx
        .aerial("oblique", &aerial_id)
        .ok_or_else(|| format!("oblique image {aerial_id} is not in the campaign"))?;
    let pairs: Vec<(&CorrObs, &CorrObs, &ControlPoint)> = points
        .iter()
        .filter_map(|p| {
            let mo = p.pano.iter().find(|o| o.image_id == rec.image_id)?;
            let ao = p
                .aerial
                .iter()
                .find(|o| o.kind == "oblique" && o.image_id == aerial_id)?;
            Some((mo, ao, *p))
        })
        .collect();
    if pairs.is_empty() {
        return Err("no control point seen in both images".into());
    }
    let positions_px = |left: bool| -> Vec<(f64, f64)> {
        pairs
            .iter()
            .map(|(m, a, _)| {
                if left {
                    (m.u_px, m.v_px)
                } else {
                    (a.u_px, a.v_px)
                }
            })
            .collect()
    };
    let lb = bbox(&positions_px(true), 60.0, 200.0);
    let rb = bbox(&positions_px(false), 40.0, 120.0);
    let (ls, rs) = (HEIGHT / lb.3, HEIGHT / rb.3);
    let pano_path = ctx.campaign.root.join("mm/panoramas").join(&rec.file);
    let left = crop_of(ctx.images, &pano_path, lb, ls)?;
    let right = crop_of(ctx.images, &ctx.aerial_path("oblique", aerial), rb, rs)?;
    let gap = 12;
    let mut img = side_by_side(&left, &right, gap);
    let x_off = (left.width + gap) as f64;
    let mut counts = ViewCounts::default();
    for (mo, ao, p) in pairs {
        let a = ((mo.u_px - lb.0) * ls, (mo.v_px - lb.1) * ls);
        let bpt = (x_off + (ao.u_px - rb.0) * rs, (ao.v_px - rb.1) * rs);
        let v = match &ctx.oblique_truth {
            Some(t) => {
                let tie: Vec<PanoObservation> = p.pano.iter().map(pano_observation).collect();
                oblique_verdict(
                    t,
                    &tie,
                    &pano_observation(mo),
                    &aerial_id,
                    [ao.u_px, ao.v_px],
                )
            }
            None => Verdict::Ungraded,
        };
        let colour = counts.add(v);
        line(&mut img, a, bpt, colour, 1);
        ring(&mut img, a, 7.0, colour);
        ring(&mut img, bpt, 7.0, colour);
    }
    save(out, &img)?;
    Ok((aerial_id, counts))
}

pub(super) fn pano_observation(o: &CorrObs) -> PanoObservation {
    PanoObservation {
        image_id: o.image_id.clone(),
        u_px: o.u_px,
        v_px: o.v_px,
    }
}

/// The oblique grading rule's truth without the scene ([`load_scene`] adds it): true poses
/// (`truth/recordings.csv`, panorama sizes) and
/// true oblique poses (`truth/aerial_oblique.csv`, else the campaign's, which synthetic campaigns keep true).
pub(super) fn load_oblique_truth(
    root: &Path,
    campaign: &Campaign,
    truth: &BTreeMap<String, Recording>,
    pano_sizes: &BTreeMap<String, (u32, u32)>,
) -> Result<ObliqueTruth, String> {
    let aerial_path = root.join("truth/aerial_oblique.csv");
    let aerial: Vec<AerialImage> = if aerial_path.exists() {
        let (rows, problems) = read_aerial_csv(&aerial_path);
        if let Some(p) = problems.first() {
            return Err(format!("truth is unreadable: {p}"));
        }
        rows
    } else {
        campaign.oblique.clone()
    };
    Ok(ObliqueTruth {
        truth: StageTruth {
            recordings: truth
                .iter()
                .filter_map(|(id, r)| {
                    let (w, h) = *pano_sizes.get(id)?;
                    Some((id.clone(), (r.clone(), w, h)))
                })
                .collect(),
            aerial: aerial
                .into_iter()
                .map(|a| (a.image_id.clone(), a))
                .collect(),
        },
        scene: None,
    })
}

/// The scene of the campaign's `truth/scene.toml` (None without that file; an error when it cannot be rebuilt,
/// e.g. written by another generator version).
pub(super) fn load_scene(root: &Path) -> Result<Option<SceneOracle>, String> {
    let scene_path = root.join(SCENE_TRUTH_FILE);
    if !scene_path.exists() {
        return Ok(None);
    }
    let text = std::fs::read_to_string(&scene_path)
        .map_err(|e| format!("{}: {e}", scene_path.display()))?;
    SceneTruth::parse(&text)
        .and_then(|s| s.rebuild())
        .map(Some)
        .map_err(|e| format!("{}: {e}", scene_path.display()))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bbox_pads_and_enforces_minimum() {
        let (x0, y0, w, h) = bbox(&[(100.0, 100.0), (110.0, 300.0)], 10.0, 50.0);
        assert_eq!((w, h), (50.0, 220.0));
        assert_eq!((x0, y0), (80.0, 90.0));
    }
}
