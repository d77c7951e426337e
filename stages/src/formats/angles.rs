//! Angle units and attitude conventions of orientation lists, each turned into skytie's camera→world
//! rotation (campaign-format.md: camera x right, y up, z backwards; ω = φ = κ = 0 looks straight down with
//! the image top towards grid north).
//!
//! - `omega-phi-kappa`: `R = Rx(ω)·Ry(φ)·Rz(κ)`, the convention of Pix4D's and Metashape's ω-φ-κ exports and
//!   of PATB/BINGO/MATCH-AT lists.
//! - `yaw-pitch-roll`: aircraft angles of the camera, `R = N · Rz(yaw)·Ry(pitch)·Rx(roll) · N` with
//!   `N = [[0,1,0],[1,0,0],[0,0,−1]]` (swaps east/north and flips up/down: the body frame is x forward = image
//!   top, y right = image right, z down = viewing direction; the world frame north-east-down). Yaw turns
//!   clockwise from grid north, pitch raises the image top, roll lowers the image right edge.

use crate::geometry::{opk_to_matrix, rot_x, rot_y, rot_z};
use nalgebra::Matrix3;
use serde::{Deserialize, Serialize};

/// Unit of the angles in a file.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum AngleUnit {
    Degrees,
    /// 400 gon = 360°.
    Gon,
    Radians,
}

impl AngleUnit {
    /// The angle in degrees.
    pub fn to_degrees(self, value: f64) -> f64 {
        match self {
            Self::Degrees => value,
            Self::Gon => value * 0.9,
            Self::Radians => value.to_degrees(),
        }
    }

    /// Degrees to this unit.
    pub fn from_degrees(self, deg: f64) -> f64 {
        match self {
            Self::Degrees => deg,
            Self::Gon => deg / 0.9,
            Self::Radians => deg.to_radians(),
        }
    }
}

/// Which three angles a file gives.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum AttitudeConvention {
    OmegaPhiKappa,
    YawPitchRoll,
}

/// `[[0,1,0],[1,0,0],[0,0,−1]]`: ENU ↔ NED, and camera ↔ body frame (see the module doc).
pub fn swap_xy_flip_z() -> Matrix3<f64> {
    Matrix3::new(0.0, 1.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, -1.0)
}

impl AttitudeConvention {
    /// Camera→world rotation of three angles in degrees (ω, φ, κ or yaw, pitch, roll in that order).
    pub fn to_matrix(self, a_deg: f64, b_deg: f64, c_deg: f64) -> Matrix3<f64> {
        match self {
            Self::OmegaPhiKappa => opk_to_matrix(a_deg, b_deg, c_deg),
            Self::YawPitchRoll => {
                let n = swap_xy_flip_z();
                n * rot_z(a_deg.to_radians())
                    * rot_y(b_deg.to_radians())
                    * rot_x(c_deg.to_radians())
                    * n
            }
        }
    }

    /// The three angles (degrees) of a camera→world rotation.
    pub fn from_matrix(self, r: &Matrix3<f64>) -> (f64, f64, f64) {
        match self {
            Self::OmegaPhiKappa => crate::geometry::matrix_to_opk(r),
            Self::YawPitchRoll => {
                let n = swap_xy_flip_z();
                let b = n * r * n; // = Rz(yaw)·Ry(pitch)·Rx(roll)
                let pitch = (-b[(2, 0)]).clamp(-1.0, 1.0).asin();
                let yaw = b[(1, 0)].atan2(b[(0, 0)]);
                let roll = b[(2, 1)].atan2(b[(2, 2)]);
                (yaw.to_degrees(), pitch.to_degrees(), roll.to_degrees())
            }
        }
    }

    /// Names of the three angles, for messages and default column names.
    pub fn names(self) -> [&'static str; 3] {
        match self {
            Self::OmegaPhiKappa => ["omega", "phi", "kappa"],
            Self::YawPitchRoll => ["yaw", "pitch", "roll"],
        }
    }
}
