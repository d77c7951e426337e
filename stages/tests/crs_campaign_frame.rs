//! Aerial ray intersection in the campaign's Cartesian frame against the map frame, on a real-earth scene:
//! two aerial cameras 500 m / 1000 m above the ground (60 % base) see a ground point 250 m / 500 m off the
//! nadir. The cameras' poses and the point are expressed in the map CRS exactly as an import of a rigorous
//! aerial triangulation gives them (positions projected, heights reduced by the geoid, attitudes turned by
//! the meridian convergence). Intersected in map coordinates the rays miss the point by the error budget
//! (centimetres: map scale + earth curvature); intersected in [`CampaignFrame`] and converted back they hit
//! it to < 1 mm.

use nalgebra::Vector3;
use skytie_stages::crs::{
    CampaignFrame, Crs, GeoidModel, GridNorth, HorizontalTransform, LocalTangentFrame,
};
use skytie_stages::geometry::{rot_z, triangulate_rays, Ray};

struct Case {
    crs: &'static str,
    lat_deg: f64,
    lon_deg: f64,
    geoid_m: Option<f64>,
}

/// Map-frame and campaign-frame intersection errors (m) of the scene at `case` with flying height `h_m`.
fn errors(case: &Case, flying_m: f64) -> (f64, f64) {
    let crs = Crs::parse(case.crs).unwrap();
    let n = case.geoid_m.unwrap_or(0.0);
    let truth = LocalTangentFrame::new(crs.ellipsoid, case.lat_deg, case.lon_deg, n);
    let to_map = HorizontalTransform::from_own_geographic(&crs);
    let grid = GridNorth::new(&crs).unwrap();
    let map_of = |p: &Vector3<f64>| {
        let (lat, lon, h) = truth.to_geodetic(p);
        let (e, nn) = to_map.apply(lat, lon).unwrap();
        (Vector3::new(e, nn, h - n), lat, lon)
    };
    // The ground point: 0.5·H east and 0.2·H north of the nadir, on the geoid (H = 0).
    let (g_lat, g_lon, _) = truth.to_geodetic(&Vector3::new(0.5 * flying_m, 0.2 * flying_m, 0.0));
    let p_true = truth.from_geodetic(g_lat, g_lon, n);
    let (p_map, _, _) = map_of(&p_true);
    let mut map_rays = Vec::new();
    for x in [-0.3 * flying_m, 0.3 * flying_m] {
        let c = Vector3::new(x, 0.0, flying_m);
        let (c_map, lat, lon) = map_of(&c);
        let d_enu_c = truth.enu_at(lat, lon).transpose() * (p_true - c).normalize();
        let gamma = grid.true_north_grid_azimuth_deg(lat, lon).unwrap();
        map_rays.push(Ray::new(c_map, rot_z(-gamma.to_radians()) * d_enu_c));
    }
    let sigma = [1e-5, 1e-5];
    let in_map = triangulate_rays(&map_rays, &sigma).unwrap().point_world;
    let frame = CampaignFrame::new(
        &crs,
        case.geoid_m
            .map(|s| GeoidModel::Constant { separation_m: s }),
        // Any origin in the area: 800 m away from the scene.
        p_map + Vector3::new(-600.0, 530.0, 12.0),
    )
    .unwrap();
    let local_rays: Vec<Ray> = map_rays
        .iter()
        .map(|r| frame.ray_to_local(r).unwrap())
        .collect();
    let local = triangulate_rays(&local_rays, &sigma).unwrap().point_world;
    let back = frame.point_to_map(&local).unwrap();
    ((in_map - p_map).norm(), (back - p_map).norm())
}

#[test]
fn aerial_intersection_in_the_campaign_frame_removes_scale_and_curvature() {
    let cases = [
        // RD New + NAP near Utrecht (k ≈ 0.99991), constant quasi-geoid.
        Case {
            crs: "EPSG:28992+5709",
            lat_deg: 52.0907,
            lon_deg: 5.1214,
            geoid_m: Some(43.25),
        },
        // ETRS89 / UTM 32N on its central meridian (k = 0.9996), heights without a vertical CRS.
        Case {
            crs: "EPSG:25832",
            lat_deg: 51.0,
            lon_deg: 9.0,
            geoid_m: None,
        },
    ];
    for case in &cases {
        for flying_m in [500.0, 1000.0] {
            let (map_m, local_m) = errors(case, flying_m);
            println!(
                "{} H = {flying_m} m: map frame {:.4} m, campaign frame {:.6} m",
                case.crs, map_m, local_m
            );
            assert!(
                local_m < 1e-3,
                "{} at {flying_m} m: {local_m} m in the campaign frame",
                case.crs
            );
            assert!(
                map_m > 0.01,
                "{} at {flying_m} m: the map-frame error should show ({map_m} m)",
                case.crs
            );
        }
    }
}

#[test]
fn points_and_attitudes_round_trip() {
    let crs = Crs::parse("EPSG:28992+5709").unwrap();
    let frame = CampaignFrame::new(
        &crs,
        Some(GeoidModel::Constant {
            separation_m: 43.25,
        }),
        Vector3::new(136_000.0, 455_000.0, 0.0),
    )
    .unwrap();
    // The origin is the tangent frame's origin.
    let o = frame
        .point_to_local(&Vector3::new(136_000.0, 455_000.0, 0.0))
        .unwrap();
    assert!(o.norm() < 1e-6, "{o}");
    for p in [
        Vector3::new(136_512.25, 454_301.5, 1.75),
        Vector3::new(139_000.0, 458_000.0, 1012.0),
    ] {
        let back = frame
            .point_to_map(&frame.point_to_local(&p).unwrap())
            .unwrap();
        assert!((back - p).norm() < 1e-6, "{p} → {back}");
    }
    // Near the origin the frame is the map frame turned by the convergence: vertical stays vertical.
    let r = frame
        .map_to_local_rotation(&Vector3::new(136_000.0, 455_000.0, 0.0))
        .unwrap();
    assert!((r * Vector3::z() - Vector3::z()).norm() < 1e-9);
    // A synthetic campaign's own frame needs no conversion: `CampaignFrame` is only built for a real CRS.
    assert!(CampaignFrame::new(&Crs::parse("EPSG:4258").unwrap(), None, Vector3::zeros()).is_err());
}
