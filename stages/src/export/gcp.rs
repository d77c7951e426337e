//! Ground control for downstream photogrammetry: the aerial-triangulated control points (thesis 3.4.5.4,
//! 4.4.7) with their σ and image observations, in the files the tools read — written into `ground_control/`:
//!
//! - `gcp_list.txt` (OpenSfM / OpenDroneMap): a projection line (`EPSG:<code>` or a PROJ string, the
//!   campaign CRS), then one line per image observation `x y z px py image [label]`. Pixel coordinates
//!   follow OpenSfM's convention, where pixel centres lie on integers: `px = u − 0.5`, `py = v − 0.5` from the
//!   campaign's continuous coordinates (first pixel centre at (0.5, 0.5)). Fields are separated by white
//!   space, so an image whose file name contains white space cannot be listed (counted, see [`GcpExport`]).
//! - `metashape_reference.csv` (Agisoft Metashape "Import Reference", columns `nxyzXYZ`: label, x, y, z and
//!   their accuracies) and `metashape_projections.csv` (label, camera label = file name without extension,
//!   file, u, v in Metashape's pixel convention, which is the campaign's: top-left image corner at (0, 0)).
//! - `control_points.csv`: the plain list — label, source, point id, x, y, z, σ per axis, the numbers of
//!   aerial and panorama observations, the adjusted point minus the aerial triangulation (empty when the
//!   adjustment did not determine the point) and the point's `status` ([`ControlStatus`]).
//!
//! Only points with an aerial triangulation (seen in ≥ 2 aerial images) are control; the others are counted
//! in [`GcpExport::skipped_single_aerial`]. Control that the adjustment did not use — its gross-error test
//! rejected an aerial observation of it, or its checks left it out as inconsistent with the neighbouring
//! recordings' control or too weak — is not handed to other tools: it is listed in `control_points.csv` with
//! status `rejected` or `left_out`, counted in [`GcpExport::left_out_by_adjustment`], and kept out of
//! `gcp_list.txt` and the Metashape files. Labels are `<source>_<point id>` with white space replaced by `_`.

use super::control_status::{ControlStatus, ControlStatuses};
use crate::adjustment::AdjustmentRun;
use crate::campaign::{AerialKind, Campaign};
use crate::correspondence::AerialControlPoint;
use crate::fsutil::atomic_write_with;
use skytie_util::csv_out::quote;
use std::collections::HashMap;
use std::io::{self, Write};
use std::path::Path;

/// What [`write_ground_control`] wrote.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct GcpExport {
    /// Control points in the tools' files (`gcp_list.txt`, the Metashape files).
    pub points: usize,
    /// Their image observations.
    pub observations: usize,
    /// Control points the adjustment left out or rejected: listed in `control_points.csv` only.
    pub left_out_by_adjustment: usize,
    pub skipped_single_aerial: usize,
    /// Observations left out because their image is not in the campaign.
    pub skipped_unknown_image: usize,
    /// Observations left out of `gcp_list.txt` because the image's file name contains white space (the
    /// format separates fields by white space; OpenSfM takes the first word as the image name).
    pub gcp_list_skipped_names: usize,
    /// Why `gcp_list.txt` was not written (its projection line needs a known CRS).
    pub gcp_list_skipped: Option<String>,
}

/// One control point ready for the writers.
pub(crate) struct Gcp<'a> {
    pub(crate) label: String,
    pub(crate) source: &'a str,
    pub(crate) point: &'a AerialControlPoint,
    pub(crate) xyz: [f64; 3],
    pub(crate) sigma: [f64; 3],
    /// (file name, u, v) per observation, panorama observations first.
    observations: Vec<(&'a str, f64, f64)>,
}

/// The projection line of `gcp_list.txt` for a campaign CRS, or why there is none.
pub fn opensfm_projection(crs: &str) -> Result<String, String> {
    let c = crs.trim();
    let epsg = c
        .strip_prefix("EPSG:")
        .or_else(|| c.strip_prefix("epsg:"))
        .filter(|code| !code.is_empty() && code.bytes().all(|b| b.is_ascii_digit()));
    if let Some(code) = epsg {
        return Ok(format!("EPSG:{code}"));
    }
    if c.contains("+proj") {
        return Ok(c.to_string());
    }
    Err(format!(
        "campaign crs '{crs}' is neither EPSG:<code> nor a PROJ string; set crs in campaign.toml"
    ))
}

fn label(source: &str, id: &str) -> String {
    format!("{source}_{id}")
        .chars()
        .map(|c| if c.is_whitespace() { '_' } else { c })
        .collect()
}

/// The control points of `groups` with an aerial triangulation, labelled, with their observations' files.
pub(crate) fn collect<'a>(
    campaign: &'a Campaign,
    groups: &[(&'a str, &'a [AerialControlPoint])],
    out: &mut GcpExport,
) -> Vec<Gcp<'a>> {
    let panos: HashMap<&str, &str> = campaign
        .recordings
        .iter()
        .map(|r| (r.image_id.as_str(), r.file.as_str()))
        .collect();
    let aerial = |kind: AerialKind| -> HashMap<&'a str, &'a str> {
        let list = match kind {
            AerialKind::Nadir => &campaign.nadir,
            AerialKind::Oblique => &campaign.oblique,
        };
        list.iter()
            .map(|a| (a.image_id.as_str(), a.file.as_str()))
            .collect()
    };
    let (nadir, oblique) = (aerial(AerialKind::Nadir), aerial(AerialKind::Oblique));
    let mut gcps = Vec::new();
    for &(source, points) in groups {
        for p in points {
            let Some(xyz) = p.point_world else {
                out.skipped_single_aerial += 1;
                continue;
            };
            let sigma = p
                .covariance_m2
                .map_or([0.0; 3], |c| [0, 1, 2].map(|k| c[k][k].max(0.0).sqrt()));
            let mut observations = Vec::new();
            for o in &p.mm {
                match panos.get(o.image_id.as_str()) {
                    Some(f) => observations.push((*f, o.u_px, o.v_px)),
                    None => out.skipped_unknown_image += 1,
                }
            }
            for o in &p.aerial {
                let files = match o.kind {
                    AerialKind::Nadir => &nadir,
                    AerialKind::Oblique => &oblique,
                };
                match files.get(o.image_id.as_str()) {
                    Some(f) => observations.push((*f, o.u_px, o.v_px)),
                    None => out.skipped_unknown_image += 1,
                }
            }
            out.points += 1;
            out.observations += observations.len();
            gcps.push(Gcp {
                label: label(source, &p.tie_point_id),
                source,
                point: p,
                xyz,
                sigma,
                observations,
            });
        }
    }
    gcps
}

/// Writes the files of the module doc into `dir` (created when missing). `groups` are (source label,
/// control points); `run` (optional) gives each point's status — only used control goes into the tools'
/// files — and the residuals of `control_points.csv`.
pub fn write_ground_control(
    dir: &Path,
    campaign: &Campaign,
    groups: &[(&str, &[AerialControlPoint])],
    run: Option<&AdjustmentRun>,
) -> io::Result<GcpExport> {
    std::fs::create_dir_all(dir)?;
    let mut out = GcpExport::default();
    let gcps = collect(campaign, groups, &mut out);
    let statuses = ControlStatuses::of(run);
    let status: Vec<ControlStatus> = gcps
        .iter()
        .map(|g| statuses.get(&g.point.tie_point_id))
        .collect();
    let delivered: Vec<&Gcp<'_>> = gcps
        .iter()
        .zip(&status)
        .filter(|(_, s)| s.delivered())
        .map(|(g, _)| g)
        .collect();
    out.left_out_by_adjustment = gcps.len() - delivered.len();
    out.points = delivered.len();
    out.observations = delivered.iter().map(|g| g.observations.len()).sum();
    match opensfm_projection(&campaign.crs) {
        Ok(projection) => {
            out.gcp_list_skipped_names =
                write_gcp_list(&dir.join("gcp_list.txt"), &projection, &delivered)?
        }
        Err(why) => out.gcp_list_skipped = Some(why),
    }
    write_metashape(dir, &delivered)?;
    write_point_list(&dir.join("control_points.csv"), &gcps, &status, run)?;
    Ok(out)
}

/// Returns the number of observations left out for a file name with white space.
fn write_gcp_list(path: &Path, projection: &str, gcps: &[&Gcp<'_>]) -> io::Result<usize> {
    let mut skipped = 0;
    atomic_write_with(path, |w| {
        skipped = 0;
        writeln!(w, "{projection}")?;
        for g in gcps {
            let [x, y, z] = g.xyz;
            for &(file, u, v) in &g.observations {
                if file.contains(char::is_whitespace) {
                    skipped += 1;
                    continue;
                }
                writeln!(w, "{x} {y} {z} {} {} {file} {}", u - 0.5, v - 0.5, g.label)?;
            }
        }
        Ok(())
    })?;
    Ok(skipped)
}

fn file_stem(file: &str) -> &str {
    let name = file.rsplit(['/', '\\']).next().unwrap_or(file);
    name.rsplit_once('.').map_or(name, |(stem, _)| stem)
}

fn write_metashape(dir: &Path, gcps: &[&Gcp<'_>]) -> io::Result<()> {
    atomic_write_with(&dir.join("metashape_reference.csv"), |w| {
        writeln!(w, "label,x,y,z,sigma_x,sigma_y,sigma_z")?;
        for g in gcps {
            let ([x, y, z], [sx, sy, sz]) = (g.xyz, g.sigma);
            writeln!(w, "{},{x},{y},{z},{sx},{sy},{sz}", quote(&g.label))?;
        }
        Ok(())
    })?;
    atomic_write_with(&dir.join("metashape_projections.csv"), |w| {
        writeln!(w, "label,camera,file,u,v")?;
        for g in gcps {
            for &(file, u, v) in &g.observations {
                writeln!(
                    w,
                    "{},{},{},{u},{v}",
                    quote(&g.label),
                    quote(file_stem(file)),
                    quote(file)
                )?;
            }
        }
        Ok(())
    })
}

fn write_point_list(
    path: &Path,
    gcps: &[Gcp<'_>],
    status: &[ControlStatus],
    run: Option<&AdjustmentRun>,
) -> io::Result<()> {
    let adjusted: HashMap<&str, [f64; 3]> = run
        .map(|r| {
            r.points
                .iter()
                .filter(|p| p.determined)
                .map(|p| (p.point.id.as_str(), p.position_world))
                .collect()
        })
        .unwrap_or_default();
    atomic_write_with(path, |w| {
        writeln!(
            w,
            "label,source,point_id,x,y,z,sigma_x,sigma_y,sigma_z,aerial_observations,panorama_observations,\
             residual_x,residual_y,residual_z,status"
        )?;
        for (g, status) in gcps.iter().zip(status) {
            let ([x, y, z], [sx, sy, sz]) = (g.xyz, g.sigma);
            let residual = adjusted
                .get(g.point.tie_point_id.as_str())
                .map(|a| [0, 1, 2].map(|k| format!("{}", a[k] - g.xyz[k])).join(","))
                .unwrap_or_else(|| ",,".to_string());
            writeln!(
                w,
                "{},{},{},{x},{y},{z},{sx},{sy},{sz},{},{},{residual},{}",
                quote(&g.label),
                g.source,
                quote(&g.point.tie_point_id),
                g.point.aerial.len(),
                g.point.mm.len(),
                status.as_str()
            )?;
        }
        Ok(())
    })
}
