//! Writing a run's user-facing files into `OUT/` (or `OUT/variants/<name>/` in a sweep) once the adjustment
//! and verification nodes have produced their values (every file is described in `docs/outputs.md`):
//! `trajectory_adjusted.csv` (the input recordings file with the adjusted values), `corrections.csv` (the
//! correction time series), `sbet_adjusted.out` + `sbet_adjusted_quality.csv` (the corrected SBET of a
//! campaign imported from one), `ground_control/` (control points for OpenSfM/OpenDroneMap, Metashape and as a
//! plain list), `skytie.gpkg` (GeoPackage layers for GIS), `trajectory.geojson`, `tie_points.ply`,
//! `checkpoints.csv`, `verification.csv` and `verification_adjusted.csv`, `correspondences.csv`, a COLMAP
//! text model in `colmap/`, and the adjusted trajectory, corrections and control points in the campaign's
//! second CRS (`epsg_<code>/`, when `campaign.toml` names one in `[outputs]`). The encoders live in `skytie_stages::export`; every file is written atomically.
//! A failed export is a warning naming the file; the run's other outputs are still written.

use crate::nodes::adjust::adjustment::{AdjustReport, Verdict};
use crate::nodes::campaign::load::CampaignSnapshot;
use crate::nodes::oblique::consensus::ObliqueOutput;
use skytie_stages::adjustment::verify::{write_verification_csv, Verification};
use skytie_stages::adjustment::AdjustmentRun;
use skytie_stages::campaign::format_time_iso;
use skytie_stages::campaign::Campaign;
use skytie_stages::correspondence::AerialControlPoint;
use skytie_stages::crs::{OutputsSection, SecondCrs};
use skytie_stages::export::gpkg::{run_layers, srs_for, write_geopackage, RunLayers};
use skytie_stages::export::second_crs_files::{SECOND_CORRECTIONS_CSV, SECOND_TRAJECTORY_CSV};
use skytie_stages::export::{
    write_adjusted_trajectory, write_checkpoint_errors_csv, write_colmap_model,
    write_corrected_sbet, write_corrections_csv, write_correspondences_csv, write_ground_control,
    write_run_geojson, write_second_crs_files, write_tie_points_ply, CorrectionSeries,
    SecondCrsRun, SBET_ADJUSTED, SBET_QUALITY_CSV,
};
use skytie_stages::imaging::io::dimensions;
use skytie_stages::nadir::RecordingControl;
use std::path::{Path, PathBuf};
use std::sync::Arc;

/// The values one variant's exports are made of.
pub struct ExportInputs<'a> {
    pub snapshot: &'a CampaignSnapshot,
    pub report: Option<&'a AdjustReport>,
    pub verification: Option<&'a Verification>,
    /// The adjusted trajectory's verification (same control points and parameters; not an independent check
    /// when the adjustment used these control points — the check points are).
    pub verification_adjusted: Option<&'a Verification>,
    /// The nadir chain's per-recording control points (trajectory order).
    pub nadir_control: &'a [Arc<RecordingControl>],
    /// The oblique chain's consensus output.
    pub oblique: Option<&'a ObliqueOutput>,
}

/// Collects the problems of one export folder, one line each.
struct Problems {
    dir: PathBuf,
    lines: Vec<String>,
}

impl Problems {
    fn note<T>(&mut self, file: &str, r: std::io::Result<T>) -> Option<T> {
        r.map_err(|e| {
            self.lines.push(format!(
                "{}: not written: {e}",
                self.dir.join(file).display()
            ))
        })
        .ok()
    }

    fn warn(&mut self, file: &str, what: String) {
        self.lines
            .push(format!("{}: {what}", self.dir.join(file).display()));
    }
}

/// Write every export that the values allow into `dir`; returns the problems (one line each).
pub fn write_exports(dir: &Path, x: &ExportInputs<'_>) -> Vec<String> {
    let mut p = Problems {
        dir: dir.to_path_buf(),
        lines: Vec::new(),
    };
    if let Err(e) = std::fs::create_dir_all(dir) {
        return vec![format!("{}: cannot create the folder: {e}", dir.display())];
    }
    let nadir: Vec<AerialControlPoint> = x
        .nadir_control
        .iter()
        .flat_map(|r| r.points.iter().cloned())
        .collect();
    let oblique: &[AerialControlPoint] = x.oblique.map_or(&[], |o| &o.result.control);
    let groups: [(&str, &[AerialControlPoint]); 2] = [("nadir", &nadir), ("oblique", oblique)];
    if !x.nadir_control.is_empty() || x.oblique.is_some() {
        let path = dir.join("correspondences.csv");
        p.note(
            "correspondences.csv",
            write_correspondences_csv(&path, &groups, x.report.map(|r| &r.run)),
        );
    }
    for (file, v) in [
        ("verification.csv", x.verification),
        ("verification_adjusted.csv", x.verification_adjusted),
    ] {
        if let Some(v) = v {
            p.note(file, write_verification_csv(&dir.join(file), v));
        }
    }
    if let Some(report) = x.report {
        adjusted_exports(dir, x, report, &groups, &mut p);
    }
    p.lines
}

/// The files that present the trajectory as adjusted; only a [`Verdict::Corrected`] adjustment writes them.
const ADJUSTED_TRAJECTORY_FILES: [&str; 3] =
    ["trajectory_adjusted.csv", "corrections.csv", "skytie.gpkg"];

/// The exports that need an adjustment.
fn adjusted_exports(
    dir: &Path,
    x: &ExportInputs<'_>,
    report: &AdjustReport,
    groups: &[(&str, &[AerialControlPoint])],
    p: &mut Problems,
) {
    let c = &x.snapshot.campaign;
    let run = &report.run;
    let rows = &report.multi_view.rows;
    let series = match report.verdict() {
        Verdict::Corrected => p.note(
            "corrections.csv",
            CorrectionSeries::from_run(&c.recordings, run),
        ),
        verdict => {
            withhold_adjusted_trajectory(dir, c, verdict, p);
            None
        }
    };
    if let Some(series) = &series {
        let path = dir.join("corrections.csv");
        p.note("corrections.csv", write_corrections_csv(&path, series));
        let input = c.root.join("mm/recordings.csv");
        let path = dir.join("trajectory_adjusted.csv");
        p.note(
            "trajectory_adjusted.csv",
            write_adjusted_trajectory(&path, &input, series, run),
        );
        p.note(
            SBET_ADJUSTED,
            write_corrected_sbet(&c.root, &c.crs, series, dir),
        );
        second_crs_exports(dir, x, run, series, groups, p);
    }
    let path = dir.join("checkpoints.csv");
    p.note("checkpoints.csv", write_checkpoint_errors_csv(&path, rows));
    let path = dir.join("trajectory.geojson");
    let geojson = write_run_geojson(
        &path,
        &c.crs,
        &c.recordings,
        run,
        &c.checkpoints,
        rows,
        x.verification,
    );
    p.note("trajectory.geojson", geojson);
    let path = dir.join("tie_points.ply");
    p.note("tie_points.ply", write_tie_points_ply(&path, run));
    let gcp = write_ground_control(&dir.join("ground_control"), c, groups, Some(run));
    if let Some(e) = p.note("ground_control/", gcp) {
        if let Some(why) = e.gcp_list_skipped {
            p.warn("ground_control/gcp_list.txt", format!("not written: {why}"));
        }
        if e.gcp_list_skipped_names > 0 {
            p.warn(
                "ground_control/gcp_list.txt",
                format!(
                    "{} observation(s) left out: their image file names contain white space",
                    e.gcp_list_skipped_names
                ),
            );
        }
    }
    let sizes: Result<Vec<(u32, u32)>, String> = c
        .recordings
        .iter()
        .map(|r| dimensions(&c.root.join("mm/panoramas").join(&r.file)).map_err(|e| e.to_string()))
        .collect();
    let sizes = match sizes {
        Ok(s) => s,
        Err(e) => {
            p.warn("colmap/", format!("not written: {e}"));
            return;
        }
    };
    if let Some(series) = &series {
        let layers = RunLayers {
            recordings: &c.recordings,
            run,
            series,
            checkpoints: &c.checkpoints,
            checkpoint_rows: rows,
            control: groups,
            verification: x.verification,
            verification_adjusted: x.verification_adjusted,
        };
        p.note(
            "skytie.gpkg",
            write_gpkg(&dir.join("skytie.gpkg"), &c.crs, &layers),
        )
        .flatten()
        .into_iter()
        .for_each(|w| p.warn("skytie.gpkg", w));
    }
    let colmap = write_colmap_model(
        &dir.join("colmap"),
        &c.crs,
        &c.recordings,
        &sizes,
        run,
        &c.nadir,
        &c.oblique,
    );
    p.note("colmap/", colmap);
}

/// The campaign's second output CRS (`[outputs]` of `campaign.toml`), if it names one that can be used (one
/// that cannot was reported when the campaign was read).
fn second_crs(c: &Campaign) -> Option<SecondCrs> {
    let section = OutputsSection::read(&c.root).ok()?;
    SecondCrs::new(&c.crs, &section, &c.root).ok().flatten()
}

/// The adjusted trajectory, corrections and control points in the campaign's second CRS, if it names one.
fn second_crs_exports(
    dir: &Path,
    x: &ExportInputs<'_>,
    run: &AdjustmentRun,
    series: &CorrectionSeries,
    groups: &[(&str, &[AerialControlPoint])],
    p: &mut Problems,
) {
    let c = &x.snapshot.campaign;
    if let Some(second) = second_crs(c) {
        let files = SecondCrsRun {
            campaign: c,
            run,
            series,
            control: groups,
        };
        p.note(
            &format!("{}/", second.folder_name()),
            write_second_crs_files(dir, &second, &files),
        );
    }
}

/// `skytie.gpkg`; returns the warning for a CRS that is not an EPSG code.
fn write_gpkg(path: &Path, crs: &str, layers: &RunLayers<'_>) -> std::io::Result<Option<String>> {
    let (srs, warning) = match srs_for(crs) {
        Ok(s) => (s, None),
        Err((s, w)) => (s, Some(w)),
    };
    // A timestamp from the data, not the clock, so the same run gives the same bytes.
    let last = layers
        .recordings
        .iter()
        .map(|r| r.time_s)
        .fold(f64::NEG_INFINITY, f64::max);
    let stamp = format_time_iso(last).unwrap_or_else(|| "1970-01-01T00:00:00.000Z".to_string());
    write_geopackage(path, &srs, &run_layers(layers), &stamp)?;
    Ok(warning)
}

/// Never present an uncorrected or worsened trajectory as the adjusted one: the files that would (and any older
/// copies of them) are not there, and the problem list says why.
fn withhold_adjusted_trajectory(dir: &Path, c: &Campaign, verdict: Verdict, p: &mut Problems) {
    let why = match verdict {
        Verdict::NothingCorrected => "no recording observes aerial control, nothing was corrected",
        _ => "the adjustment made the check points worse",
    };
    for file in ADJUSTED_TRAJECTORY_FILES {
        let path = dir.join(file);
        if path.exists() {
            p.note(file, std::fs::remove_file(&path));
        }
        p.warn(file, format!("not written: {why}"));
    }
    // A corrected SBET or second-CRS trajectory of an earlier run into the same folder must not outlive its
    // verdict.
    let second: Vec<String> = second_crs(c)
        .map(|s| {
            [SECOND_TRAJECTORY_CSV, SECOND_CORRECTIONS_CSV]
                .map(|f| format!("{}/{f}", s.folder_name()))
                .to_vec()
        })
        .unwrap_or_default();
    let earlier = [SBET_ADJUSTED, SBET_QUALITY_CSV]
        .into_iter()
        .chain(second.iter().map(String::as_str));
    for file in earlier {
        let path = dir.join(file);
        if path.exists() {
            p.note(file, std::fs::remove_file(&path));
            p.warn(file, format!("removed: {why}"));
        }
    }
}
