//! The adjustment with aerial pixel observations in the bundle (`aerial_observations = true`) on a campaign
//! in a projected CRS: run in the campaign's tangent frame it recovers the true recordings and points to
//! < 1 mm; run in map coordinates as if they were Cartesian, the aerial rays of 1000 m carry the map scale and
//! the earth's curvature and pull everything centimetres off.

use nalgebra::Vector3;
use skytie_stages::adjustment::{run, run_in_frame, AdjustConfig, AdjustInputs, AdjustmentRun};
use skytie_stages::campaign::{AerialImage, AerialKind, Recording};
use skytie_stages::correspondence::{
    AerialControlPoint, AerialObservation, MmTiePoint, PanoObservation,
};
use skytie_stages::crs::{CoordinateFrame, MapFrame, MapFrameSpec};
use skytie_stages::geometry::{FrameCamera, PanoramaCamera};

const PANO_SIZE_PX: (u32, u32) = (8000, 4000);

/// Recordings 5 m apart along a street near Utrecht (RD New's scale factor there ≈ 0.99991), the ground
/// points beside them, and three wide-angle nadir frames 1000 m up whose nadirs lie 250–430 m away.
struct Scene {
    frame: MapFrame,
    recordings_true_map: Vec<Vector3<f64>>,
    points_true_map: Vec<Vector3<f64>>,
    aerial: Vec<AerialImage>,
}

fn scene() -> Scene {
    let site = Vector3::new(136_400.0, 455_300.0, 0.0);
    let (spec, note) = MapFrameSpec::for_campaign(
        CoordinateFrame::Projected,
        "EPSG:28992+5709",
        Some([site.x, site.y, site.z]),
    );
    assert!(note.is_none(), "{note:?}");
    let frame = MapFrame::from_spec(&spec).unwrap();
    let recordings_true_map = (0..3)
        .map(|i| site + Vector3::new(5.0 * f64::from(i), 0.0, 2.5))
        .collect();
    let points_true_map = (0..6)
        .map(|k| {
            let side = if k % 2 == 0 { 6.0 } else { -7.0 };
            site + Vector3::new(2.5 * f64::from(k) - 2.0, side, 0.1 * f64::from(k))
        })
        .collect();
    let aerial = [(-400.0, -150.0), (-400.0, 150.0), (-250.0, 0.0)]
        .into_iter()
        .enumerate()
        .map(|(k, (dx, dy))| {
            AerialImage::ideal(
                &format!("n{k}"),
                [site.x + dx, site.y + dy, 1000.0],
                [0.0; 3],
                10_000.0,
                [20_000, 20_000],
            )
        })
        .collect();
    Scene {
        frame,
        recordings_true_map,
        points_true_map,
        aerial,
    }
}

/// The campaign's rows (recordings recorded 0.5 m off) and correspondences: every pixel is the true point
/// seen by the true camera in the tangent frame, which is where the world is Cartesian.
struct Rows {
    recordings: Vec<Recording>,
    tie_points: Vec<MmTiePoint>,
    control: Vec<AerialControlPoint>,
    /// Every recording's panorama size, px.
    sizes: Vec<(u32, u32)>,
}

impl Rows {
    /// The adjustment's inputs: these rows and the scene's nadir frames.
    fn inputs<'a>(&'a self, s: &'a Scene) -> AdjustInputs<'a> {
        AdjustInputs {
            recordings: &self.recordings,
            pano_size_px: &self.sizes,
            pano_detail_level: &[],
            tie_points: &self.tie_points,
            control: &self.control,
            nadir: &s.aerial,
            oblique: &[],
            heights: None,
            tie_point_heights: None,
        }
    }
}

fn rows(s: &Scene) -> Rows {
    let (w, h) = PANO_SIZE_PX;
    let offset = Vector3::new(0.4, -0.3, 0.05);
    let recordings: Vec<Recording> = s
        .recordings_true_map
        .iter()
        .enumerate()
        .map(|(i, c)| {
            let recorded = c + offset;
            Recording::new(
                &format!("p{i}"),
                i as f64,
                [recorded.x, recorded.y, recorded.z],
                90.0,
                2.5,
            )
        })
        .collect();
    let mut tie_points = Vec::new();
    let mut control = Vec::new();
    for (k, p_map) in s.points_true_map.iter().enumerate() {
        let p_local = s.frame.point_to_local(p_map).unwrap();
        let mm: Vec<PanoObservation> = s
            .recordings_true_map
            .iter()
            .enumerate()
            .map(|(i, c)| {
                let truth = PanoramaCamera::new(w, h, *c, 0.0, 0.0, 0.0);
                let camera = s.frame.panorama_to_local(&truth).unwrap();
                let (u_px, v_px) = camera.project_world(&p_local).unwrap();
                PanoObservation {
                    image_id: format!("p{i}"),
                    u_px,
                    v_px,
                }
            })
            .collect();
        let aerial: Vec<AerialObservation> = s
            .aerial
            .iter()
            .map(|row| {
                let camera = s
                    .frame
                    .camera_to_local(&FrameCamera::from_aerial(row))
                    .unwrap();
                let (u_px, v_px) = camera.project_world(&p_local).unwrap();
                AerialObservation {
                    image_id: row.image_id.clone(),
                    kind: AerialKind::Nadir,
                    u_px,
                    v_px,
                    score: 1.0,
                    sigma_px: None,
                }
            })
            .collect();
        let id = format!("t{k}");
        let initial = p_map + offset;
        tie_points.push(MmTiePoint {
            id: id.clone(),
            observations: mm.clone(),
            point_world: initial.into(),
            covariance_m2: [[1e-4, 0.0, 0.0], [0.0, 1e-4, 0.0], [0.0, 0.0, 1e-4]],
            max_angle_deg: 60.0,
        });
        control.push(AerialControlPoint {
            tie_point_id: id,
            mm,
            aerial,
            point_world: Some((*p_map).into()),
            covariance_m2: None,
            map: None,
            ray_ground: None,
        });
    }
    Rows {
        sizes: vec![PANO_SIZE_PX; recordings.len()],
        recordings,
        tie_points,
        control,
    }
}

/// Largest distance (m) of the adjusted recordings and points from the truth, map coordinates.
fn largest_error_m(run: &AdjustmentRun, s: &Scene) -> f64 {
    let recordings = run
        .recordings
        .iter()
        .zip(&s.recordings_true_map)
        .map(|(r, t)| (Vector3::from(r.adjusted_world) - t).norm());
    let points = run
        .points
        .iter()
        .zip(&s.points_true_map)
        .map(|(p, t)| (Vector3::from(p.position_world) - t).norm());
    recordings.chain(points).fold(0.0, f64::max)
}

#[test]
fn aerial_observations_in_the_campaign_frame_are_free_of_map_scale_and_curvature() {
    let s = scene();
    let r = rows(&s);
    let inputs = r.inputs(&s);
    let config = AdjustConfig {
        aerial_observations: true,
        pano_sigma_px: 0.5,
        prior_sigma_xy_m: Some(50.0),
        prior_sigma_z_m: Some(50.0),
        ..AdjustConfig::default()
    };
    let in_frame = run_in_frame(&inputs, &config, &s.frame).unwrap();
    assert_eq!(in_frame.build.aerial_observations, 18);
    assert_eq!(in_frame.build.aerial_observations_skipped, 0);
    let in_map = run(&inputs, &config).unwrap();
    let (e_frame, e_map) = (largest_error_m(&in_frame, &s), largest_error_m(&in_map, &s));
    eprintln!("largest error: tangent frame {e_frame:.2e} m, map coordinates {e_map:.4} m");
    assert!(e_frame < 1e-3, "tangent frame: {e_frame} m");
    assert!(e_map > 0.01, "map coordinates: {e_map} m");
    // The recordings moved from their recorded positions onto the truth.
    for (rec, t) in in_frame.recordings.iter().zip(&s.recordings_true_map) {
        let moved = Vector3::from(rec.adjusted_world) - Vector3::from(rec.recorded_world);
        assert!((moved - (t - Vector3::from(rec.recorded_world))).norm() < 1e-3);
        assert!(rec.sigma_m.iter().all(|v| v.is_finite() && *v > 0.0));
    }
    // The aerial pixels are met to a hundredth of a pixel by the converted solution.
    for (p, cp) in in_frame.points.iter().zip(&r.control) {
        let p_local = s
            .frame
            .point_to_local(&Vector3::from(p.position_world))
            .unwrap();
        for (o, row) in cp.aerial.iter().zip(&s.aerial) {
            let camera = s
                .frame
                .camera_to_local(&FrameCamera::from_aerial(row))
                .unwrap();
            let (u, v) = camera.project_world(&p_local).unwrap();
            assert!((u - o.u_px).hypot(v - o.v_px) < 0.01, "{u} {v} vs {o:?}");
        }
    }
}

#[test]
fn without_aerial_observations_the_frame_changes_nothing() {
    let s = scene();
    let r = rows(&s);
    let inputs = r.inputs(&s);
    let config = AdjustConfig::default();
    assert_eq!(
        run_in_frame(&inputs, &config, &s.frame).unwrap(),
        run(&inputs, &config).unwrap()
    );
}
