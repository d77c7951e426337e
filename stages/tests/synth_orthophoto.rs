//! Known-answer test of the generator's orthophoto and DTM: GeoTIFFs whose headers read back to the grid they
//! were written on, markers at known ground points found in the orthophoto displaced by exactly the warp the
//! generator states, and DTM heights equal to the scene's ground.

use nalgebra::Vector3;
use skytie_stages::campaign::Recording;
use skytie_stages::imaging::georef::read_header;
use skytie_stages::imaging::io::load_rgb;
use skytie_stages::orthophoto::dtm::load_tile;
use skytie_stages::synth::orthophoto::{write_area, OrthophotoOptions};
use skytie_stages::synth::scene::{Marker, Scene};

const ORIGIN: [f64; 2] = [155_000.0, 463_000.0];
const GROUND_Z: f64 = 2.5;

#[test]
fn markers_appear_where_the_stated_warp_puts_them_and_the_dtm_is_the_ground() {
    let points = [[155_004.0, 463_003.0], [155_011.5, 462_996.5]];
    let markers = points
        .iter()
        .map(|p| Marker {
            center_world: Vector3::new(p[0], p[1], GROUND_Z),
            radius_m: 0.4,
            rgb: [1.0, 1.0, 1.0],
        })
        .collect();
    let scene = Scene::markers_only(ORIGIN, GROUND_Z, markers);
    let truth: Vec<Recording> = [[155_000.0, 463_000.0], [155_015.0, 463_000.0]]
        .iter()
        .enumerate()
        .map(|(i, p)| {
            Recording::new(
                &format!("r{i}"),
                i as f64,
                [p[0], p[1], GROUND_Z + 2.5],
                90.0,
                2.5,
            )
        })
        .collect();
    let o = OrthophotoOptions {
        gsd_m: 0.05,
        error_m: 0.4,
        without_nadir: true,
    };
    let dir = tempfile::tempdir().unwrap();
    let files = write_area(&scene, &truth, &o, 9, 0, dir.path()).unwrap();
    let header = read_header(&dir.path().join(&files.orthophoto)).unwrap();
    assert_eq!(header.epsg, Some(28992));
    assert!((header.transform.pixel_m - 0.05).abs() < 1e-12);
    assert!(
        header.contains(155_000.0, 463_000.0, 29.0) && header.contains(155_015.0, 463_000.0, 29.0)
    );
    let img = load_rgb(&dir.path().join(&files.orthophoto)).unwrap();
    for p in points {
        // Centroid of the bright marker pixels near where the warp puts it.
        let d = o.displacement_m(9, 0, p[0], p[1]);
        let (u0, v0) = header.transform.world_to_pixel(p[0] + d[0], p[1] + d[1]);
        let rows = (v0 as usize - 20)..(v0 as usize + 20);
        let cols = (u0 as usize - 20)..(u0 as usize + 20);
        let grey = |col: usize, row: usize| img.get(col, row).iter().sum::<f32>();
        let (mut lo, mut hi) = (f32::INFINITY, f32::NEG_INFINITY);
        for row in rows.clone() {
            for col in cols.clone() {
                (lo, hi) = (lo.min(grey(col, row)), hi.max(grey(col, row)));
            }
        }
        let threshold = 0.5 * (lo + hi);
        let (mut su, mut sv, mut n) = (0.0, 0.0, 0.0);
        for row in rows {
            for col in cols.clone() {
                if grey(col, row) > threshold {
                    su += col as f64 + 0.5;
                    sv += row as f64 + 0.5;
                    n += 1.0;
                }
            }
        }
        assert!(n > 50.0, "marker {p:?} not found");
        let (u, v) = (su / n, sv / n);
        let [x, y] = header.transform.pixel_to_world(u, v);
        let err = (x - p[0] - d[0]).hypot(y - p[1] - d[1]);
        assert!(
            err < 0.03,
            "marker {p:?}: shown at ({x:.3}, {y:.3}), warp {d:?}, error {err:.3} m"
        );
        assert!(d[0].hypot(d[1]) > 0.05, "the test needs a visible warp");
    }
    let dtm = load_tile(
        &dir.path().join(&files.dtm),
        &files.dtm,
        [154_990.0, 462_990.0, 155_020.0, 463_010.0],
    )
    .unwrap()
    .unwrap();
    let z = dtm.height_at(155_007.3, 463_001.1).unwrap();
    assert!((z - GROUND_Z).abs() < 1e-5, "DTM {z}");
}
