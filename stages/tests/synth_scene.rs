//! Known-answer tests of the procedural street scene (`skytie_stages::synth::scene`): determinism, ground
//! heights and slopes, façade distances, epoch-dependent shadows and cars, markers, check-point candidates.

use nalgebra::Vector3;
use skytie_stages::synth::scene::{Epoch, Marker, Scene, SceneSpec, SurfaceKind};

fn demo() -> Scene {
    Scene::generate(&SceneSpec::demo(), 7)
}

/// Local (street) point → world point at height z.
fn world(scene: &Scene, x: f64, y: f64, z: f64) -> Vector3<f64> {
    let w = scene.local_to_world_xy([x, y]);
    Vector3::new(w[0], w[1], z)
}

fn local_dir(scene: &Scene, x: f64, y: f64, z: f64) -> Vector3<f64> {
    scene.local_dir_to_world(&Vector3::new(x, y, z))
}

#[test]
fn generation_is_deterministic_per_seed_and_seeds_differ() {
    let a = demo();
    let b = demo();
    let c = Scene::generate(&SceneSpec::demo(), 8);
    let route = a.route_world().to_vec();
    let mut n_diff = 0;
    let mut n = 0;
    for (i, p) in route.iter().enumerate() {
        let o = Vector3::new(p[0], p[1], a.ground_height_m(p[0], p[1]) + 2.5);
        for k in 0..64 {
            let az = k as f64 * 0.0981 + i as f64 * 0.01;
            let el = -0.6 + (k % 9) as f64 * 0.15;
            let d = Vector3::new(az.cos() * el.cos(), az.sin() * el.cos(), el.sin());
            for e in [Epoch::MobileMapping, Epoch::Aerial] {
                let ra = a.radiance(&o, &d, e);
                assert_eq!(
                    ra,
                    b.radiance(&o, &d, e),
                    "same seed must give identical radiance"
                );
                if ra != c.radiance(&o, &d, e) {
                    n_diff += 1;
                }
                n += 1;
            }
        }
    }
    assert!(
        n_diff * 4 > n,
        "different seeds should differ on many rays: {n_diff}/{n}"
    );
}

#[test]
fn vertical_rays_hit_the_road_at_ground_height_which_slopes_and_has_crossfall() {
    let s = demo();
    let mut n = 0;
    for p in s.route_world() {
        let z = s.ground_height_m(p[0], p[1]);
        let h = s
            .first_hit(
                &Vector3::new(p[0], p[1], z + 50.0),
                &Vector3::new(0.0, 0.0, -1.0),
                Epoch::MobileMapping,
            )
            .unwrap();
        assert!(
            matches!(h.surface, SurfaceKind::Road | SurfaceKind::Marking),
            "{:?}",
            h.surface
        );
        assert!(
            (h.point_world.z - z).abs() < 1e-3,
            "hit z {} vs ground {}",
            h.point_world.z,
            z
        );
        assert!((h.distance_m - 50.0).abs() < 1e-3);
        n += 1;
    }
    assert!(n >= 2);
    // longitudinal slope: ≥ 0.3 m over 100 m along the main street
    let a = world(&s, 10.0, -1.5, 0.0);
    let b = world(&s, 110.0, -1.5, 0.0);
    let dz = (s.ground_height_m(b.x, b.y) - s.ground_height_m(a.x, a.y)).abs();
    assert!(dz >= 0.3, "slope over 100 m: {dz}");
    // cross-fall: 2 % from the crown to 3 m off it (both sides lower)
    let c = world(&s, 50.0, 0.0, 0.0);
    let l = world(&s, 50.0, 3.0, 0.0);
    let r = world(&s, 50.0, -3.0, 0.0);
    let zc = s.ground_height_m(c.x, c.y);
    let spec = SceneSpec::demo();
    assert!((zc - s.ground_height_m(l.x, l.y) - (0.06 - 3.0 * spec.slope_y)).abs() < 1e-6);
    assert!((zc - s.ground_height_m(r.x, r.y) - (0.06 + 3.0 * spec.slope_y)).abs() < 1e-6);
    // the kerb: 0.12 m step up from the road edge to the sidewalk
    let e_in = world(&s, 50.0, 4.499, 0.0);
    let e_out = world(&s, 50.0, 4.501, 0.0);
    let step = s.ground_height_m(e_out.x, e_out.y) - s.ground_height_m(e_in.x, e_in.y);
    assert!((step - 0.12).abs() < 1e-3, "kerb step {step}");
}

#[test]
fn horizontal_rays_from_the_crown_hit_facades_at_their_setback() {
    for scene in [demo(), Scene::generate(&SceneSpec::tiny(), 3)] {
        let mut facade_hits = 0;
        let mut total = 0;
        for b in scene.buildings() {
            let f = b.front_normal_local;
            if f[1].abs() < 0.5 {
                continue; // cross-street buildings
            }
            total += 1;
            let x = 0.5 * (b.footprint_min_local[0] + b.footprint_max_local[0]);
            let expect = if f[1] < 0.0 {
                b.footprint_min_local[1]
            } else {
                -b.footprint_max_local[1]
            };
            let z = b.floor0_z_m + 1.7;
            let o = world(&scene, x, 0.0, z);
            let d = local_dir(&scene, 0.0, -f[1], 0.0);
            let h = scene
                .first_hit(&o, &d, Epoch::MobileMapping)
                .expect("a horizontal ray towards a building hits");
            match h.surface {
                SurfaceKind::Facade { building } => {
                    assert_eq!(building, b.id);
                    assert!(
                        (h.distance_m - expect).abs() < 1e-6,
                        "distance {} vs set-back {}",
                        h.distance_m,
                        expect
                    );
                    facade_hits += 1;
                }
                // a tree trunk may stand in front of the façade, never anything behind it
                SurfaceKind::Tree => assert!(h.distance_m < expect),
                other => panic!(
                    "unexpected {other:?} at {} (façade at {expect})",
                    h.distance_m
                ),
            }
        }
        assert!(total >= 2);
        assert!(facade_hits * 10 >= total * 8, "{facade_hits}/{total}");
    }
}

#[test]
fn shadows_and_cars_differ_between_epochs() {
    let s = demo();
    // shadows: radiance of ground points seen from above differs between the two suns
    let mut differ = 0;
    let mut n = 0;
    for i in 0..200 {
        for j in 0..20 {
            let (x, y) = (i as f64, -12.0 + j as f64 * 1.2);
            let o = world(&s, x, y, 60.0);
            let d = Vector3::new(0.0, 0.0, -1.0);
            let (Some(a), Some(b)) = (
                s.first_hit(&o, &d, Epoch::MobileMapping),
                s.first_hit(&o, &d, Epoch::Aerial),
            ) else {
                continue;
            };
            if a.surface != b.surface
                || !matches!(
                    a.surface,
                    SurfaceKind::Road | SurfaceKind::Sidewalk | SurfaceKind::Grass
                )
            {
                continue;
            }
            n += 1;
            let ra = s.radiance(&o, &d, Epoch::MobileMapping);
            let rb = s.radiance(&o, &d, Epoch::Aerial);
            let (la, lb) = (ra[1], rb[1]);
            // lit vs shadowed is a factor > 2 in brightness
            if la > 2.0 * lb || lb > 2.0 * la {
                differ += 1;
            }
        }
    }
    assert!(n > 1000);
    assert!(
        differ * 50 > n,
        "shadows differ at {differ} of {n} ground points"
    );
    // a car present in one epoch only is hit in that epoch only
    let mut checked = 0;
    for car in s.cars() {
        let in_mm = Scene::car_in_epoch(car, Epoch::MobileMapping);
        let in_ae = Scene::car_in_epoch(car, Epoch::Aerial);
        if in_mm == in_ae {
            continue;
        }
        let side = car.centre_local[1].signum();
        let o = world(&s, car.centre_local[0], 0.0, car.ground_z_m + 0.6);
        let d = local_dir(&s, 0.0, side, 0.0);
        let hm = s.first_hit(&o, &d, Epoch::MobileMapping);
        let ha = s.first_hit(&o, &d, Epoch::Aerial);
        assert_eq!(hm.is_some_and(|h| h.surface == SurfaceKind::Car), in_mm);
        assert_eq!(ha.is_some_and(|h| h.surface == SurfaceKind::Car), in_ae);
        let near_side = car.centre_local[1].abs() - 0.5 * car.width_m;
        let h = if in_mm { hm } else { ha }.unwrap();
        assert!((h.distance_m - near_side).abs() < 1e-6);
        checked += 1;
    }
    assert!(
        checked >= 2,
        "the demo must have single-epoch cars: {checked}"
    );
}

#[test]
fn markers_are_hit_and_emit_their_colour() {
    let origin = [92_000.0, 437_000.0];
    let c = Vector3::new(92_010.0, 437_020.0, 3.5);
    let m = Marker {
        center_world: c,
        radius_m: 0.25,
        rgb: [0.9, 0.1, 0.2],
    };
    let s = Scene::markers_only(origin, 1.0, vec![m.clone()]);
    let o = Vector3::new(92_000.0, 437_000.0, 2.5);
    let d = c - o;
    let h = s.first_hit(&o, &d, Epoch::Aerial).unwrap();
    assert_eq!(h.surface, SurfaceKind::Marker);
    assert!((h.distance_m - (d.norm() - 0.25)).abs() < 1e-9);
    assert_eq!(s.radiance(&o, &d, Epoch::MobileMapping), [0.9, 0.1, 0.2]);
    // the plain ground is flat at 1.0 and uniformly grey (markers cast no shadow)
    let down = Vector3::new(0.0, 0.0, -1.0);
    let g = s
        .first_hit(
            &Vector3::new(92_011.0, 437_020.0, 10.0),
            &down,
            Epoch::MobileMapping,
        )
        .unwrap();
    assert_eq!(g.surface, SurfaceKind::Road);
    assert!((g.point_world.z - 1.0).abs() < 1e-9);
    let r1 = s.radiance(
        &Vector3::new(92_011.0, 437_020.0, 10.0),
        &down,
        Epoch::MobileMapping,
    );
    let r2 = s.radiance(
        &Vector3::new(91_950.0, 436_990.0, 10.0),
        &down,
        Epoch::MobileMapping,
    );
    assert_eq!(r1, r2);
    // markers added to a generated scene
    let mut s = demo();
    let p = s.route_world()[0];
    let z = s.ground_height_m(p[0], p[1]);
    let c = Vector3::new(p[0] + 0.3, p[1], z + 1.0);
    s.add_markers(&[Marker {
        center_world: c,
        radius_m: 0.1,
        rgb: [0.0, 1.0, 0.0],
    }]);
    let o = Vector3::new(p[0] + 0.3, p[1], z + 30.0);
    let h = s.first_hit(&o, &down, Epoch::MobileMapping).unwrap();
    assert_eq!(h.surface, SurfaceKind::Marker);
    assert!((h.point_world.z - (z + 1.1)).abs() < 1e-9);
    assert_eq!(s.radiance(&o, &down, Epoch::Aerial), [0.0, 1.0, 0.0]);
}

#[test]
fn checkpoint_candidates_lie_on_the_ground_and_are_visible() {
    let s = demo();
    let cands = s.checkpoint_candidates();
    assert!(cands.len() >= 50, "{} candidates", cands.len());
    for kind in [
        "zebra_corner",
        "stop_line_corner",
        "manhole_centre",
        "arrow_tip",
        "dash_end",
    ] {
        assert!(cands.iter().any(|(k, _)| k == kind), "no {kind}");
    }
    for (kind, p) in &cands {
        let z = s.ground_height_m(p.x, p.y);
        assert!((p.z - z).abs() < 1e-3, "{kind} off the ground");
        for e in [Epoch::MobileMapping, Epoch::Aerial] {
            let h = s
                .first_hit(
                    &(p + Vector3::new(0.0, 0.0, 2.0)),
                    &Vector3::new(0.0, 0.0, -1.0),
                    e,
                )
                .unwrap();
            assert!(
                matches!(h.surface, SurfaceKind::Road | SurfaceKind::Marking),
                "{kind}: {:?}",
                h.surface
            );
            assert!((h.point_world - p).norm() < 1e-3);
        }
    }
    // a zebra corner is on a paint boundary: slightly inside the stripe is Marking
    let zebra: Vec<_> = cands.iter().filter(|(k, _)| k == "zebra_corner").collect();
    assert!(zebra.len() >= 32);
}

#[test]
fn all_presets_generate_and_render() {
    for spec in [
        SceneSpec::tiny(),
        SceneSpec::demo(),
        SceneSpec::paper_area(0),
        SceneSpec::paper_area(1),
        SceneSpec::paper_area(2),
        SceneSpec::paper_area(3),
    ] {
        let s = Scene::generate(&spec, 1);
        let r = s.route_world();
        assert!(r.len() >= 2);
        let (lo, hi) = s.bounds_world();
        for p in r {
            assert!(p[0] > lo[0] && p[0] < hi[0] && p[1] > lo[1] && p[1] < hi[1]);
        }
        let p = r[0];
        let o = Vector3::new(p[0], p[1], s.ground_height_m(p[0], p[1]) + 2.5);
        for k in 0..100 {
            let a = k as f64 * 0.0628;
            let rad = s.radiance(
                &o,
                &Vector3::new(a.cos(), a.sin(), -0.3 + 0.006 * k as f64),
                Epoch::MobileMapping,
            );
            assert!(rad.iter().all(|v| v.is_finite() && *v >= 0.0 && *v <= 1.5));
        }
    }
    // area 2 has water, area 1 has trees over the road
    let s = Scene::generate(&SceneSpec::paper_area(2), 1);
    let w = world(&s, 50.0, -20.0, 30.0);
    assert_eq!(
        s.first_hit(&w, &Vector3::new(0.0, 0.0, -1.0), Epoch::Aerial)
            .unwrap()
            .surface,
        SurfaceKind::Water
    );
    assert!(s
        .checkpoint_candidates()
        .iter()
        .all(|(k, _)| k == "manhole_centre"));
    let s = Scene::generate(&SceneSpec::paper_area(1), 1);
    let mut tree = 0;
    for i in 0..190 {
        let o = world(&s, 5.0 + i as f64, -1.2, 40.0);
        if s.first_hit(&o, &Vector3::new(0.0, 0.0, -1.0), Epoch::Aerial)
            .unwrap()
            .surface
            == SurfaceKind::Tree
        {
            tree += 1;
        }
    }
    assert!(tree > 40, "area 1: road under trees ({tree}/190)");
}

#[test]
fn scene_is_send_and_sync_and_kerb_faces_are_hit() {
    fn assert_send_sync<T: Send + Sync>() {}
    assert_send_sync::<Scene>();
    let s = Scene::generate(&SceneSpec::tiny(), 5);
    let spec = SceneSpec::tiny();
    // a horizontal ray 5 cm above the road edge, across the street, hits the kerb's vertical face
    let x = 15.0;
    let edge = world(&s, x, -(spec.road_half_width_m - 0.001), 0.0);
    let z = s.ground_height_m(edge.x, edge.y) + 0.05;
    let o = world(&s, x, 0.0, z);
    let h = s
        .first_hit(&o, &local_dir(&s, 0.0, -1.0, 0.0), Epoch::MobileMapping)
        .unwrap();
    assert_eq!(h.surface, SurfaceKind::Kerb);
    assert!((h.distance_m - spec.road_half_width_m).abs() < 1e-6);
    let n_local = s.world_to_local_xy([
        h.normal_world.x + s.origin_world()[0],
        h.normal_world.y + s.origin_world()[1],
    ]);
    assert!(
        (n_local[1] - 1.0).abs() < 1e-9,
        "kerb face faces the road: {n_local:?}"
    );
}

#[test]
fn paper_area_3_has_far_facades() {
    let spec = SceneSpec::paper_area(3);
    let s = Scene::generate(&spec, 2);
    let min_q = spec.road_half_width_m + spec.sidewalk_width_m + spec.setback_m[0];
    let main_street: Vec<_> = s
        .buildings()
        .iter()
        .filter(|b| b.front_normal_local[1].abs() > 0.5)
        .collect();
    assert!(!main_street.is_empty());
    for b in main_street {
        let near = b.footprint_min_local[1]
            .abs()
            .min(b.footprint_max_local[1].abs());
        assert!(
            near >= min_q - 1e-9,
            "façade at {near} m, expected ≥ {min_q}"
        );
    }
}
