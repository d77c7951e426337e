//! Coverage of the demo and paper flight plans (thesis 3.5.1.1: 60 % / 40 % overlap; 4.5: obliques in four
//! directions): every panorama's ground point is seen by ≥ 2 nadir frames (most by 4+) and by ≥ 2 oblique
//! frames per viewing direction; the paper areas do not overlap. Planning only, no rendering.

use nalgebra::Vector3;
use skytie_stages::campaign::AerialImage;
use skytie_stages::geometry::FrameCamera;
use skytie_stages::synth::generate::plan_campaign;
use skytie_stages::synth::{Preset, SynthOptions};

fn seen_by(images: &[AerialImage], p: &Vector3<f64>) -> usize {
    images
        .iter()
        .filter(|a| {
            let c = FrameCamera::from_aerial(a);
            c.project_world(p).is_some_and(|(u, v)| c.contains(u, v))
        })
        .count()
}

#[test]
fn demo_route_is_covered_by_nadir_and_oblique_frames() {
    let plan = plan_campaign(&SynthOptions::new(Preset::Demo, 1)).unwrap();
    let area = &plan.areas[0];
    let mut nadir_counts = Vec::new();
    for r in &area.truth {
        let ground = Vector3::new(r.x, r.y, r.z - r.camera_height_m);
        nadir_counts.push(seen_by(&area.nadir, &ground));
        for letter in ["_n_", "_e_", "_s_", "_w_"] {
            let obl: Vec<AerialImage> = area
                .oblique
                .iter()
                .filter(|a| a.image_id.contains(letter))
                .cloned()
                .collect();
            let n = seen_by(&obl, &ground);
            assert!(
                n >= 2,
                "{} seen by {n} obliques looking {letter}",
                r.image_id
            );
        }
    }
    eprintln!(
        "demo: {} nadir, {} oblique; nadir views per panorama: {nadir_counts:?}",
        area.nadir.len(),
        area.oblique.len()
    );
    assert!(nadir_counts.iter().all(|&n| n >= 2), "{nadir_counts:?}");
    let four_plus = nadir_counts.iter().filter(|&&n| n >= 4).count();
    assert!(
        four_plus * 2 > nadir_counts.len(),
        "most in 4+ nadir frames: {nadir_counts:?}"
    );
    for a in &area.nadir {
        assert!(a.omega_deg.abs() < 1.0 && a.phi_deg.abs() < 1.0);
        assert!(
            (a.z - (area.truth[0].z - 2.2) - 4470.0).abs() < 5.0,
            "≈ 4470 m above ground"
        );
        assert!((a.focal_px - 44_700.0).abs() < 1e-6);
    }
}

#[test]
fn paper_has_four_separate_areas_of_about_a_hundred_panoramas() {
    let plan = plan_campaign(&SynthOptions::new(Preset::Paper, 1)).unwrap();
    assert_eq!(plan.areas.len(), 4);
    for (i, a) in plan.areas.iter().enumerate() {
        assert!(
            (30..=100).contains(&a.truth.len()),
            "area {i}: {} panoramas",
            a.truth.len()
        );
        // No aerial frame of another area sees this area's route.
        for (j, b) in plan.areas.iter().enumerate().filter(|(j, _)| *j != i) {
            for r in &a.truth {
                let p = Vector3::new(r.x, r.y, r.z - 2.2);
                assert_eq!(
                    seen_by(&b.nadir, &p) + seen_by(&b.oblique, &p),
                    0,
                    "area {j} frames see area {i}"
                );
            }
        }
    }
    let ids: std::collections::BTreeSet<_> =
        plan.recorded().iter().map(|r| r.image_id.clone()).collect();
    assert_eq!(
        ids.len(),
        plan.recorded().len(),
        "image ids unique across areas"
    );
}
