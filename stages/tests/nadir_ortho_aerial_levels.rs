//! Known-answer test of the aerial-oriented ortho's level (`ortho_aerial`, thesis 3.4.5.1–3.4.5.2) for an aerial
//! frame enlarged by pixel repetition: a 15 cm frame (coarser than the default `registration_gsd_m` of 12 cm, so
//! registered at full resolution) and its copy with every pixel repeated 4 × 4 times (3.75 cm, camera table
//! scaled by 4). The copy's pyramid has detail level 2; the ortho made for it must be the original's (same GSD,
//! rotation, size, pixels and mask), not the 7.5 cm ortho its 12 cm working level alone would give.

mod support;

use skytie_stages::campaign::{AerialImage, Recording};
use skytie_stages::geometry::FrameCamera;
use skytie_stages::imaging::pyramid::{MemoryPyramid, TileSource};
use skytie_stages::nadir::aerial_overlap::foot_point_world;
use skytie_stages::nadir::aerial_patch::ortho_params_for_aerial_image;
use skytie_stages::nadir::{ortho_project_whole, OrthoParams};
use support::texture::repeated_texture;

/// Linear enlargement of the copy.
const FACTOR: u32 = 4;

fn recording() -> Recording {
    Recording {
        time: "2020-01-01T00:00:00Z".into(),
        ..Recording::new(
            "r1",
            1_577_836_800.0,
            [92_345.678, 437_123.456, 3.5],
            63.0,
            2.2,
        )
    }
}

/// The aerial frame's camera row: 4470 m above the recording's ground, κ = 30°, 15 cm GSD (`scale` = 1), or
/// its enlarged copy's (every pixel quantity times `scale`).
fn aerial_row(rec: &Recording, scale: u32) -> AerialImage {
    let ground_z = rec.z - rec.camera_height_m;
    let s = f64::from(scale);
    let row = AerialImage::ideal(
        "nadir_test",
        [rec.x + 12.0, rec.y - 7.0, ground_z + 4470.0],
        [0.1, -0.08, 30.0],
        s * 4470.0 / 0.15,
        [400 * scale, 300 * scale],
    );
    AerialImage {
        cx_px: s * 203.0,
        cy_px: s * 148.0,
        ..row
    }
}

#[test]
fn a_pixel_repeated_frame_gives_the_same_aerial_ortho_as_the_original() {
    let rec = recording();
    let panorama = repeated_texture(1024, 512, 1, 7);
    let foot = foot_point_world(&rec);
    let base = OrthoParams::default();
    assert!(base.registration_gsd_m < 0.15);

    let frame = MemoryPyramid::from_gray(&repeated_texture(400, 300, 1, 11));
    let enlarged = MemoryPyramid::from_gray(&repeated_texture(400, 300, FACTOR as usize, 11));
    assert_eq!(frame.layout().detail_level, 0);
    assert_eq!(enlarged.layout().detail_level, 2);

    let cam = FrameCamera::from_aerial(&aerial_row(&rec, 1));
    let cam4 = FrameCamera::from_aerial(&aerial_row(&rec, FACTOR));
    let original = ortho_params_for_aerial_image(&cam, foot, &base, frame.layout().detail_level);
    let copy = ortho_params_for_aerial_image(&cam4, foot, &base, enlarged.layout().detail_level);
    assert!((original.gsd_m - 0.15).abs() < 0.002, "{}", original.gsd_m);
    assert!(
        (copy.gsd_m - original.gsd_m).abs() < 1e-12,
        "{} vs {}",
        copy.gsd_m,
        original.gsd_m
    );
    assert!((copy.rotation_deg - original.rotation_deg).abs() < 1e-9);
    // Without the detail level, the copy's 3.75 cm would be registered at its 7.5 cm level.
    let finer = ortho_params_for_aerial_image(&cam4, foot, &base, 0);
    assert!((finer.gsd_m - original.gsd_m / 2.0).abs() < 1e-12);

    let a = ortho_project_whole(&panorama, &rec, &original);
    let b = ortho_project_whole(&panorama, &rec, &copy);
    assert_eq!(a.georef.width_px, b.georef.width_px);
    assert_eq!(a.georef.height_px, b.georef.height_px);
    assert_eq!(a.valid, b.valid);
    let max_diff = a
        .image
        .data
        .iter()
        .zip(&b.image.data)
        .map(|(x, y)| (x - y).abs())
        .fold(0.0f32, f32::max);
    assert!(
        max_diff < 1e-5,
        "ortho grey values differ by up to {max_diff}"
    );
    let c = ortho_project_whole(&panorama, &rec, &finer);
    assert_ne!(a.georef.width_px, c.georef.width_px);
}
