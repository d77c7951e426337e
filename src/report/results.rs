//! The result sections of one result set (a plain run, or one sweep variant): trajectory map, nadir
//! registration statistics (Table 3-1's structure), accuracy per adjustment configuration (RMSE X/Y/Z/2D/3D
//! before/after, Tables 5-2/5-4/5-9's structure), the check-point residual histogram, verification
//! (Table 5-13's structure) and the registration views.

use super::headline_section::{headline_section, rank_segments, RANKED_SEGMENTS};
use super::html::Page;
use super::inputs::{num_at, obj_at, read_csv_opt, ResultSet, RunOutputs};
use super::map_data::{MapData, AREA_GAP_M};
use super::plots::histogram::{histogram, HistSeries};
use super::plots::trajectory::{trajectory_map, trim, MapRecording};
use super::plots::{GREY, VERMILLION};
use super::tables::{fmt_count, fmt_num, fmt_percent, Origin, Table};
use super::{interactive_map, registration, thesis_values, Builder};
use serde_json::Value;

/// Appends the sections of `set` to `page`.
pub fn results_sections(
    b: &mut Builder,
    page: &mut Page,
    set: &ResultSet,
    _run: &RunOutputs,
) -> Result<(), String> {
    let prefix = set.anchor_prefix();
    // Answer first, then the map, accuracy, registration; the map is built last (it links the registration
    // views) but shown second.
    headline_section(b, page, set, &prefix)?;
    let mut rest = Page::new("");
    accuracy_section(b, &mut rest, set)?;
    super::headline_section::adjusted_verification_table(b, &mut rest, set, &prefix)?;
    verification_section(b, &mut rest, set, &prefix)?;
    nadir_section(b, &mut rest, &set.metrics, &prefix);
    registration::registration_section(b, &mut rest, set, &prefix)?;
    map_section(b, &mut rest, set)?;
    let views = std::mem::take(&mut b.recording_views);
    interactive_map::map_section(b, page, set, &prefix, &views)?;
    page.append(rest);
    Ok(())
}

/// Most recordings drawn in one static trajectory figure.
pub const STATIC_MAP_LIMIT: usize = 3000;

fn map_section(b: &mut Builder, page: &mut Page, set: &ResultSet) -> Result<(), String> {
    let (prefix, title_suffix) = (set.anchor_prefix(), set.title_suffix());
    page.heading(
        &format!("{prefix}static-map"),
        "Trajectory map (static figure)",
    );
    let campaign = b.campaign.clone();
    let Some(data) = b.cache.map_data(&set.dir, campaign.as_deref())? else {
        b.note(
            page,
            format!(
                "{}: no trajectory.geojson and no campaign recordings: no trajectory map",
                set.dir.display()
            ),
        );
        return Ok(());
    };
    let areas = MapData::clone(&data).areas(AREA_GAP_M);
    let n_areas = areas.len();
    if n_areas > 1 {
        page.raw(&format!(
            "<p>{n_areas} areas more than {} m apart: one map each.</p>\n",
            trim(AREA_GAP_M)
        ));
    }
    for (k, area) in areas.iter().enumerate() {
        let (file, which) = if n_areas > 1 {
            (
                format!("{prefix}trajectory-area{}.svg", k + 1),
                format!(", area {} of {n_areas}", k + 1),
            )
        } else {
            (format!("{prefix}trajectory.svg"), String::new())
        };
        let (path, href) = b.figure_path(&file);
        // A static figure of a city's recordings would be tens of megabytes of circles drawn over each other:
        // beyond STATIC_MAP_LIMIT recordings every k-th is drawn (the interactive map keeps the flagged ones).
        let stride = area.recordings.len().div_ceil(STATIC_MAP_LIMIT).max(1);
        let drawn: Vec<MapRecording> = area.recordings.iter().step_by(stride).copied().collect();
        let scales = trajectory_map(
            &path,
            &format!("Recordings and check points{title_suffix}{which}"),
            &drawn,
            &area.checkpoints,
        )?;
        b.wrote_figure(path);
        let truth = if area.has_truth {
            "true positions from the campaign's truth/ folder (evaluation only)"
        } else {
            "no true positions (no truth/ folder)"
        };
        page.figure(
            &href,
            "trajectory map",
            &format!(
                "{}{} recordings: recorded (hollow), adjusted (filled, coloured by aerial correspondences), {truth}. \
                 {} check points with horizontal error vectors (estimated − true) before (grey) and after (red) \
                 the adjustment, drawn {}× longer than they are; scale bar {} m.",
                if n_areas > 1 { format!("Area {} of {n_areas}: ", k + 1) } else { String::new() },
                if stride > 1 {
                    format!("every {stride}th of {}", area.recordings.len())
                } else {
                    area.recordings.len().to_string()
                },
                area.checkpoints.len(),
                trim(scales.exaggeration),
                trim(scales.scale_bar_m)
            ),
        );
    }
    Ok(())
}

/// Table 3-1's structure from `nadir.*` metrics, beside the thesis' table.
fn nadir_section(b: &mut Builder, page: &mut Page, m: &Value, prefix: &str) {
    if m.get("nadir").is_none() {
        return;
    }
    page.heading(&format!("{prefix}nadir"), "Nadir registration (Table 3-1)");
    let mut t = Table::new(
        &format!("{prefix}table-3-1"),
        "Table 3-1 structure: nadir registration results",
        Origin::Skytie,
        &["", "this campaign"],
    )
    .with_note(
        "Correct = within 1 aerial pixel of the truth-triangulated point (README, truth grading rule); \
         n/a without truth.",
    );
    let c = |k: &str| fmt_count(num_at(m, k));
    t.push(vec!["MM images".into(), c("nadir.recordings")]);
    t.push(vec![
        "MM images with correspondences to aerial images".into(),
        c("nadir.recordings_with_aerial"),
    ]);
    t.push(vec![
        "tie points with individual aerial images".into(),
        c("nadir.tie_points"),
    ]);
    t.push(vec![
        "correct tie points".into(),
        c("nadir.correct_tie_points"),
    ]);
    t.push(vec![
        "inlier ratio %".into(),
        fmt_percent(num_at(m, "nadir.inlier_ratio")),
    ]);
    t.push(vec![
        "mean aerial images matched per MM image".into(),
        fmt_num(num_at(m, "nadir.mean_aerial_images_per_recording"), 2),
    ]);
    t.push(vec![
        "control points (≥ 2 aerial images)".into(),
        c("nadir.control_points"),
    ]);
    t.push(vec![
        "MM-to-MM pairs (KAZE / pose fallback)".into(),
        format!(
            "{} ({} / {})",
            c("nadir.mm_pairs"),
            c("nadir.mm_pairs_kaze"),
            c("nadir.mm_pairs_fallback")
        ),
    ]);
    t.push(vec![
        "control-point error, median horizontal / vertical, m".into(),
        format!(
            "{} / {}",
            fmt_num(
                num_at(m, "nadir.control_point_error_m.median_horizontal"),
                3
            ),
            fmt_num(num_at(m, "nadir.control_point_error_m.median_vertical"), 3)
        ),
    ]);
    b.table(page, t);
    if prefix.is_empty() {
        b.table(page, thesis_values::table_3_1());
    }
}

const AXES: [(&str, &str); 5] = [
    ("x", "X"),
    ("y", "Y"),
    ("z", "Z"),
    ("2d", "2D"),
    ("3d", "3D"),
];

fn accuracy_section(b: &mut Builder, page: &mut Page, set: &ResultSet) -> Result<(), String> {
    let (prefix, title_suffix) = (set.anchor_prefix(), set.title_suffix());
    let m = &set.metrics;
    let Some(adjust) = obj_at(m, "adjust") else {
        return Ok(());
    };
    page.heading(
        &format!("{prefix}accuracy"),
        "Accuracy per adjustment configuration",
    );
    let mut header = vec!["configuration", "check points", "evaluation", "count"];
    let names: Vec<String> = AXES
        .iter()
        .flat_map(|(_, n)| [format!("{n} before"), format!("{n} after")])
        .collect();
    header.extend(names.iter().map(|s| s.as_str()));
    let mut t = Table::new(
        &format!("{prefix}accuracy"),
        "Check-point RMSE before / after the adjustment [m]",
        Origin::Skytie,
        &header,
    )
    .with_note(
        "multi-view: check points triangulated from all recordings within 15 m; two-view: from the two \
         nearest. before = recorded poses, after = adjusted poses.",
    );
    for (config, a) in adjust {
        for (key, label) in [
            ("checkpoints", "multi-view"),
            ("checkpoints_two_view", "two-view"),
        ] {
            if a.get(key).is_none() {
                continue;
            }
            let mut row = vec![
                config.clone(),
                label.to_string(),
                "RMSE".to_string(),
                fmt_count(num_at(a, &format!("{key}.after.count"))),
            ];
            for (k, _) in AXES {
                row.push(fmt_num(num_at(a, &format!("{key}.before.{k}")), 3));
                row.push(fmt_num(num_at(a, &format!("{key}.after.{k}")), 3));
            }
            t.push(row);
        }
    }
    b.table(page, t);
    // Recordings vs truth.
    let mut r = Table::new(
        &format!("{prefix}recordings-vs-truth"),
        "Recording positions vs truth [m]",
        Origin::Skytie,
        &[
            "configuration",
            "count",
            "RMSE 2D before",
            "RMSE 2D after",
            "RMSE 3D before",
            "RMSE 3D after",
            "max 2D before",
            "max 2D after",
        ],
    );
    for (config, a) in adjust {
        if a.get("recordings").is_none() {
            continue;
        }
        let v = |k: &str| fmt_num(num_at(a, &format!("recordings.{k}")), 3);
        r.push(vec![
            config.clone(),
            fmt_count(num_at(a, "recordings.after.count")),
            v("before.rmse_2d"),
            v("after.rmse_2d"),
            v("before.rmse_3d"),
            v("after.rmse_3d"),
            v("before.max_2d"),
            v("after.max_2d"),
        ]);
    }
    if !r.rows.is_empty() {
        b.table(page, r);
    }
    // Tables 5-2 / 5-4 / 5-9 structure (plain run only: in a sweep each variant is one configuration).
    if prefix.is_empty() {
        thesis_structured_accuracy(b, page, m);
    }
    // Residual histogram from checkpoints.csv.
    if let Some(cp) = read_csv_opt(&set.dir.join("checkpoints.csv"))? {
        let col =
            |name: &str| -> Vec<f64> { cp.rows.iter().filter_map(|r| cp.num(r, name)).collect() };
        let (before, after) = (col("before_2d"), col("after_2d"));
        if !before.is_empty() || !after.is_empty() {
            let (path, href) = b.figure_path(&format!("{prefix}checkpoint-residuals.svg"));
            histogram(
                &path,
                &format!("Check-point horizontal errors{title_suffix}"),
                "2D error of the check point [m]",
                &[
                    HistSeries {
                        name: format!("before adjustment ({} points)", before.len()),
                        color: GREY,
                        samples: before,
                    },
                    HistSeries {
                        name: format!("after adjustment ({} points)", after.len()),
                        color: VERMILLION,
                        samples: after,
                    },
                ],
            )?;
            b.wrote_figure(path);
            page.figure(
                &href,
                "check-point residual histogram",
                "Histogram of the check points' horizontal errors (multi-view triangulation, checkpoints.csv).",
            );
        }
    }
    Ok(())
}

/// Our tables with the structure of thesis Tables 5-2 (nadir), 5-4 (oblique) and 5-9 (RMSE 3D).
fn thesis_structured_accuracy(b: &mut Builder, page: &mut Page, m: &Value) {
    let area = super::inputs::str_at(m, "campaign.name")
        .unwrap_or("this campaign")
        .to_string();
    for (source, id, title, thesis) in [
        (
            "nadir",
            "table-5-2",
            "Table 5-2 structure: adjustment with nadir correspondences only [m]",
            thesis_values::table_5_2 as fn() -> Table,
        ),
        (
            "oblique",
            "table-5-4",
            "Table 5-4 structure: adjustment with oblique correspondences only [m]",
            thesis_values::table_5_4,
        ),
    ] {
        let key = format!("adjust.{source}.checkpoints");
        if obj_at(m, &key).is_none() {
            continue;
        }
        let mut t = Table::new(
            id,
            title,
            Origin::Skytie,
            &[
                "area", "X before", "X after", "Y before", "Y after", "Z before", "Z after",
            ],
        );
        let mut row = vec![area.clone()];
        for k in ["x", "y", "z"] {
            row.push(fmt_num(num_at(m, &format!("{key}.before.{k}")), 3));
            row.push(fmt_num(num_at(m, &format!("{key}.after.{k}")), 3));
        }
        t.push(row);
        b.table(page, t);
        b.table(page, thesis());
    }
    let configs = ["nadir", "oblique", "combined"];
    if configs
        .iter()
        .any(|c| obj_at(m, &format!("adjust.{c}.checkpoints")).is_some())
    {
        let mut t = Table::new(
            "table-5-9",
            "Table 5-9 structure: check-point RMSE 3D before and after the adjustments [m]",
            Origin::Skytie,
            &[
                "area",
                "before",
                "after nadir",
                "after oblique",
                "after combined",
            ],
        );
        let before = configs
            .iter()
            .find_map(|c| num_at(m, &format!("adjust.{c}.checkpoints.before.3d")));
        let mut row = vec![area, fmt_num(before, 3)];
        for c in configs {
            row.push(fmt_num(
                num_at(m, &format!("adjust.{c}.checkpoints.after.3d")),
                3,
            ));
        }
        t.push(row);
        b.table(page, t);
        b.table(page, thesis_values::table_5_9());
    }
}

fn verification_section(
    b: &mut Builder,
    page: &mut Page,
    set: &ResultSet,
    prefix: &str,
) -> Result<(), String> {
    let m = &set.metrics;
    let csv = read_csv_opt(&set.dir.join("verification.csv"))?;
    if m.get("verify").is_none() && csv.is_none() {
        return Ok(());
    }
    page.heading(
        &format!("{prefix}verification"),
        "Verification of the recorded trajectory (Table 5-13)",
    );
    if let Some(passed) = m
        .get("verify")
        .and_then(|v| v.get("passed"))
        .and_then(|v| v.as_bool())
    {
        let (class, word) = if passed {
            ("ok", "PASSED")
        } else {
            ("fail", "FAILED")
        };
        page.raw(&format!(
            "<p>Verification <span class=\"{class}\">{word}</span>: {} of {} segment(s) failed.</p>\n",
            fmt_count(num_at(m, "verify.segments_failed")),
            fmt_count(num_at(m, "verify.segments"))
        ));
    }
    if let Some(v) = csv {
        let mut t = Table::new(
            &format!("{prefix}verification"),
            "Per segment, recorded poses: MM − aerial control-point offsets [m] and verdicts",
            Origin::Skytie,
            &[
                "segment",
                "recordings",
                "first",
                "last",
                "points",
                "mean X",
                "mean Y",
                "mean Z",
                "SD X",
                "SD Y",
                "SD Z",
                "mean 3D",
                "SD 3D",
                "status",
            ],
        )
        .with_note("Same structure as thesis Table 5-13 (mean and SD of the differences), one row per segment.");
        let keys: Vec<(&str, &str, Option<f64>)> = v
            .rows
            .iter()
            .map(|r| {
                let offset = match (v.num(r, "mean_x"), v.num(r, "mean_y")) {
                    (Some(x), Some(y)) => Some(x.hypot(y)),
                    _ => None,
                };
                (v.text(r, "segment"), v.text(r, "status"), offset)
            })
            .collect();
        let ranked = rank_segments(&keys);
        for r in &v.rows {
            let n = |k: &str| fmt_num(v.num(r, k), 3);
            t.push(vec![
                v.text(r, "segment").to_string(),
                v.text(r, "recordings").to_string(),
                v.text(r, "first_image_id").to_string(),
                v.text(r, "last_image_id").to_string(),
                v.text(r, "points").to_string(),
                n("mean_x"),
                n("mean_y"),
                n("mean_z"),
                n("sd_x"),
                n("sd_y"),
                n("sd_z"),
                n("mean_3d"),
                n("sd_3d"),
                v.text(r, "status").to_uppercase(),
            ]);
        }
        b.table(page, t.rank_for_html(ranked, RANKED_SEGMENTS));
    }
    if prefix.is_empty() {
        b.table(page, thesis_values::table_5_13());
    }
    Ok(())
}
