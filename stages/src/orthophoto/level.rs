//! The resolution at which a recording's ground ortho meets the orthophoto: the orthophoto's pyramid level whose
//! pixel is not finer than `registration_gsd_m` (`nadir::aerial_patch::working_level`), and never finer than
//! the orthophoto's detail level (`PyramidLayout::detail_level`): an orthophoto enlarged by pixel repetition
//! holds no detail below that level, so its finer levels would only make the registration slower and its
//! parameters in pixels mean less on the ground. The ortho is made north-up at that level's pixel size.

use crate::imaging::pyramid::{PyramidLayout, SampleDepth, DEFAULT_TILE_SIDE};
use crate::nadir::aerial_patch::working_level;
use crate::nadir::OrthoParams;

/// The pyramid level of an orthophoto of `pixel_m` and `size_px` (width, height) that the route works at:
/// [`working_level`] for `registration_gsd_m`, raised to `detail_level` (clamped to the coarsest level).
pub fn orthophoto_level(
    pixel_m: f64,
    registration_gsd_m: f64,
    size_px: (u32, u32),
    detail_level: usize,
) -> usize {
    let levels = PyramidLayout::new(
        size_px.0.max(1) as usize,
        size_px.1.max(1) as usize,
        SampleDepth::U8,
        DEFAULT_TILE_SIDE,
    )
    .map_or(1, |l| l.levels());
    working_level(pixel_m, registration_gsd_m, size_px).max(detail_level.min(levels - 1))
}

/// `base` made north-up at the pixel size of the orthophoto's working level ([`orthophoto_level`]).
pub fn ortho_params_for_orthophoto(
    base: &OrthoParams,
    pixel_m: f64,
    size_px: (u32, u32),
    detail_level: usize,
) -> OrthoParams {
    let level = orthophoto_level(pixel_m, base.registration_gsd_m, size_px, detail_level);
    OrthoParams {
        gsd_m: pixel_m * (1u64 << level) as f64,
        rotation_deg: 0.0,
        ..base.clone()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_level_is_the_working_level_unless_the_detail_level_is_coarser() {
        // 10 cm orthophoto, 12 cm registration GSD: full resolution.
        assert_eq!(orthophoto_level(0.10, 0.12, (4000, 3000), 0), 0);
        // 2.5 cm: level 2 (10 cm) by the registration GSD alone.
        assert_eq!(orthophoto_level(0.025, 0.12, (16000, 12000), 0), 2);
        assert_eq!(orthophoto_level(0.025, 0.12, (16000, 12000), 1), 2);
        // A 10 cm orthophoto enlarged 4× (2.5 cm pixels, detail level 2) and 8× (detail level 3).
        assert_eq!(orthophoto_level(0.025, 0.12, (16000, 12000), 2), 2);
        assert_eq!(orthophoto_level(0.0125, 0.12, (32000, 24000), 3), 3);
        // A 5 cm orthophoto that is a 4× enlargement of a 20 cm one: the 20 cm level, coarser than 12 cm.
        assert_eq!(orthophoto_level(0.05, 0.12, (8000, 6000), 2), 2);
        // The detail level never points past the coarsest level.
        let levels = PyramidLayout::new(300, 200, SampleDepth::U8, DEFAULT_TILE_SIDE)
            .expect("a valid size")
            .levels();
        assert_eq!(orthophoto_level(0.05, 0.12, (300, 200), 99), levels - 1);
        let p = ortho_params_for_orthophoto(&OrthoParams::default(), 0.05, (8000, 6000), 2);
        assert!((p.gsd_m - 0.20).abs() < 1e-12 && p.rotation_deg == 0.0);
    }
}
