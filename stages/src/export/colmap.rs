//! A COLMAP text model of the adjusted block (`cameras.txt`, `images.txt`, `points3D.txt`) so users can
//! inspect it in COLMAP.
//!
//! Cameras: panoramas use COLMAP's `EQUIRECTANGULAR` model (parameters `w, h`; camera frame x right, y down,
//! z forward; pixel `x = (θ/2π + ½)·w`, `y = (½ − φ/π)·h` with `θ = atan2(x_c, z_c)`, `φ = atan2(−y_c,
//! ‖(x_c, z_c)‖)`), one camera per panorama size. Our panorama frame is (east, north, up) at azimuth 0 /
//! elevation 0 = north (campaign-format.md), so `p_colmap = (p.x, −p.z, p.y)`. Aerial frame cameras (x right,
//! y up, z backwards) become `PINHOLE` (no distortion) or `OPENCV` with `p_colmap = (p.x, −p.y, −p.z)`; the
//! y flip turns our Brown coefficients into OpenCV's as `(k1, k2, −p1, p2)`. Both conventions put the first
//! pixel's centre at (0.5, 0.5), like campaign-format.md, so pixels are written unchanged.
//!
//! Poses: COLMAP stores world→camera `x_cam = R·X + t` as the quaternion (QW, QX, QY, QZ) of R (QW ≥ 0) and t.
//! World coordinates are shifted to a local origin (whole metres near the mean recording centre) so single
//! precision viewers stay exact; the origin and the CRS are written in a comment of every file.
//! Points: determined tie points with their panorama and aerial observations as tracks; ERROR is the mean
//! reprojection error in pixels with the written poses.

use crate::adjustment::AdjustmentRun;
use crate::campaign::{AerialImage, AerialKind, Recording};
use crate::fsutil::atomic_write_with;
use crate::geometry::{FrameCamera, PanoramaCamera};
use nalgebra::{Matrix3, Rotation3, UnitQuaternion, Vector3};
use std::collections::{BTreeMap, HashMap};
use std::io::{self, Write};
use std::path::Path;

/// What was written.
#[derive(Clone, Debug, PartialEq)]
pub struct ColmapExport {
    /// World = local + origin, metres.
    pub origin_world: [f64; 3],
    pub cameras: usize,
    pub images: usize,
    pub points: usize,
}

/// Panorama frame (east, north, up) → COLMAP equirectangular camera frame (right, down, forward).
pub fn pano_to_colmap() -> Matrix3<f64> {
    Matrix3::new(1.0, 0.0, 0.0, 0.0, 0.0, -1.0, 0.0, 1.0, 0.0)
}

/// Our frame-camera frame (x right, y up, z backwards) → COLMAP pinhole frame (right, down, forward).
pub fn frame_to_colmap() -> Matrix3<f64> {
    Matrix3::new(1.0, 0.0, 0.0, 0.0, -1.0, 0.0, 0.0, 0.0, -1.0)
}

/// COLMAP pose of a camera: (QW, QX, QY, QZ) and t for `x_cam = R·(X_world − origin) + t`.
pub fn colmap_pose(
    rotation_world_to_cam: &Matrix3<f64>,
    center_world: &Vector3<f64>,
    origin_world: &Vector3<f64>,
) -> ([f64; 4], [f64; 3]) {
    let q = UnitQuaternion::from_rotation_matrix(&Rotation3::from_matrix(rotation_world_to_cam));
    let mut qv = [q.w, q.i, q.j, q.k];
    if qv[0] < 0.0 {
        qv = qv.map(|v| -v);
    }
    let t = -(rotation_world_to_cam * (center_world - origin_world));
    (qv, t.into())
}

struct Image {
    name: String,
    camera_id: usize,
    q: [f64; 4],
    t: [f64; 3],
    /// (x, y, point3D id)
    points2d: Vec<(f64, f64, usize)>,
}

impl Image {
    /// The image's two lines of `images.txt` (its pose, then its 2-D points), image id `id`.
    fn lines(&self, id: usize) -> String {
        let [qw, qx, qy, qz] = self.q;
        let [tx, ty, tz] = self.t;
        let cells: Vec<String> = self
            .points2d
            .iter()
            .map(|(x, y, p)| format!("{x} {y} {p}"))
            .collect();
        format!(
            "{id} {qw} {qx} {qy} {qz} {tx} {ty} {tz} {} {}\n{}",
            self.camera_id,
            self.name,
            cells.join(" ")
        )
    }
}

fn invalid(message: String) -> io::Error {
    io::Error::new(io::ErrorKind::InvalidInput, message)
}

/// The `cameras.txt` line of aerial camera `cam` with camera id `id`: `PINHOLE` without distortion, else
/// `OPENCV` (or `FULL_OPENCV` with k3); an error for distortion terms no COLMAP model carries.
fn aerial_camera_line(id: usize, cam: &FrameCamera, image_id: &str) -> io::Result<String> {
    let d = cam.distortion;
    if d.k4 != 0.0 || d.a2 != 0.0 {
        return Err(invalid(format!(
            "aerial image '{image_id}' has k4 or b2, which no COLMAP camera model carries; export without them"
        )));
    }
    // b1 scales the u axis only: fx = f + b1 (COLMAP's y points down, hence −p1).
    let fx = cam.focal_px * (1.0 + d.a1);
    let (w, h, f, cx, cy) = (
        cam.width_px,
        cam.height_px,
        cam.focal_px,
        cam.cx_px,
        cam.cy_px,
    );
    Ok(if d.is_zero() {
        format!("{id} PINHOLE {w} {h} {f} {f} {cx} {cy}")
    } else if d.k3 == 0.0 {
        format!(
            "{id} OPENCV {w} {h} {fx} {f} {cx} {cy} {} {} {} {}",
            d.k1, d.k2, -d.p1, d.p2
        )
    } else {
        format!(
            "{id} FULL_OPENCV {w} {h} {fx} {f} {cx} {cy} {} {} {} {} {} 0 0 0",
            d.k1, d.k2, -d.p1, d.p2, d.k3
        )
    })
}

/// The adjustment's aerial images as COLMAP images: each one's camera (appended to `camera_lines`, one camera
/// per image) and its image entry at the adjusted pose.
fn aerial_images(
    run: &AdjustmentRun,
    nadir: &[AerialImage],
    oblique: &[AerialImage],
    origin: &Vector3<f64>,
    camera_lines: &mut Vec<String>,
) -> io::Result<(Vec<FrameCamera>, Vec<Image>)> {
    // First row of each id per kind (as a linear search would find it).
    let mut row_of: HashMap<(bool, &str), &AerialImage> = HashMap::new();
    for (is_nadir, rows) in [(true, nadir), (false, oblique)] {
        for r in rows {
            row_of.entry((is_nadir, r.image_id.as_str())).or_insert(r);
        }
    }
    let mut cams = Vec::with_capacity(run.aerial_images.len());
    let mut images = Vec::with_capacity(run.aerial_images.len());
    for a in &run.aerial_images {
        let is_nadir = matches!(a.kind, AerialKind::Nadir);
        let row = row_of
            .get(&(is_nadir, a.image_id.as_str()))
            .copied()
            .ok_or_else(|| {
                invalid(format!(
                    "aerial image '{}' of the adjustment is not among the aerial rows passed",
                    a.image_id
                ))
            })?;
        let cam = FrameCamera::from_aerial(row);
        let camera_id = camera_lines.len() + 1;
        camera_lines.push(aerial_camera_line(camera_id, &cam, &a.image_id)?);
        let rot = frame_to_colmap() * cam.rotation_cam_to_world.transpose();
        let (q, t) = colmap_pose(&rot, &cam.center_world, origin);
        let folder = match a.kind {
            AerialKind::Nadir => "nadir",
            AerialKind::Oblique => "oblique",
        };
        images.push(Image {
            name: format!("{folder}/{}", row.file),
            camera_id,
            q,
            t,
            points2d: Vec::new(),
        });
        cams.push(cam);
    }
    Ok((cams, images))
}

/// The adjusted cameras of every image, in COLMAP image order (panoramas, then aerial images).
struct PosedCameras<'a> {
    pano: &'a [PanoramaCamera],
    aerial: &'a [FrameCamera],
}

/// The `points3D.txt` line of determined point `p` with point id `id`; its observations are added to the
/// 2-D points of `images` (its track).
fn point_line(
    id: usize,
    p: &crate::adjustment::RunPoint,
    cams: &PosedCameras<'_>,
    images: &mut [Image],
    origin: &Vector3<f64>,
) -> String {
    let n_pano = cams.pano.len();
    let x = Vector3::from(p.position_world);
    let mut track = Vec::new();
    let (mut err_sum, mut err_n) = (0.0, 0usize);
    for &(r, u, v) in &p.point.pano {
        let img = &mut images[r];
        track.push((r + 1, img.points2d.len()));
        img.points2d.push((u, v, id));
        if let Some(e) = pano_reprojection_px(&cams.pano[r], &x, u, v) {
            err_sum += e;
            err_n += 1;
        }
    }
    for &(a, u, v) in &p.point.aerial {
        let img = &mut images[n_pano + a];
        track.push((n_pano + a + 1, img.points2d.len()));
        img.points2d.push((u, v, id));
        if let Some((pu, pv)) = cams.aerial[a].project_world(&x) {
            err_sum += (pu - u).hypot(pv - v);
            err_n += 1;
        }
    }
    let [r, g, b] = super::ply::source_colour(match p.point.kind {
        crate::adjustment::PointKind::Tie => super::ply::PLY_SOURCE_TIE,
        crate::adjustment::PointKind::Control => super::ply::PLY_SOURCE_CONTROL,
        crate::adjustment::PointKind::SingleAerial => super::ply::PLY_SOURCE_SINGLE_AERIAL,
    });
    let local = x - origin;
    let error = if err_n > 0 {
        err_sum / err_n as f64
    } else {
        0.0
    };
    let mut line = format!(
        "{id} {} {} {} {r} {g} {b} {error}",
        local.x, local.y, local.z
    );
    for (image_id, idx) in track {
        line.push_str(&format!(" {image_id} {idx}"));
    }
    line
}

/// Writes one COLMAP text file: `header`, the comment lines `format` describing its entries, their count
/// (`# Number of <what>: N`) and the entries.
fn write_listing(
    path: &Path,
    header: &str,
    format: &[&str],
    what: &str,
    entries: &[String],
) -> io::Result<()> {
    atomic_write_with(path, |w| {
        w.write_all(header.as_bytes())?;
        for l in format {
            writeln!(w, "{l}")?;
        }
        writeln!(w, "# Number of {what}: {}", entries.len())?;
        for e in entries {
            writeln!(w, "{e}")?;
        }
        Ok(())
    })
}

/// One `EQUIRECTANGULAR` camera per panorama size, in order of first appearance: their `cameras.txt` lines
/// and the camera id of each size.
fn panorama_cameras(pano_size_px: &[(u32, u32)]) -> (Vec<String>, BTreeMap<(u32, u32), usize>) {
    let mut lines: Vec<String> = Vec::new();
    let mut id_of: BTreeMap<(u32, u32), usize> = BTreeMap::new();
    for &(w, h) in pano_size_px {
        if let std::collections::btree_map::Entry::Vacant(slot) = id_of.entry((w, h)) {
            let id = lines.len() + 1;
            slot.insert(id);
            lines.push(format!("{id} EQUIRECTANGULAR {w} {h} {w} {h}"));
        }
    }
    (lines, id_of)
}

/// Writes the three files of the model into `dir` (created if missing), each with `header`.
fn write_model_files(
    dir: &Path,
    header: &str,
    cameras: &[String],
    images: &[String],
    points: &[String],
) -> io::Result<()> {
    std::fs::create_dir_all(dir)?;
    write_listing(
        &dir.join("cameras.txt"),
        header,
        &[
            "# Camera list with one line of data per camera:",
            "#   CAMERA_ID, MODEL, WIDTH, HEIGHT, PARAMS[]",
        ],
        "cameras",
        cameras,
    )?;
    write_listing(
        &dir.join("images.txt"),
        header,
        &[
            "# Image list with two lines of data per image:",
            "#   IMAGE_ID, QW, QX, QY, QZ, TX, TY, TZ, CAMERA_ID, NAME",
            "#   POINTS2D[] as (X, Y, POINT3D_ID)",
        ],
        "images",
        images,
    )?;
    write_listing(
        &dir.join("points3D.txt"),
        header,
        &[
            "# 3D point list with one line of data per point:",
            "#   POINT3D_ID, X, Y, Z, R, G, B, ERROR, TRACK[] as (IMAGE_ID, POINT2D_IDX)",
        ],
        "points",
        points,
    )
}

/// Writes `cameras.txt`, `images.txt` and `points3D.txt` into `dir` (created if missing). `recordings` and
/// `pano_size_px` are the run's recordings; `nadir`/`oblique` the aerial rows its aerial images refer to.
pub fn write_colmap_model(
    dir: &Path,
    crs: &str,
    recordings: &[Recording],
    pano_size_px: &[(u32, u32)],
    run: &AdjustmentRun,
    nadir: &[AerialImage],
    oblique: &[AerialImage],
) -> io::Result<ColmapExport> {
    let pano_cams =
        crate::adjustment::campaign_checkpoints::adjusted_cameras(recordings, pano_size_px, run)
            .map_err(invalid)?;
    let n = pano_cams.len().max(1) as f64;
    let mean = pano_cams
        .iter()
        .fold(Vector3::zeros(), |s, c| s + c.center_world)
        / n;
    let origin = mean.map(f64::round);
    let header = format!(
        "# skytie adjusted block; coordinates local: world = local + origin ({}, {}, {}) m, CRS {}\n",
        origin.x,
        origin.y,
        origin.z,
        if crs.is_empty() { "unknown" } else { crs }
    );

    // Cameras: one EQUIRECTANGULAR per panorama size, then one per aerial image.
    let (mut camera_lines, pano_camera_id) = panorama_cameras(pano_size_px);

    // Images: panoramas first (ids 1..), then aerial images.
    let mut images: Vec<Image> = pano_cams
        .iter()
        .zip(recordings)
        .zip(pano_size_px)
        .map(|((cam, r), size)| {
            let rot = pano_to_colmap() * cam.rotation_pano_to_world.transpose();
            let (q, t) = colmap_pose(&rot, &cam.center_world, &origin);
            Image {
                name: r.file.clone(),
                camera_id: pano_camera_id[size],
                q,
                t,
                points2d: Vec::new(),
            }
        })
        .collect();
    let (aerial_cams, aerial) = aerial_images(run, nadir, oblique, &origin, &mut camera_lines)?;
    images.extend(aerial);

    // Points and their tracks.
    let cams = PosedCameras {
        pano: &pano_cams,
        aerial: &aerial_cams,
    };
    let mut point_lines: Vec<String> = Vec::new();
    for p in run.points.iter().filter(|p| p.determined) {
        let id = point_lines.len() + 1;
        point_lines.push(point_line(id, p, &cams, &mut images, &origin));
    }
    let image_lines: Vec<String> = images
        .iter()
        .enumerate()
        .map(|(i, img)| img.lines(i + 1))
        .collect();

    write_model_files(dir, &header, &camera_lines, &image_lines, &point_lines)?;
    Ok(ColmapExport {
        origin_world: origin.into(),
        cameras: camera_lines.len(),
        images: images.len(),
        points: point_lines.len(),
    })
}

/// Pixel distance between an observation and the projection of `x` (u wrapped across the seam).
fn pano_reprojection_px(cam: &PanoramaCamera, x: &Vector3<f64>, u: f64, v: f64) -> Option<f64> {
    let (pu, pv) = cam.project_world(x)?;
    let w = f64::from(cam.width_px);
    let mut du = (pu - u).rem_euclid(w);
    if du > w / 2.0 {
        du -= w;
    }
    Some(du.hypot(pv - v))
}
