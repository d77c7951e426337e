//! Orientation lists: one row per image with its projection centre and three attitude angles, as written by
//! Pix4D (`*_calibrated_external_camera_parameters.txt`: `imageName X Y Z Omega Phi Kappa`, blank-separated,
//! degrees), Metashape (Omega-Phi-Kappa export: a `# Cameras (N)` comment, a commented header `PhotoID, X, Y,
//! Z, Omega, Phi, Kappa, r11, …, r33`, tab-separated rows, degrees) and classical AT packages (any column
//! layout, declared by the user: delimiter, header or not, column names or 1-based positions, degrees or gon,
//! ω-φ-κ or yaw-pitch-roll).
//!
//! Where a file also carries the rotation matrix (Metashape's r11…r33), it must agree with the angles, as the
//! camera→world matrix or its transpose; a file where it does not is refused, never guessed.

use super::angles::{AngleUnit, AttitudeConvention};
use super::text_table::{Delimiter, RowReader, TextTable};
use crate::campaign::Problem;
use nalgebra::Matrix3;
use serde::{Deserialize, Serialize};
use std::path::Path;

/// The layout of an orientation list.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct OpkListFormat {
    pub delimiter: Delimiter,
    /// The first non-comment line is a header.
    #[serde(default = "yes")]
    pub header: bool,
    /// The header is the last comment line before the data (Metashape).
    #[serde(default)]
    pub comment_header: bool,
    pub angle_unit: AngleUnit,
    pub attitude: AttitudeConvention,
    pub columns: OpkColumns,
}

fn yes() -> bool {
    true
}

/// Column names (header names, case-insensitive) or 1-based positions.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct OpkColumns {
    pub image: String,
    pub x: String,
    pub y: String,
    pub z: String,
    /// ω, φ, κ or yaw, pitch, roll, in that order.
    pub angles: [String; 3],
    /// Optional r11…r33 (row-major) to check the angles against.
    #[serde(default)]
    pub matrix: Option<[String; 9]>,
}

impl OpkListFormat {
    /// Pix4D `*_calibrated_external_camera_parameters.txt`.
    pub fn pix4d() -> Self {
        Self {
            delimiter: Delimiter::Whitespace,
            header: true,
            comment_header: false,
            angle_unit: AngleUnit::Degrees,
            attitude: AttitudeConvention::OmegaPhiKappa,
            columns: OpkColumns {
                image: "imagename".into(),
                x: "x".into(),
                y: "y".into(),
                z: "z".into(),
                angles: ["omega".into(), "phi".into(), "kappa".into()],
                matrix: None,
            },
        }
    }

    /// Metashape "Omega Phi Kappa" text export.
    /// A classical aerial-triangulation list: semicolons, no header, gon, yaw-pitch-roll, columns by
    /// position (image, X, Y, Z, yaw, pitch, roll).
    pub fn at_list() -> Self {
        Self {
            delimiter: Delimiter::Semicolon,
            header: false,
            comment_header: false,
            angle_unit: AngleUnit::Gon,
            attitude: AttitudeConvention::YawPitchRoll,
            columns: OpkColumns {
                image: "1".into(),
                x: "2".into(),
                y: "3".into(),
                z: "4".into(),
                angles: ["5".into(), "6".into(), "7".into()],
                matrix: None,
            },
        }
    }

    pub fn metashape() -> Self {
        let r = |i: usize, j: usize| format!("r{i}{j}");
        Self {
            delimiter: Delimiter::Tab,
            header: false,
            comment_header: true,
            angle_unit: AngleUnit::Degrees,
            attitude: AttitudeConvention::OmegaPhiKappa,
            columns: OpkColumns {
                image: "photoid".into(),
                x: "x".into(),
                y: "y".into(),
                z: "z".into(),
                angles: ["omega".into(), "phi".into(), "kappa".into()],
                matrix: Some([
                    r(1, 1),
                    r(1, 2),
                    r(1, 3),
                    r(2, 1),
                    r(2, 2),
                    r(2, 3),
                    r(3, 1),
                    r(3, 2),
                    r(3, 3),
                ]),
            },
        }
    }
}

/// One image's pose as read (coordinates in the file's CRS, native order: easting/northing or
/// latitude/longitude).
#[derive(Debug, Clone, PartialEq)]
pub struct PoseRow {
    pub line: usize,
    pub image: String,
    pub a: f64,
    pub b: f64,
    pub z: f64,
    /// Camera→world rotation in the file's frame (skytie camera axes).
    pub rotation: Matrix3<f64>,
}

/// Largest difference between a file's matrix and the one of its angles (angles printed to ≈ 1e-6°).
const MATRIX_TOLERANCE: f64 = 1e-5;

/// Read an orientation list; rows with a problem are left out and reported.
pub fn read_opk_list(path: &Path, format: &OpkListFormat) -> (Vec<PoseRow>, Vec<Problem>) {
    let table = match TextTable::read(path, format.delimiter, format.header, format.comment_header)
    {
        Ok(t) => t,
        Err(p) => return (Vec::new(), vec![p]),
    };
    let c = &format.columns;
    let names = format.attitude.names();
    let mut problems = Vec::new();
    let mut col = |name: &str| match table.column(name) {
        Ok(i) => Some(i),
        Err(p) => {
            problems.push(p);
            None
        }
    };
    let cols = [
        &c.image,
        &c.x,
        &c.y,
        &c.z,
        &c.angles[0],
        &c.angles[1],
        &c.angles[2],
    ]
    .map(|n| col(n));
    let matrix_cols: Option<Vec<Option<usize>>> = c
        .matrix
        .as_ref()
        .map(|m| m.iter().map(|n| col(n)).collect());
    let (Some(image), Some(x), Some(y), Some(z), Some(a1), Some(a2), Some(a3)) = (
        cols[0], cols[1], cols[2], cols[3], cols[4], cols[5], cols[6],
    ) else {
        return (Vec::new(), problems);
    };
    if matrix_cols
        .as_ref()
        .is_some_and(|m| m.iter().any(Option::is_none))
    {
        return (Vec::new(), problems);
    }
    let mut rows = Vec::new();
    for (line, cells) in &table.rows {
        let mut r = RowReader::new(path, *line, cells);
        let id = r.text(image, &c.image);
        let (xa, yb, zz) = (r.number(x, &c.x), r.number(y, &c.y), r.number(z, &c.z));
        let angles = [(a1, 0), (a2, 1), (a3, 2)].map(|(i, k)| {
            let v = r.number(i, &c.angles[k]);
            format.angle_unit.to_degrees(v)
        });
        for (k, v) in angles.iter().enumerate() {
            if v.abs() > 360.0 {
                r.error(
                    &c.angles[k],
                    format!("{} = {v}° lies outside ±360°", names[k]),
                    "check the angle unit (degrees, gon or radians) in the import configuration",
                );
            }
        }
        let rotation = format.attitude.to_matrix(angles[0], angles[1], angles[2]);
        if let (Some(m), true) = (&matrix_cols, r.ok()) {
            let values: Vec<f64> = m
                .iter()
                .zip(c.matrix.as_ref().expect("matrix columns"))
                .map(|(i, n)| r.number(i.expect("checked"), n))
                .collect();
            if r.ok() {
                let file_m = Matrix3::from_row_slice(&values);
                let diff = (file_m - rotation)
                    .abs()
                    .max()
                    .min((file_m - rotation.transpose()).abs().max());
                if diff > MATRIX_TOLERANCE {
                    r.error(&c.matrix.as_ref().expect("matrix")[0], format!("the rotation matrix differs from the matrix of the angles by {diff:.2e} (neither camera→world nor its transpose)"), "check the attitude convention and angle unit; the file's angles and matrix must describe the same rotation");
                }
            }
        }
        if r.ok() {
            rows.push(PoseRow {
                line: *line,
                image: id,
                a: xa,
                b: yb,
                z: zz,
                rotation,
            });
        } else {
            problems.append(&mut r.problems);
        }
    }
    (rows, problems)
}

/// Write an orientation list in `format` (header, or Metashape's comment lines; the matrix, if the format
/// has one, as world→camera, i.e. the transpose of camera→world). Numbers are written in their shortest
/// form that reads back to the same f64.
pub fn write_opk_list(
    path: &Path,
    format: &OpkListFormat,
    rows: &[PoseRow],
) -> std::io::Result<()> {
    let sep = match format.delimiter {
        Delimiter::Comma => ",",
        Delimiter::Semicolon => ";",
        Delimiter::Tab => "\t",
        Delimiter::Whitespace => " ",
    };
    let c = &format.columns;
    let mut header: Vec<String> = vec![c.image.clone(), c.x.clone(), c.y.clone(), c.z.clone()];
    header.extend(c.angles.iter().cloned());
    if let Some(m) = &c.matrix {
        header.extend(m.iter().cloned());
    }
    let mut out = String::new();
    if format.comment_header {
        out.push_str(&format!(
            "# Cameras ({})\n# {}\n",
            rows.len(),
            header.join(", ")
        ));
    } else if format.header {
        out.push_str(&header.join(sep));
        out.push('\n');
    }
    for row in rows {
        let (a, b, cc) = format.attitude.from_matrix(&row.rotation);
        let mut cells = vec![
            row.image.clone(),
            row.a.to_string(),
            row.b.to_string(),
            row.z.to_string(),
        ];
        cells.extend([a, b, cc].map(|v| format.angle_unit.from_degrees(v).to_string()));
        if c.matrix.is_some() {
            let t = row.rotation.transpose();
            for i in 0..3 {
                for j in 0..3 {
                    cells.push(t[(i, j)].to_string());
                }
            }
        }
        out.push_str(&cells.join(sep));
        out.push('\n');
    }
    crate::fsutil::atomic_write(path, out.as_bytes())
}
