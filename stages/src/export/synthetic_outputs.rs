//! Image-free synthetic run results at city scale, for benchmarks and tests of the searches, the export
//! writers and the report: recordings every 5 m along the street grid of
//! [`crate::adjustment::synthetic_streets::route`]
//! with a slowly varying GNSS bias, a block of nadir images over the area and oblique images looking along the
//! four directions, aerial control points beside the road observed in three panoramas and the nadir images that
//! see them (found through [`crate::nadir::footprint_index`]), tie points, check points, and an adjustment
//! result whose adjusted positions are the true ones plus centimetre noise — except one verification segment
//! of `segment_recordings` recordings every `failed_every` recordings, left at the recorded positions so that
//! the adjusted trajectory's verification fails there. No adjustment is solved and no image is rendered: 10⁵
//! recordings generate in seconds. [`write_outputs`] writes a run's output folder from it with the real
//! export writers.

use super::checkpoints::AxisErrors;
use super::gpkg::{run_layers, srs_for, write_geopackage, RunLayers};
use super::{
    write_adjusted_trajectory, write_checkpoint_errors_csv, write_colmap_model,
    write_corrections_csv, write_correspondences_csv, write_ground_control, write_run_geojson,
    write_tie_points_ply, CheckPointRow, CorrectionSeries,
};
use crate::adjustment::from_correspondences::AerialImageRef;
use crate::adjustment::synthetic_streets::route::{drive, recorded_positions, CAMERA_HEIGHT_M};
use crate::adjustment::verify::{verify, write_verification_csv, Verification, VerifyConfig};
use crate::adjustment::{
    AdjustConfig, AdjustmentRun, BlockPoint, PointKind, RunPoint, RunRecording,
};
use crate::campaign::{
    format_time_iso, write_recordings_csv, AerialImage, AerialKind, Campaign, CheckPoint, Recording,
};
use crate::correspondence::{
    AerialControlPoint, AerialObservation, AerialRayGround, PanoObservation,
};
use crate::geometry::{FrameCamera, PanoramaCamera};
use crate::nadir::footprint_index::FootprintIndex;
use crate::rng::SplitMix64;
use nalgebra::Vector3;
use std::io;
use std::path::Path;
use std::time::Instant;

/// Panorama size of the synthetic recordings, pixels.
pub const PANO_SIZE_PX: (u32, u32) = (8000, 4000);

/// What to generate.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct OutputsSpec {
    pub recordings: usize,
    /// One adjusted-verification segment left uncorrected every this many recordings (0: none).
    pub failed_every: usize,
    /// Recordings per verification segment (the verify default).
    pub segment_recordings: usize,
    /// One aerial control point every this many recordings.
    pub control_every: usize,
    /// One check point every this many recordings.
    pub checkpoint_every: usize,
    pub seed: u64,
}

impl Default for OutputsSpec {
    fn default() -> Self {
        Self {
            recordings: 10_000,
            failed_every: 5_000,
            segment_recordings: VerifyConfig::default().segment_recordings,
            control_every: 3,
            checkpoint_every: 100,
            seed: 1,
        }
    }
}

/// The generated results (recordings in time order).
pub struct SyntheticOutputs {
    pub spec: OutputsSpec,
    pub crs: String,
    /// Recorded poses (the campaign's `mm/recordings.csv`).
    pub recordings: Vec<Recording>,
    /// The same rows at the adjusted positions (for the adjusted trajectory's verification).
    pub adjusted: Vec<Recording>,
    pub nadir: Vec<AerialImage>,
    pub oblique: Vec<AerialImage>,
    pub control: Vec<AerialControlPoint>,
    pub checkpoints: Vec<CheckPoint>,
    pub checkpoint_rows: Vec<CheckPointRow>,
    pub run: AdjustmentRun,
}

fn row(id: String, time_s: f64, c: Vector3<f64>, heading_deg: f64) -> Recording {
    Recording {
        time: format_time_iso(time_s).unwrap_or_default(),
        sigma_xy_m: Some(2.0),
        sigma_z_m: Some(2.0),
        ..Recording::new(&id, time_s, [c.x, c.y, c.z], heading_deg, CAMERA_HEIGHT_M)
    }
}

/// Nadir images 500 m above the area of `centers` (0.125 m per pixel, 1600 × 1200 px: 200 m × 150 m), every
/// 80 m east and 60 m north, and oblique images 45° down at every second grid node, looking N, E, S, W in turn.
fn aerial_block(centers: &[Vector3<f64>]) -> (Vec<AerialImage>, Vec<AerialImage>) {
    let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
    for c in centers {
        for k in 0..2 {
            lo[k] = lo[k].min(c[k]);
            hi[k] = hi[k].max(c[k]);
        }
    }
    let (mut nadir, mut oblique) = (Vec::new(), Vec::new());
    let z = 100.0 + 500.0;
    let mut y = lo[1] - 30.0;
    let mut row_k = 0;
    while y <= hi[1] + 30.0 {
        let mut x = lo[0] - 40.0;
        while x <= hi[0] + 40.0 {
            let k = nadir.len();
            let id = format!("nadir_{k:06}");
            nadir.push(AerialImage::ideal(
                &id,
                [x, y, z],
                [0.0, 0.0, 0.0],
                4000.0,
                [1600, 1200],
            ));
            if (k + row_k) % 2 == 0 {
                let look = (k / 2) % 4;
                // ω tilts the view north (look 0), κ turns it: the ground point seen is ~450 m ahead.
                let kappa = [0.0, -90.0, 180.0, 90.0][look];
                let ahead = [[0.0, -450.0], [-450.0, 0.0], [0.0, 450.0], [450.0, 0.0]][look];
                let id = format!("oblique_{:06}", oblique.len());
                oblique.push(AerialImage::ideal(
                    &id,
                    [x + ahead[0], y + ahead[1], 100.0 + 450.0],
                    [45.0, 0.0, kappa],
                    6000.0,
                    [1600, 1200],
                ));
            }
            x += 80.0;
        }
        y += 60.0;
        row_k += 1;
    }
    (nadir, oblique)
}

impl OutputsSpec {
    /// Generates the results (deterministic for a spec).
    pub fn generate(&self) -> SyntheticOutputs {
        let n = self.recordings.max(2);
        let (truth, headings) = drive(n, 100.0, 5.0);
        let recorded = recorded_positions(&truth, 0.8, 100, 0.03, self.seed);
        let mut rng = SplitMix64::new(self.seed ^ 0x5CA1_E0A7);
        let id = |i: usize| format!("rec{i:07}");
        let time = |i: usize| 1_560_506_400.0 + 0.6 * i as f64;
        let recordings: Vec<Recording> = (0..n)
            .map(|i| row(id(i), time(i), recorded[i], headings[i]))
            .collect();
        let seg = self.segment_recordings.max(1);
        let failed = |i: usize| self.failed_every > 0 && (i % self.failed_every) / seg == 1;
        let adjusted_world: Vec<Vector3<f64>> = (0..n)
            .map(|i| {
                if failed(i) {
                    recorded[i]
                } else {
                    truth[i] + Vector3::new(rng.next_gaussian(), rng.next_gaussian(), 0.0) * 0.02
                }
            })
            .collect();
        let adjusted: Vec<Recording> = (0..n)
            .map(|i| row(id(i), time(i), adjusted_world[i], headings[i]))
            .collect();
        let (nadir, oblique) = aerial_block(&truth);
        let (w, h) = PANO_SIZE_PX;
        let true_camera = |i: usize| {
            PanoramaCamera::from_recording(&row(id(i), time(i), truth[i], headings[i]), w, h)
        };
        let footprints = FootprintIndex::new(&nadir, [90.0, 110.0]);
        let nadir_cams: Vec<FrameCamera> = nadir.iter().map(FrameCamera::from_aerial).collect();
        let mut control = Vec::new();
        let mut points = Vec::new();
        for i in (1..n - 1).step_by(self.control_every.max(1)) {
            let right = {
                let hd = headings[i].to_radians();
                Vector3::new(hd.cos(), -hd.sin(), 0.0)
            };
            let p = truth[i] + right * 4.0 - Vector3::new(0.0, 0.0, CAMERA_HEIGHT_M);
            let mut pano = Vec::new();
            for r in i - 1..=i + 1 {
                if let Some((u, v)) = true_camera(r).project_world(&p) {
                    pano.push((
                        r,
                        u + 0.3 * rng.next_gaussian(),
                        v + 0.3 * rng.next_gaussian(),
                    ));
                }
            }
            let mut aerial = Vec::new();
            for a in footprints.candidates([p.x, p.y], [p.x, p.y], [p.z, p.z]) {
                let cam = &nadir_cams[a];
                if let Some((u, v)) = cam.project_world(&p).filter(|&(u, v)| cam.contains(u, v)) {
                    aerial.push((a, u, v));
                }
                if aerial.len() == 3 {
                    break;
                }
            }
            let point_world =
                p + Vector3::new(rng.next_gaussian(), rng.next_gaussian(), 0.0) * 0.03;
            let tie_id = format!("{}#0", id(i));
            control.push(AerialControlPoint {
                tie_point_id: tie_id.clone(),
                mm: pano
                    .iter()
                    .map(|&(r, u, v)| PanoObservation {
                        image_id: id(r),
                        u_px: u,
                        v_px: v,
                    })
                    .collect(),
                aerial: aerial
                    .iter()
                    .map(|&(a, u, v)| AerialObservation {
                        image_id: nadir[a].image_id.clone(),
                        kind: AerialKind::Nadir,
                        u_px: u,
                        v_px: v,
                        score: 0.9,
                        sigma_px: None,
                    })
                    .collect(),
                point_world: (aerial.len() >= 2).then(|| point_world.into()),
                covariance_m2: (aerial.len() >= 2).then_some([
                    [0.0025, 0.0, 0.0],
                    [0.0, 0.0025, 0.0],
                    [0.0, 0.0, 0.04],
                ]),
                map: None,
                ray_ground: match aerial.as_slice() {
                    &[(a, u, v)] => AerialRayGround::from_ray(
                        &nadir_cams[a].pixel_ray(u, v),
                        point_world.z,
                        0.05,
                    ),
                    _ => None,
                },
            });
            points.push(RunPoint {
                point: BlockPoint {
                    id: tie_id,
                    kind: if aerial.len() >= 2 {
                        PointKind::Control
                    } else {
                        PointKind::SingleAerial
                    },
                    pano,
                    aerial,
                },
                position_world: p.into(),
                determined: true,
                control_rejected: false,
            });
        }
        let mut checkpoints = Vec::new();
        let mut checkpoint_rows = Vec::new();
        for i in (self.checkpoint_every / 2..n).step_by(self.checkpoint_every.max(1)) {
            let c = truth[i] - Vector3::new(0.0, 0.0, CAMERA_HEIGHT_M);
            let point_id = format!("cp{i:07}");
            checkpoints.push(CheckPoint {
                point_id: point_id.clone(),
                x: c.x,
                y: c.y,
                z: c.z,
                sigma_xy_m: Some(0.02),
                sigma_z_m: Some(0.03),
            });
            let before = recorded[i] - truth[i];
            let after = adjusted_world[i] - truth[i];
            checkpoint_rows.push(CheckPointRow {
                point_id,
                before: Some(AxisErrors {
                    views: 4,
                    error_m: before.into(),
                }),
                after: Some(AxisErrors {
                    views: 4,
                    error_m: after.into(),
                }),
                note: String::new(),
            });
        }
        let run = AdjustmentRun {
            config: AdjustConfig::default(),
            recordings: (0..n)
                .map(|i| RunRecording {
                    image_id: id(i),
                    recorded_world: recorded[i].into(),
                    adjusted_world: adjusted_world[i].into(),
                    yaw_correction_deg: 0.0,
                    sigma_m: [0.03, 0.03, 0.05],
                    sigma_yaw_deg: 0.0,
                    sigma_is_a_posteriori: true,
                    held: Default::default(),
                })
                .collect(),
            points,
            aerial_images: nadir
                .iter()
                .map(|a| AerialImageRef {
                    kind: AerialKind::Nadir,
                    image_id: a.image_id.clone(),
                })
                .collect(),
            iterations: 5,
            termination: "CostChange".to_string(),
            observations: Default::default(),
            rejected: Default::default(),
            rejected_total: 0,
            final_cost: 0.0,
            variance_factor: Some(1.0),
            redundancy: 1,
            rejection_rounds: 0,
            build: Default::default(),
            relative_sigma: Default::default(),
            yaw_chains: Vec::new(),
        };
        SyntheticOutputs {
            spec: *self,
            crs: "EPSG:28992".to_string(),
            recordings,
            adjusted,
            nadir,
            oblique,
            control,
            checkpoints,
            checkpoint_rows,
            run,
        }
    }
}

impl SyntheticOutputs {
    /// The verification of the recorded (`adjusted` false) or adjusted trajectory with the verify defaults.
    pub fn verification(&self, adjusted: bool) -> Result<Verification, String> {
        let rows = if adjusted {
            &self.adjusted
        } else {
            &self.recordings
        };
        let config = VerifyConfig {
            segment_recordings: self.spec.segment_recordings,
            ..VerifyConfig::default()
        };
        verify(
            rows,
            &vec![PANO_SIZE_PX; rows.len()],
            &self.control,
            &config,
        )
    }

    /// The campaign these results belong to, rooted at `root` (no images).
    pub fn campaign(&self, root: &Path) -> Campaign {
        Campaign {
            root: root.to_path_buf(),
            name: format!("synthetic city, {} recordings", self.recordings.len()),
            crs: self.crs.clone(),
            // The synthetic street grid is a Cartesian scene labelled with a CRS.
            frame: crate::crs::CoordinateFrame::Cartesian,
            recordings: self.recordings.clone(),
            nadir: self.nadir.clone(),
            oblique: self.oblique.clone(),
            checkpoints: self.checkpoints.clone(),
            observations: Vec::new(),
            orthophoto: None,
            dtm: None,
        }
    }
}

/// Seconds taken by each file (or folder) written by [`write_outputs`], in writing order.
pub type WriteTimes = Vec<(&'static str, f64)>;

/// Writes a run's output folder `out` for `s` with the export writers (`campaign/mm/recordings.csv` goes into
/// `campaign`), plus a `metrics.json` with the sections the report reads. Returns the time of each writer.
pub fn write_outputs(s: &SyntheticOutputs, campaign: &Path, out: &Path) -> io::Result<WriteTimes> {
    std::fs::create_dir_all(campaign.join("mm"))?;
    std::fs::create_dir_all(out)?;
    let mut times: WriteTimes = Vec::new();
    let mut timed = |name: &'static str, f: &mut dyn FnMut() -> io::Result<()>| {
        let t0 = Instant::now();
        let r = f();
        times.push((name, t0.elapsed().as_secs_f64()));
        r
    };
    let input = campaign.join("mm/recordings.csv");
    timed("recordings.csv (campaign)", &mut || {
        write_recordings_csv(&input, &s.recordings)
    })?;
    let mut verification = None;
    let mut verification_adjusted = None;
    timed("verification (recorded poses)", &mut || {
        verification = Some(s.verification(false).map_err(io::Error::other)?);
        Ok(())
    })?;
    timed("verification (adjusted poses)", &mut || {
        verification_adjusted = Some(s.verification(true).map_err(io::Error::other)?);
        Ok(())
    })?;
    let (v, va) = (
        verification.expect("set"),
        verification_adjusted.expect("set"),
    );
    let groups: [(&str, &[AerialControlPoint]); 2] = [("nadir", &s.control), ("oblique", &[])];
    timed("correspondences.csv", &mut || {
        write_correspondences_csv(&out.join("correspondences.csv"), &groups, Some(&s.run))
    })?;
    timed("verification.csv", &mut || {
        write_verification_csv(&out.join("verification.csv"), &v)
    })?;
    timed("verification_adjusted.csv", &mut || {
        write_verification_csv(&out.join("verification_adjusted.csv"), &va)
    })?;
    let mut series = None;
    timed("corrections.csv", &mut || {
        let made = CorrectionSeries::from_run(&s.recordings, &s.run)?;
        write_corrections_csv(&out.join("corrections.csv"), &made)?;
        series = Some(made);
        Ok(())
    })?;
    let series = series.expect("set");
    timed("trajectory_adjusted.csv", &mut || {
        write_adjusted_trajectory(
            &out.join("trajectory_adjusted.csv"),
            &input,
            &series,
            &s.run,
        )
        .map(|_| ())
    })?;
    timed("checkpoints.csv", &mut || {
        write_checkpoint_errors_csv(&out.join("checkpoints.csv"), &s.checkpoint_rows)
    })?;
    timed("trajectory.geojson", &mut || {
        write_run_geojson(
            &out.join("trajectory.geojson"),
            &s.crs,
            &s.recordings,
            &s.run,
            &s.checkpoints,
            &s.checkpoint_rows,
            Some(&v),
        )
    })?;
    timed("tie_points.ply", &mut || {
        write_tie_points_ply(&out.join("tie_points.ply"), &s.run)
    })?;
    let c = s.campaign(campaign);
    timed("ground_control/", &mut || {
        write_ground_control(&out.join("ground_control"), &c, &groups, Some(&s.run)).map(|_| ())
    })?;
    timed("skytie.gpkg", &mut || {
        let layers = RunLayers {
            recordings: &s.recordings,
            run: &s.run,
            series: &series,
            checkpoints: &s.checkpoints,
            checkpoint_rows: &s.checkpoint_rows,
            control: &groups,
            verification: Some(&v),
            verification_adjusted: Some(&va),
        };
        let srs = srs_for(&s.crs).unwrap_or_else(|(srs, _)| srs);
        write_geopackage(
            &out.join("skytie.gpkg"),
            &srs,
            &run_layers(&layers),
            "2019-06-14T10:00:00.000Z",
        )
    })?;
    timed("colmap/", &mut || {
        let sizes = vec![PANO_SIZE_PX; s.recordings.len()];
        write_colmap_model(
            &out.join("colmap"),
            &s.crs,
            &s.recordings,
            &sizes,
            &s.run,
            &s.nadir,
            &s.oblique,
        )
        .map(|_| ())
    })?;
    timed("metrics.json", &mut || {
        let text = serde_json::to_string_pretty(&metrics(s, &v, &va)).map_err(io::Error::other)?;
        crate::fsutil::atomic_write(&out.join("metrics.json"), text.as_bytes())
    })?;
    Ok(times)
}

/// The `metrics.json` sections the report reads (campaign, adjustment check points and verdict, verification).
fn metrics(s: &SyntheticOutputs, v: &Verification, va: &Verification) -> serde_json::Value {
    let rms = |f: &dyn Fn(&CheckPointRow) -> Option<[f64; 3]>, k: &[usize]| {
        let e: Vec<f64> = s
            .checkpoint_rows
            .iter()
            .filter_map(f)
            .map(|e| k.iter().map(|&i| e[i] * e[i]).sum::<f64>())
            .collect();
        (e.iter().sum::<f64>() / e.len().max(1) as f64).sqrt()
    };
    let side = |after: bool| {
        let f = move |r: &CheckPointRow| if after { r.after } else { r.before }.map(|e| e.error_m);
        serde_json::json!({
            "count": s.checkpoint_rows.len(),
            "x": rms(&f, &[0]), "y": rms(&f, &[1]), "z": rms(&f, &[2]),
            "2d": rms(&f, &[0, 1]), "3d": rms(&f, &[0, 1, 2]),
        })
    };
    let failed = |v: &Verification| {
        v.segments
            .iter()
            .filter(|s| s.status.label() == "fail")
            .count()
    };
    serde_json::json!({
        "campaign": {
            "name": format!("synthetic city, {} recordings", s.recordings.len()),
            "recordings": s.recordings.len(),
            "nadir_images": s.nadir.len(),
            "oblique_images": s.oblique.len(),
            "checkpoints": s.checkpoints.len(),
        },
        "adjust": {"nadir": {
            "verdict": "corrected",
            "checkpoints": {"before": side(false), "after": side(true)},
        }},
        "verify": {
            "passed": v.passed(),
            "segments": v.segments.len(),
            "segments_failed": failed(v),
        },
        "verify_adjusted": {
            "passed": va.passed(),
            "segments": va.segments.len(),
            "segments_failed": failed(va),
        },
    })
}
