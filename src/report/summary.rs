//! The report's diagnostics section (last on the page): campaign and workflow, failed / skipped nodes (with reasons when `metrics.json` records them under
//! `engine.failures` / `engine.skipped_nodes`), rejected items with their reasons (`nadir.transforms_rejected`,
//! the verification's skipped points, the adjustment's rejected observations, in words) and input problems,
//! then what ran and what was served from the cache and the time per stage.

use super::html::Page;
use super::inputs::{num_at, obj_at, str_at, RunOutputs};
use super::tables::{fmt_count, fmt_num, Origin, Table};
use super::Builder;

/// Appends the summary to `page`.
pub fn summary_section(b: &mut Builder, page: &mut Page, run: &RunOutputs) {
    let m = &run.metrics;
    // For sweeps the campaign section lives in the variants' metrics.
    let first = run.sets.first().map(|s| &s.metrics).unwrap_or(m);
    let prov = run.provenance.as_ref();
    page.heading("summary", "Diagnostics");
    let mut t = Table::new("summary-run", "Run", Origin::Skytie, &["item", "value"]);
    let mut kv = |k: &str, v: String| t.push(vec![k.to_string(), v]);
    let campaign_name = str_at(first, "campaign.name").unwrap_or("n/a");
    kv("campaign", campaign_name.to_string());
    if let Some(p) = prov.and_then(|p| p.get("campaign")) {
        let src = if let Some(path) = p.get("path").and_then(|v| v.as_str()) {
            format!("folder {path}")
        } else if let Some(s) = p.get("synth").and_then(|v| v.as_str()) {
            format!(
                "synthetic preset {s}, seed {}",
                p.get("seed").map(|v| v.to_string()).unwrap_or_default()
            )
        } else {
            p.to_string()
        };
        kv("campaign source", src);
    }
    for (label, key) in [
        ("recordings", "campaign.recordings"),
        ("nadir images", "campaign.nadir_images"),
        ("oblique images", "campaign.oblique_images"),
        ("check points", "campaign.checkpoints"),
        ("check-point observations", "campaign.observations"),
        ("input errors (rows skipped)", "campaign.input_errors"),
        ("input warnings", "campaign.input_warnings"),
    ] {
        if let Some(v) = num_at(first, key) {
            kv(label, fmt_count(Some(v)));
        }
    }
    if let Some(w) = prov.and_then(|p| p.get("workflow")) {
        for (label, key) in [
            ("workflow", "name"),
            ("workflow file", "path"),
            ("pipeline", "pipeline"),
        ] {
            if let Some(v) = w.get(key).and_then(|v| v.as_str()) {
                kv(label, v.to_string());
            }
        }
        if let Some(st) = w.get("stages").and_then(|v| v.as_array()) {
            let names: Vec<&str> = st.iter().filter_map(|v| v.as_str()).collect();
            kv("enabled stages", names.join(", "));
        }
    }
    if let Some(v) = prov
        .and_then(|p| p.get("skytie_version"))
        .and_then(|v| v.as_str())
    {
        kv("skytie version", v.to_string());
    }
    if run.is_sweep {
        kv("variants", fmt_count(Some(run.sets.len() as f64)));
    }
    b.table(page, t);
    problems(b, page, run);

    // What this particular run did: differs between runs of one workflow (a warm rerun executes nothing).
    let mut t = Table::new(
        "summary-engine",
        "This run: nodes executed / served from the cache, time",
        Origin::Skytie,
        &["item", "value"],
    )
    .with_note(
        "run log: written to run-log/, not tables/ (it differs between runs of the same workflow)",
    );
    let mut kv = |k: &str, v: String| t.push(vec![k.to_string(), v]);
    if let Some(s) = prov.and_then(|p| num_at(p, "timings.finished_unix_s")) {
        kv("finished (unix time, s)", fmt_count(Some(s)));
    }
    for (label, key, decimals) in [
        ("nodes total", "engine.nodes_total", None),
        ("nodes executed", "engine.nodes_executed", None),
        ("nodes served from cache", "engine.nodes_cached", None),
        ("nodes failed", "engine.nodes_failed", None),
        (
            "nodes skipped (upstream failed)",
            "engine.nodes_skipped",
            None,
        ),
        ("warnings", "engine.warnings", None),
        ("wall time, s", "engine.seconds", Some(1)),
    ] {
        if let Some(v) = num_at(m, key) {
            kv(
                label,
                match decimals {
                    Some(d) => fmt_num(Some(v), d),
                    None => fmt_count(Some(v)),
                },
            );
        }
    }
    b.run_log_table(page, t);

    if let Some(stages) = obj_at(m, "stages") {
        let mut t = Table::new(
            "summary-stages",
            "Stages: nodes executed / cached / failed / skipped and summed node time",
            Origin::Skytie,
            &["stage", "executed", "cached", "failed", "skipped", "seconds"],
        )
        .with_note(
            "seconds = summed node time (nodes run in parallel, so the sum can exceed the wall time); run log: \
             written to run-log/, not tables/",
        );
        for (name, s) in stages {
            let c = |k: &str| fmt_count(num_at(s, k));
            t.push(vec![
                name.clone(),
                c("executed"),
                c("cached"),
                c("failed"),
                c("skipped"),
                fmt_num(num_at(s, "seconds"), 2),
            ]);
        }
        b.run_log_table(page, t);
    }
}

/// Failed / skipped nodes and rejected items with their reasons.
fn problems(b: &mut Builder, page: &mut Page, run: &RunOutputs) {
    let m = &run.metrics;
    page.subheading("Failures, skipped and rejected items");
    let failed = num_at(m, "engine.nodes_failed").unwrap_or(0.0);
    let skipped = num_at(m, "engine.nodes_skipped").unwrap_or(0.0);
    let mut t = Table::new(
        "summary-problems",
        "Failed and skipped nodes",
        Origin::Skytie,
        &["node", "status", "reason"],
    );
    for (key, status, reason_key) in [
        ("engine.failures", "failed", "error"),
        ("engine.skipped_nodes", "skipped", "upstream"),
    ] {
        let mut cur = Some(m);
        for part in key.split('.') {
            cur = cur.and_then(|v| v.get(part));
        }
        if let Some(list) = cur.and_then(|v| v.as_array()) {
            for item in list {
                t.push(vec![
                    item.get("node")
                        .and_then(|v| v.as_str())
                        .unwrap_or("?")
                        .to_string(),
                    status.to_string(),
                    item.get(reason_key)
                        .and_then(|v| v.as_str())
                        .unwrap_or("")
                        .to_string(),
                ]);
            }
        }
    }
    if failed == 0.0 && skipped == 0.0 {
        page.para("No node failed and none was skipped.");
    } else if t.rows.is_empty() {
        b.note(
            page,
            format!(
                "{failed} node(s) failed and {skipped} were skipped; their reasons are printed by `skytie run` \
                 but not recorded in metrics.json"
            ),
        );
    } else {
        b.table(page, t);
    }
    // Rejected items per variant / run, with reasons.
    let mut r = Table::new(
        "summary-rejections",
        "Rejected and skipped items with reasons",
        Origin::Skytie,
        &["result set", "what", "reason", "count"],
    );
    for set in &run.sets {
        let name = if set.name.is_empty() {
            "run"
        } else {
            &set.name
        };
        let sm = &set.metrics;
        if let Some(rej) = obj_at(sm, "nadir.transforms_rejected") {
            for (reason, v) in rej {
                r.push(vec![
                    name.to_string(),
                    "nadir initial transform (recording × aerial image) rejected".into(),
                    super::reasons::transform_rejection(reason),
                    fmt_count(v.as_f64()),
                ]);
            }
        }
        const NOT_LOCATED: &str = "nadir tie point (× aerial image) not located";
        const DROPPED: &str = "nadir tie point (× aerial image) located, dropped";
        for (key, what, reason) in [
            (
                "nadir.unusable_templates",
                NOT_LOCATED,
                "no usable template (touches the vehicle mask, leaves the ortho, or flat)",
            ),
            (
                "nadir.weak_peaks",
                NOT_LOCATED,
                "correlation peak below min_peak",
            ),
            (
                "nadir.beyond_search",
                NOT_LOCATED,
                "found beyond the search margin",
            ),
            (
                "nadir.parallax_rejected",
                NOT_LOCATED,
                "a neighbouring recording shows the template differently (parallax)",
            ),
            (
                "nadir.point_inconsistent",
                DROPPED,
                "departs from its MM object point more than the image's other corners",
            ),
            (
                "nadir.shift_inconsistent",
                DROPPED,
                "its correction disagrees with the image's other corners",
            ),
            (
                "nadir.view_inconsistent",
                DROPPED,
                "another view of the corner lands elsewhere",
            ),
            (
                "nadir.unconfirmed",
                DROPPED,
                "too few located in that image (min_located)",
            ),
            (
                "verify.skipped_single_aerial",
                "verification point skipped",
                "control point seen in one aerial image only",
            ),
            (
                "verify.skipped_mm",
                "verification point skipped",
                "MM triangulation not possible",
            ),
        ] {
            if let Some(v) = num_at(sm, key).filter(|v| *v > 0.0) {
                r.push(vec![
                    name.to_string(),
                    what.into(),
                    reason.into(),
                    fmt_count(Some(v)),
                ]);
            }
        }
        if let Some(adj) = obj_at(sm, "adjust") {
            for (config, a) in adj {
                if let Some(kinds) = a.get("rejected_by_kind").and_then(|v| v.as_object()) {
                    for (kind, v) in kinds {
                        if v.as_f64().unwrap_or(0.0) > 0.0 {
                            r.push(vec![
                                name.to_string(),
                                format!("adjustment {config}: observation rejected"),
                                super::reasons::rejected_observation(kind),
                                fmt_count(v.as_f64()),
                            ]);
                        }
                    }
                }
            }
        }
    }
    if r.rows.is_empty() {
        page.para("No item was rejected.");
    } else {
        b.table(page, r);
    }
}
