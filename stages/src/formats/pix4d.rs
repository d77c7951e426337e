//! Pix4D exports: the calibrated internal camera parameters file (`*_pix4d_calibrated_internal_camera_
//! parameters.cam`: `F`, `Px`, `Py` in millimetres "assuming a sensor width of W×H mm", radial `K1…K3`,
//! tangential `T1`, `T2`) and, through [`super::opk_list::OpkListFormat::pix4d`], the calibrated external
//! camera parameters list. Followed: Pix4D support articles "How are the internal and external camera
//! parameters defined?" (perspective lens) and the output file descriptions of Pix4Dmapper 4.x.

use super::camera_model::{Pix4dInternals, Pix4dLens};
use crate::campaign::Problem;
use std::path::Path;

/// The values of a `.cam` file.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Pix4dCamFile {
    /// `F`, `Px`, `Py`, `K1…K3`, `T1`, `T2`.
    pub lens: Pix4dLens,
    /// From the comment "assuming a sensor width of W×H mm", if present.
    pub sensor_width_mm: Option<f64>,
    pub sensor_height_mm: Option<f64>,
}

impl Pix4dCamFile {
    /// Internals for images of `width_px` × `height_px`; the pixel size is the sensor width over the image
    /// width (`Err` when the file does not state the sensor width: the millimetres cannot be converted).
    pub fn internals(
        &self,
        path: &Path,
        width_px: u32,
        height_px: u32,
    ) -> Result<Pix4dInternals, Problem> {
        let sensor = self.sensor_width_mm.ok_or_else(|| {
            Problem::error(path, None, Some("F"), "the file does not state the sensor width its millimetres assume", "keep Pix4D's comment line '#Focal Length mm assuming a sensor width of W x H mm', or set sensor_width_mm in the import configuration")
        })?;
        Ok(Pix4dInternals {
            lens: self.lens,
            pixel_size_mm: sensor / f64::from(width_px),
            width_px,
            height_px,
        })
    }
}

/// Read a `.cam` file; every key must appear once with a finite number (K1…K3, T1, T2 default to 0).
pub fn read_pix4d_cam(path: &Path) -> Result<Pix4dCamFile, Vec<Problem>> {
    let text = std::fs::read_to_string(path).map_err(|e| vec![super::unreadable(path, &e)])?;
    let mut cam = Pix4dCamFile::default();
    let mut seen = [false; 3];
    let mut problems = Vec::new();
    for (i, line) in text.lines().enumerate() {
        let t = line.trim();
        if let Some(comment) = t.strip_prefix('#') {
            if let Some((w, h)) = sensor_size(comment) {
                cam.sensor_width_mm = Some(w);
                cam.sensor_height_mm = Some(h);
            }
            continue;
        }
        let mut parts = t.split_whitespace();
        let (Some(key), Some(value), None) = (parts.next(), parts.next(), parts.next()) else {
            continue; // the title line "Pix4D camera calibration file 0" and blank lines
        };
        let slot = match key {
            "F" => &mut cam.lens.focal_mm,
            "Px" => &mut cam.lens.px_mm,
            "Py" => &mut cam.lens.py_mm,
            "K1" => &mut cam.lens.r1,
            "K2" => &mut cam.lens.r2,
            "K3" => &mut cam.lens.r3,
            "T1" => &mut cam.lens.t1,
            "T2" => &mut cam.lens.t2,
            _ => continue,
        };
        match value.parse::<f64>() {
            Ok(v) if v.is_finite() => *slot = v,
            _ => problems.push(Problem::error(
                path,
                Some(i + 1),
                Some(key),
                format!("'{value}' is not a finite number"),
                "write a decimal number with '.' as decimal mark",
            )),
        }
        if let Some(k) = ["F", "Px", "Py"].iter().position(|k| *k == key) {
            seen[k] = true;
        }
    }
    for (k, name) in ["F", "Px", "Py"].iter().enumerate() {
        if !seen[k] {
            problems.push(Problem::error(
                path,
                None,
                Some(name),
                "is missing",
                "this is not a Pix4D internal camera parameters file (.cam) or it is truncated",
            ));
        }
    }
    if cam.lens.focal_mm <= 0.0 && seen[0] {
        problems.push(Problem::error(
            path,
            None,
            Some("F"),
            format!("{} mm is not a focal length", cam.lens.focal_mm),
            "give the focal length in mm, > 0",
        ));
    }
    if problems.is_empty() {
        Ok(cam)
    } else {
        Err(problems)
    }
}

/// "Focal Length mm assuming a sensor width of 12.83x9.62mm" → (12.83, 9.62).
fn sensor_size(comment: &str) -> Option<(f64, f64)> {
    let rest = comment.split("sensor width of").nth(1)?.trim();
    let rest = rest.trim_end_matches("mm").trim();
    let (w, h) = rest.split_once(['x', 'X', '×'])?;
    Some((
        w.trim().parse().ok()?,
        h.trim().trim_end_matches("mm").trim().parse().ok()?,
    ))
}

/// Write a `.cam` file of `p` (sensor size = pixel size × image size).
pub fn write_pix4d_cam(path: &Path, p: &Pix4dInternals) -> std::io::Result<()> {
    let w = p.pixel_size_mm * f64::from(p.width_px);
    let h = p.pixel_size_mm * f64::from(p.height_px);
    let l = &p.lens;
    let text = format!(
        "Pix4D camera calibration file 0\n#Focal Length mm assuming a sensor width of {w}x{h}mm\nF {}\n#Principal Point mm\nPx {}\nPy {}\n#Symmetrical Lens Distortion Coeffs\nK1 {}\nK2 {}\nK3 {}\n#Tangential Lens Distortion Coeffs\nT1 {}\nT2 {}\n",
        l.focal_mm, l.px_mm, l.py_mm, l.r1, l.r2, l.r3, l.t1, l.t2
    );
    crate::fsutil::atomic_write(path, text.as_bytes())
}
