//! The interior orientation of a frame camera as the campaign stores it (`aerial/*/cameras.csv`: principal
//! distance and principal point in pixels, continuous pixel coordinates from the top-left image corner,
//! Brown k1…k4, p1, p2 with normalised y up, affinity b1, b2 in pixels), and the exact conversions from and
//! to the vendors' models.
//!
//! - Pix4D perspective model (support article "How are the internal and external camera parameters
//!   defined?"): image y up from the lower-left corner, `x_d = x(1 + R1 r² + R2 r⁴ + R3 r⁶) + 2 T1 x y +
//!   T2 (r² + 2x²)`, `y_d = y(…) + T1 (r² + 2y²) + 2 T2 x y`, focal length and principal point in mm with
//!   the pixel size: k1..k3 = R1..R3, p1 = T1, p2 = T2, `cx = Px/s`, `cy = H − Py/s`.
//! - Metashape frame model (user manual, appendix "Camera models"): camera y down, z forward, `x' = x(1 +
//!   k1 r² + … + k4 r⁸) + p1 (r² + 2x²) + 2 p2 x y`, `y' = y(…) + p2 (r² + 2y²) + 2 p1 x y`, `u = W/2 + cx +
//!   x'(f + b1) + y' b2`, `v = H/2 + cy + y' f` (pixel centres at half-integers). With y up: k's unchanged,
//!   p1 = −p2(Metashape), p2 = p1(Metashape), b1 unchanged, b2 = −b2(Metashape), cx = W/2 + cx(Metashape),
//!   cy = H/2 + cy(Metashape).

use crate::campaign::AerialImage;

/// Interior orientation in the campaign's convention; also the `[aerial.camera]` table of an import
/// configuration (distortion terms optional, default 0).
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CameraModel {
    pub focal_px: f64,
    pub cx_px: f64,
    pub cy_px: f64,
    pub width_px: u32,
    pub height_px: u32,
    #[serde(default)]
    pub k1: f64,
    #[serde(default)]
    pub k2: f64,
    #[serde(default)]
    pub k3: f64,
    #[serde(default)]
    pub k4: f64,
    #[serde(default)]
    pub p1: f64,
    #[serde(default)]
    pub p2: f64,
    #[serde(default)]
    pub b1: f64,
    #[serde(default)]
    pub b2: f64,
}

/// Metashape's calibration values (f, cx, cy in pixels; cx, cy offsets from the image centre).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct MetashapeCalibration {
    pub width_px: u32,
    pub height_px: u32,
    pub f: f64,
    pub cx: f64,
    pub cy: f64,
    pub b1: f64,
    pub b2: f64,
    pub k1: f64,
    pub k2: f64,
    pub k3: f64,
    pub k4: f64,
    pub p1: f64,
    pub p2: f64,
}

/// Pix4D's perspective lens as a `.cam` file states it: focal length and principal point (mm, the principal
/// point from the image's bottom-left corner), radial coefficients R1…R3 (`K1…K3` in the file) and tangential
/// T1, T2.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Pix4dLens {
    pub focal_mm: f64,
    pub px_mm: f64,
    pub py_mm: f64,
    pub r1: f64,
    pub r2: f64,
    pub r3: f64,
    pub t1: f64,
    pub t2: f64,
}

/// Pix4D's internal parameters: the lens (mm) with the pixel size (mm) and the image size.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Pix4dInternals {
    pub lens: Pix4dLens,
    pub pixel_size_mm: f64,
    pub width_px: u32,
    pub height_px: u32,
}

impl CameraModel {
    /// From Metashape's calibration.
    pub fn from_metashape(m: &MetashapeCalibration) -> Self {
        Self {
            focal_px: m.f,
            cx_px: f64::from(m.width_px) / 2.0 + m.cx,
            cy_px: f64::from(m.height_px) / 2.0 + m.cy,
            width_px: m.width_px,
            height_px: m.height_px,
            k1: m.k1,
            k2: m.k2,
            k3: m.k3,
            k4: m.k4,
            p1: -m.p2,
            p2: m.p1,
            b1: m.b1,
            b2: -m.b2,
        }
    }

    /// To Metashape's calibration (exact inverse of [`Self::from_metashape`]).
    pub fn to_metashape(&self) -> MetashapeCalibration {
        MetashapeCalibration {
            width_px: self.width_px,
            height_px: self.height_px,
            f: self.focal_px,
            cx: self.cx_px - f64::from(self.width_px) / 2.0,
            cy: self.cy_px - f64::from(self.height_px) / 2.0,
            b1: self.b1,
            b2: -self.b2,
            k1: self.k1,
            k2: self.k2,
            k3: self.k3,
            k4: self.k4,
            p1: self.p2,
            p2: -self.p1,
        }
    }

    /// From Pix4D's internal parameters; `None` if the model needs what Pix4D's perspective model lacks.
    pub fn from_pix4d(p: &Pix4dInternals) -> Self {
        let (s, lens) = (p.pixel_size_mm, &p.lens);
        Self {
            focal_px: lens.focal_mm / s,
            cx_px: lens.px_mm / s,
            cy_px: f64::from(p.height_px) - lens.py_mm / s,
            width_px: p.width_px,
            height_px: p.height_px,
            k1: lens.r1,
            k2: lens.r2,
            k3: lens.r3,
            k4: 0.0,
            p1: lens.t1,
            p2: lens.t2,
            b1: 0.0,
            b2: 0.0,
        }
    }

    /// To Pix4D's internal parameters with pixel size `pixel_size_mm`; `Err` naming the coefficient Pix4D's
    /// perspective model cannot carry (k4, b1, b2 must be 0).
    pub fn to_pix4d(&self, pixel_size_mm: f64) -> Result<Pix4dInternals, &'static str> {
        for (name, v) in [("k4", self.k4), ("b1", self.b1), ("b2", self.b2)] {
            if v != 0.0 {
                return Err(name);
            }
        }
        Ok(Pix4dInternals {
            lens: Pix4dLens {
                focal_mm: self.focal_px * pixel_size_mm,
                px_mm: self.cx_px * pixel_size_mm,
                py_mm: (f64::from(self.height_px) - self.cy_px) * pixel_size_mm,
                r1: self.k1,
                r2: self.k2,
                r3: self.k3,
                t1: self.p1,
                t2: self.p2,
            },
            pixel_size_mm,
            width_px: self.width_px,
            height_px: self.height_px,
        })
    }

    /// The interior orientation of a campaign row.
    pub fn of_aerial(a: &AerialImage) -> Self {
        Self {
            focal_px: a.focal_px,
            cx_px: a.cx_px,
            cy_px: a.cy_px,
            width_px: a.width_px,
            height_px: a.height_px,
            k1: a.k1,
            k2: a.k2,
            k3: a.k3,
            k4: a.k4,
            p1: a.p1,
            p2: a.p2,
            b1: a.b1,
            b2: a.b2,
        }
    }

    /// Copy into a campaign row.
    pub fn apply_to(&self, a: &mut AerialImage) {
        a.focal_px = self.focal_px;
        a.cx_px = self.cx_px;
        a.cy_px = self.cy_px;
        a.width_px = self.width_px;
        a.height_px = self.height_px;
        a.k1 = self.k1;
        a.k2 = self.k2;
        a.k3 = self.k3;
        a.k4 = self.k4;
        a.p1 = self.p1;
        a.p2 = self.p2;
        a.b1 = self.b1;
        a.b2 = self.b2;
    }
}
