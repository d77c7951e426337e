//! The sweep section of the index page: an overview table of all variants, the tables whose structure
//! follows the thesis (2-10 for the nadir matcher comparison, 5-11 / 5-12 for horizontal / full adjustments
//! with weighting methods 1–4, 4-2 for the oblique experiments) each beside the thesis' published values,
//! and grouped bar charts per variant (inliers / outliers / non-matchable like Figs 4.12, 4.14, 4.19;
//! correct / wrong nadir tie points; check-point RMSE 3D before / after).
//!
//! Oblique metrics read per variant (from its metrics.json): `oblique.inliers`, `oblique.outliers`,
//! `oblique.non_matchable` (counts of correspondences graded by truth).

use super::html::Page;
use super::inputs::{num_at, obj_at, ResultSet, RunOutputs};
use super::plots::bars::{grouped_bars, BarSeries};
use super::plots::{BLUE, GREEN, GREY, ORANGE, VERMILLION};
use super::tables::{fmt_count, fmt_num, fmt_percent, Origin, Table};
use super::{thesis_values, Builder};
use serde_json::Value;

/// Oblique correspondence counts per variant (see the module documentation).
pub const OBLIQUE_INLIERS: &str = "oblique.inliers";
pub const OBLIQUE_OUTLIERS: &str = "oblique.outliers";
pub const OBLIQUE_NON_MATCHABLE: &str = "oblique.non_matchable";
pub const OBLIQUE_INLIERS_KEPT: &str = "oblique.inliers_after_consensus";
pub const OBLIQUE_OUTLIERS_KEPT: &str = "oblique.outliers_after_consensus";
pub const OBLIQUE_NON_MATCHABLE_KEPT: &str = "oblique.non_matchable_after_consensus";

/// The thesis' two inlier percentages of a (inliers, outliers, non-matchable) count: over all, and without the
/// non-matchable ones (Tables 4-2…4-8). A missing non-matchable count (campaign without scene) counts as 0.
fn inlier_percentages(m: &Value, keys: [&str; 3]) -> (Option<f64>, Option<f64>) {
    let [i, o, n] = keys.map(|k| num_at(m, k));
    let ratio = |d: Option<f64>| i.zip(d.filter(|d| *d > 0.0)).map(|(i, d)| i / d);
    let matchable = i.zip(o).map(|(i, o)| i + o);
    (
        ratio(matchable.map(|t| t + n.unwrap_or(0.0))),
        ratio(matchable),
    )
}

/// The single adjustment configuration of a variant: (name, section).
fn adjust_config(m: &Value) -> Option<(&String, &Value)> {
    obj_at(m, "adjust")?.iter().next()
}

/// A variant's adjustment parameter `key` from provenance (`stages.adjust.params.<variant>.<key>`).
fn adjust_param(run: &RunOutputs, variant: &str, key: &str) -> Option<String> {
    let v = run
        .provenance
        .as_ref()?
        .get("stages")?
        .get("adjust")?
        .get("params")?
        .get(variant)?
        .get(key)?;
    Some(match v {
        Value::String(s) => s.clone(),
        other => other.to_string(),
    })
}

/// Appends the sweep section to `page`.
pub fn sweep_section(b: &mut Builder, page: &mut Page, run: &RunOutputs) -> Result<(), String> {
    page.heading("sweep", "Sweep");
    if run.sweep.is_some() {
        page.raw(
            "<p>All metrics of all variants: <a href=\"../sweep.csv\">sweep.csv</a> (one row per variant).</p>\n",
        );
    }
    overview(b, page, &run.sets);
    nadir_tables(b, page, &run.sets)?;
    oblique_tables(b, page, &run.sets)?;
    adjustment_tables(b, page, run)?;
    Ok(())
}

fn overview(b: &mut Builder, page: &mut Page, sets: &[ResultSet]) {
    let mut t = Table::new(
        "sweep-overview",
        "Variants: key results",
        Origin::Skytie,
        &[
            "variant",
            "nadir tie points",
            "correct",
            "inlier %",
            "control points",
            "oblique inliers",
            "adjustment",
            "check-point RMSE 2D after [m]",
            "check-point RMSE 3D after [m]",
            "verification",
        ],
    );
    for s in sets {
        let m = &s.metrics;
        let (config, a2d, a3d) = match adjust_config(m) {
            Some((c, a)) => (
                c.clone(),
                fmt_num(num_at(a, "checkpoints.after.2d"), 3),
                fmt_num(num_at(a, "checkpoints.after.3d"), 3),
            ),
            None => ("n/a".into(), "n/a".into(), "n/a".into()),
        };
        let verify = match m
            .get("verify")
            .and_then(|v| v.get("passed"))
            .and_then(|v| v.as_bool())
        {
            Some(true) => "pass".to_string(),
            Some(false) => "fail".to_string(),
            None => "n/a".to_string(),
        };
        t.push(vec![
            s.name.clone(),
            fmt_count(num_at(m, "nadir.tie_points")),
            fmt_count(num_at(m, "nadir.correct_tie_points")),
            fmt_percent(num_at(m, "nadir.inlier_ratio")),
            fmt_count(num_at(m, "nadir.control_points")),
            fmt_count(num_at(m, OBLIQUE_INLIERS)),
            config,
            a2d,
            a3d,
            verify,
        ]);
    }
    b.table(page, t);
}

fn names(sets: &[ResultSet]) -> Vec<String> {
    sets.iter().map(|s| s.name.clone()).collect()
}

/// Whether any variant has the numeric metric at `path`.
fn any_has(sets: &[ResultSet], path: &str) -> bool {
    sets.iter().any(|s| num_at(&s.metrics, path).is_some())
}

/// Table 2-10 structure and the correct / wrong tie-point chart, when variants have graded nadir metrics.
fn nadir_tables(b: &mut Builder, page: &mut Page, sets: &[ResultSet]) -> Result<(), String> {
    if !any_has(sets, "nadir.correct_tie_points") {
        return Ok(());
    }
    page.subheading("Nadir matching per variant (Table 2-10)");
    let mut t = Table::new(
        "sweep-table-2-10",
        "Table 2-10 structure: matches and inliers per variant",
        Origin::Skytie,
        &["variant", "matches", "inliers", "matches/tile", "inliers/tile", "ratio %"],
    )
    .with_note(
        "matches = MM tie point × aerial image correspondences; inliers = correct by truth; tile = one \
         accepted (recording, nadir image) pair.",
    );
    for s in sets {
        let m = &s.metrics;
        let matches = num_at(m, "nadir.tie_points");
        let inliers = num_at(m, "nadir.correct_tie_points");
        let tiles = num_at(m, "nadir.transforms_accepted").filter(|t| *t > 0.0);
        let per = |v: Option<f64>| fmt_num(v.zip(tiles).map(|(v, t)| v / t), 1);
        t.push(vec![
            s.name.clone(),
            fmt_count(matches),
            fmt_count(inliers),
            per(matches),
            per(inliers),
            fmt_percent(num_at(m, "nadir.inlier_ratio")),
        ]);
    }
    b.table(page, t);
    b.table(page, thesis_values::table_2_10());
    let (path, href) = b.figure_path("sweep-nadir-tie-points.svg");
    grouped_bars(
        &path,
        "Nadir tie points per variant",
        "MM–aerial tie points (count)",
        &names(sets),
        &[
            BarSeries {
                name: "correct (inliers)".into(),
                color: GREEN,
                values: sets
                    .iter()
                    .map(|s| num_at(&s.metrics, "nadir.correct_tie_points"))
                    .collect(),
            },
            BarSeries {
                name: "wrong (outliers)".into(),
                color: VERMILLION,
                values: sets
                    .iter()
                    .map(|s| {
                        let m = &s.metrics;
                        Some(
                            num_at(m, "nadir.tie_points")? - num_at(m, "nadir.correct_tie_points")?,
                        )
                    })
                    .collect(),
            },
        ],
    )?;
    b.wrote_figure(path);
    page.figure(
        &href,
        "nadir tie points per variant",
        "Correct and wrong MM–aerial tie points per variant (graded by truth).",
    );
    Ok(())
}

/// Oblique inliers / outliers / non-matchable per variant (Figs 4.12, 4.14, 4.19; Table 4-2 structure).
fn oblique_tables(b: &mut Builder, page: &mut Page, sets: &[ResultSet]) -> Result<(), String> {
    if !any_has(sets, OBLIQUE_INLIERS) {
        return Ok(());
    }
    page.subheading("Oblique registration per variant (Tables 4-2…4-8)");
    let mut t = Table::new(
        "sweep-oblique",
        "Oblique correspondences per variant",
        Origin::Skytie,
        &[
            "variant",
            "inliers",
            "outliers",
            "non-matchable",
            "inlier %",
            "inlier % without non-matchable",
            "inlier % after outlier removal",
            "inlier % after outlier removal without non-matchable",
        ],
    );
    for s in sets {
        let m = &s.metrics;
        let before = inlier_percentages(
            m,
            [OBLIQUE_INLIERS, OBLIQUE_OUTLIERS, OBLIQUE_NON_MATCHABLE],
        );
        let after = inlier_percentages(
            m,
            [
                OBLIQUE_INLIERS_KEPT,
                OBLIQUE_OUTLIERS_KEPT,
                OBLIQUE_NON_MATCHABLE_KEPT,
            ],
        );
        t.push(vec![
            s.name.clone(),
            fmt_count(num_at(m, OBLIQUE_INLIERS)),
            fmt_count(num_at(m, OBLIQUE_OUTLIERS)),
            fmt_count(num_at(m, OBLIQUE_NON_MATCHABLE)),
            fmt_percent(before.0),
            fmt_percent(before.1),
            fmt_percent(after.0),
            fmt_percent(after.1),
        ]);
    }
    b.table(page, t);
    b.table(page, thesis_values::table_4_2());
    let series = [
        ("inliers", GREEN, OBLIQUE_INLIERS),
        ("outliers", VERMILLION, OBLIQUE_OUTLIERS),
        ("non-matchable", GREY, OBLIQUE_NON_MATCHABLE),
    ]
    .map(|(name, color, key)| BarSeries {
        name: name.into(),
        color,
        values: sets.iter().map(|s| num_at(&s.metrics, key)).collect(),
    });
    let (path, href) = b.figure_path("sweep-oblique-correspondences.svg");
    grouped_bars(
        &path,
        "Oblique correspondences per variant",
        "correspondences (count)",
        &names(sets),
        &series,
    )?;
    b.wrote_figure(path);
    page.figure(
        &href,
        "oblique correspondences per variant",
        "Inliers, outliers and non-matchable oblique correspondences per variant (thesis Figs 4.12, 4.14, 4.19).",
    );
    Ok(())
}

/// Tables 5-11 / 5-12 structure: per (sources, dimensions) the RMSE of weighting methods 1–4, and a chart
/// of RMSE 3D before / after per variant.
fn adjustment_tables(b: &mut Builder, page: &mut Page, run: &RunOutputs) -> Result<(), String> {
    let sets = &run.sets;
    if !sets.iter().any(|s| adjust_config(&s.metrics).is_some()) {
        return Ok(());
    }
    page.subheading("Adjustment per variant (Tables 5-11, 5-12)");
    // Groups (sources, dimensions) in first-seen order.
    let mut groups: Vec<(String, String)> = Vec::new();
    for s in sets {
        if adjust_config(&s.metrics).is_none() {
            continue;
        }
        let key = (
            adjust_param(run, &s.name, "sources").unwrap_or_else(|| "?".into()),
            adjust_param(run, &s.name, "dimensions").unwrap_or_else(|| "?".into()),
        );
        if !groups.contains(&key) {
            groups.push(key);
        }
    }
    let mut shown_thesis = (false, false);
    for (sources, dims) in &groups {
        let members: Vec<(&ResultSet, String)> = sets
            .iter()
            .filter(|s| {
                adjust_param(run, &s.name, "sources").as_deref() == Some(sources.as_str())
                    && adjust_param(run, &s.name, "dimensions").as_deref() == Some(dims.as_str())
                    && adjust_config(&s.metrics).is_some()
            })
            .map(|s| {
                let w =
                    adjust_param(run, &s.name, "weighting_method").unwrap_or_else(|| "?".into());
                (s, w)
            })
            .collect();
        if members.is_empty() {
            continue;
        }
        let mut header = vec!["".to_string(), "before".to_string()];
        header.extend(
            members
                .iter()
                .map(|(s, w)| format!("method {w} ({})", s.name)),
        );
        let header_ref: Vec<&str> = header.iter().map(|s| s.as_str()).collect();
        let id = format!(
            "sweep-adjust-{}-{}",
            super::slug(sources),
            super::slug(dims)
        );
        let mut t = Table::new(
            &id,
            &format!("Table 5-11/5-12 structure: {sources} correspondences, {dims} adjustment [m]"),
            Origin::Skytie,
            &header_ref,
        )
        .with_note("Check-point RMSE (multi-view triangulation); before = recorded poses.");
        for (k, label) in [
            ("x", "RMSE X"),
            ("y", "RMSE Y"),
            ("z", "RMSE Z"),
            ("3d", "RMSE 3D"),
        ] {
            let before = adjust_config(&members[0].0.metrics)
                .and_then(|(_, a)| num_at(a, &format!("checkpoints.before.{k}")));
            let mut row = vec![label.to_string(), fmt_num(before, 3)];
            for (s, _) in &members {
                row.push(fmt_num(
                    adjust_config(&s.metrics)
                        .and_then(|(_, a)| num_at(a, &format!("checkpoints.after.{k}"))),
                    3,
                ));
            }
            t.push(row);
        }
        b.table(page, t);
        if dims == "horizontal" && !shown_thesis.0 {
            b.table(page, thesis_values::table_5_11());
            shown_thesis.0 = true;
        }
        if dims == "full" && !shown_thesis.1 {
            b.table(page, thesis_values::table_5_12());
            shown_thesis.1 = true;
        }
    }
    let value = |s: &ResultSet, k: &str| adjust_config(&s.metrics).and_then(|(_, a)| num_at(a, k));
    let (path, href) = b.figure_path("sweep-adjust-rmse.svg");
    grouped_bars(
        &path,
        "Check-point RMSE 3D per variant",
        "RMSE 3D of the check points [m]",
        &names(sets),
        &[
            BarSeries {
                name: "before adjustment".into(),
                color: ORANGE,
                values: sets
                    .iter()
                    .map(|s| value(s, "checkpoints.before.3d"))
                    .collect(),
            },
            BarSeries {
                name: "after adjustment".into(),
                color: BLUE,
                values: sets
                    .iter()
                    .map(|s| value(s, "checkpoints.after.3d"))
                    .collect(),
            },
        ],
    )?;
    b.wrote_figure(path);
    page.figure(
        &href,
        "check-point RMSE per variant",
        "Check-point RMSE 3D before and after the adjustment, per variant.",
    );
    Ok(())
}
