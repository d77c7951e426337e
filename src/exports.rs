//! Writing a run's user-facing files (issue 6 "Outputs") into `OUT/` (or `OUT/variants/<name>/` in a sweep)
//! once the adjustment and verification nodes have produced their values: `trajectory_adjusted.csv`,
//! `trajectory.geojson`, `tie_points.ply`, `checkpoints.csv`, `verification.csv` (recorded trajectory), `verification_adjusted.csv`, `correspondences.csv` and a
//! COLMAP text model in `colmap/`. The encoders live in `skytie_stages::export`; every file is written atomically. A failed export is
//! a warning naming the file; the run's other outputs are still written.

use crate::nodes::adjust::adjustment::{AdjustReport, Verdict};
use crate::nodes::campaign::load::CampaignSnapshot;
use crate::nodes::oblique::consensus::ObliqueOutput;
use skytie_stages::adjustment::verify::{write_verification_csv, Verification};
use skytie_stages::correspondence::AerialControlPoint;
use skytie_stages::export::{
    write_adjusted_trajectory, write_checkpoint_errors_csv, write_colmap_model,
    write_correspondences_csv, write_run_geojson, write_tie_points_ply,
};
use skytie_stages::imaging::io::dimensions;
use skytie_stages::nadir::RecordingControl;
use std::path::Path;
use std::sync::Arc;

/// The values one variant's exports are made of.
pub struct ExportInputs<'a> {
    pub snapshot: &'a CampaignSnapshot,
    pub report: Option<&'a AdjustReport>,
    pub verification: Option<&'a Verification>,
    /// The adjusted trajectory's verification.
    pub verification_adjusted: Option<&'a Verification>,
    /// The nadir chain's per-recording control points (trajectory order).
    pub nadir_control: &'a [Arc<RecordingControl>],
    /// The oblique chain's consensus output.
    pub oblique: Option<&'a ObliqueOutput>,
}

/// Write every export that the values allow into `dir`; returns the problems (one line each).
pub fn write_exports(dir: &Path, x: &ExportInputs<'_>) -> Vec<String> {
    let mut problems = Vec::new();
    let c = &x.snapshot.campaign;
    let mut note = |file: &str, r: std::io::Result<()>| {
        if let Err(e) = r {
            problems.push(format!("{}: not written: {e}", dir.join(file).display()));
        }
    };
    if let Err(e) = std::fs::create_dir_all(dir) {
        return vec![format!("{}: cannot create the folder: {e}", dir.display())];
    }
    if !x.nadir_control.is_empty() || x.oblique.is_some() {
        let nadir: Vec<AerialControlPoint> = x
            .nadir_control
            .iter()
            .flat_map(|r| r.points.iter().cloned())
            .collect();
        let oblique: &[AerialControlPoint] = x.oblique.map_or(&[], |o| &o.result.control);
        note(
            "correspondences.csv",
            write_correspondences_csv(
                &dir.join("correspondences.csv"),
                &[("nadir", &nadir), ("oblique", oblique)],
            ),
        );
    }
    for (file, v) in [
        ("verification.csv", x.verification),
        ("verification_adjusted.csv", x.verification_adjusted),
    ] {
        if let Some(v) = v {
            note(file, write_verification_csv(&dir.join(file), v));
        }
    }
    let Some(report) = x.report else {
        return problems;
    };
    let run = &report.run;
    match report.verdict() {
        Verdict::Corrected => note(
            "trajectory_adjusted.csv",
            write_adjusted_trajectory(&dir.join("trajectory_adjusted.csv"), &c.recordings, run),
        ),
        verdict => {
            // Never present an uncorrected or worsened trajectory as the adjusted one; an older file goes too.
            let stale = dir.join("trajectory_adjusted.csv");
            if stale.exists() {
                note("trajectory_adjusted.csv", std::fs::remove_file(&stale));
            }
            let why = match verdict {
                Verdict::NothingCorrected => {
                    "no recording observes aerial control, nothing was corrected"
                }
                _ => "the adjustment made the check points worse",
            };
            note("trajectory_adjusted.csv", Err(std::io::Error::other(why)));
        }
    }
    note(
        "checkpoints.csv",
        write_checkpoint_errors_csv(&dir.join("checkpoints.csv"), &report.multi_view.rows),
    );
    note(
        "trajectory.geojson",
        write_run_geojson(
            &dir.join("trajectory.geojson"),
            &c.crs,
            &c.recordings,
            run,
            &c.checkpoints,
            &report.multi_view.rows,
            x.verification,
        ),
    );
    note(
        "tie_points.ply",
        write_tie_points_ply(&dir.join("tie_points.ply"), run),
    );
    let sizes: Result<Vec<(u32, u32)>, String> = c
        .recordings
        .iter()
        .map(|r| dimensions(&c.root.join("mm/panoramas").join(&r.file)).map_err(|e| e.to_string()))
        .collect();
    match sizes {
        Ok(sizes) => note(
            "colmap/",
            write_colmap_model(
                &dir.join("colmap"),
                &c.crs,
                &c.recordings,
                &sizes,
                run,
                &c.nadir,
                &c.oblique,
            )
            .map(|_| ()),
        ),
        Err(e) => problems.push(format!(
            "{}: not written: {e}",
            dir.join("colmap").display()
        )),
    }
    problems
}
