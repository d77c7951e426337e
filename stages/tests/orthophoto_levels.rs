//! Known-answer test of the orthophoto route's working resolution (`orthophoto::ortho_params_for_orthophoto`)
//! for an orthophoto enlarged by pixel repetition: a 20 cm orthophoto (coarser than the default
//! `registration_gsd_m` of 12 cm, so registered at full resolution) and its copies with every pixel repeated
//! 4 × 4 times (5 cm pixels, detail level 2) and 8 × 8 times (2.5 cm, detail level 3). The ground ortho made
//! for a copy must be the original's 20 cm one, not the 10 cm one its 12 cm working level alone would give.

mod support;

use skytie_stages::imaging::pyramid::{MemoryPyramid, TileSource};
use skytie_stages::nadir::aerial_patch::working_level;
use skytie_stages::nadir::OrthoParams;
use skytie_stages::orthophoto::ortho_params_for_orthophoto;
use support::texture::repeated_texture;

/// Pixel size of the original orthophoto, m.
const ORIGINAL_GSD_M: f64 = 0.20;

#[test]
fn a_pixel_repeated_orthophoto_gives_the_original_orthophotos_ortho() {
    let base = OrthoParams::default();
    assert!(base.registration_gsd_m < ORIGINAL_GSD_M && base.registration_gsd_m >= 0.10);
    let (w, h) = (240usize, 180usize);
    let made_for = |factor: usize| {
        let pyramid = MemoryPyramid::from_gray(&repeated_texture(w, h, factor, 5));
        let size = ((w * factor) as u32, (h * factor) as u32);
        let gsd_m = ORIGINAL_GSD_M / factor as f64;
        let detail = pyramid.layout().detail_level;
        let alone = working_level(gsd_m, base.registration_gsd_m, size);
        (
            ortho_params_for_orthophoto(&base, gsd_m, size, detail),
            detail,
            gsd_m * (1u64 << alone) as f64,
        )
    };
    let (original, detail, _) = made_for(1);
    assert_eq!(detail, 0);
    assert_eq!(
        (original.gsd_m, original.rotation_deg),
        (ORIGINAL_GSD_M, 0.0)
    );
    for (factor, expected_detail) in [(4, 2), (8, 3)] {
        let (copy, detail, working_alone_gsd_m) = made_for(factor);
        assert_eq!(detail, expected_detail, "{factor}× copy");
        assert!(
            (working_alone_gsd_m - 0.10).abs() < 1e-12,
            "{factor}× copy: the working level alone gives {working_alone_gsd_m} m"
        );
        assert!(
            (copy.gsd_m - original.gsd_m).abs() < 1e-12,
            "{factor}× copy: ortho GSD {} m, the original's {} m",
            copy.gsd_m,
            original.gsd_m
        );
        assert_eq!(
            copy, original,
            "{factor}× copy: every other ortho parameter is the workflow's"
        );
    }
}
