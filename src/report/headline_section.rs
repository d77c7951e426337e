//! The report's first section: the answer a surveyor reads in five seconds ([`super::headline`], the same
//! numbers the terminal can print), the sign convention, and the verification of the adjusted trajectory per
//! segment.

use super::headline::{SegmentLine, Status};
use super::html::{escape, Page};
use super::inputs::ResultSet;
use super::tables::{fmt_num, Origin, Table};
use super::Builder;

/// The sentence stating the sign conventions of every number in the report and the output files.
pub const SIGN_CONVENTION: &str = "Sign convention everywhere: a correction is adjusted − recorded position; a \
    verification offset is MM − aerial (the control point triangulated from the panoramas with the given poses \
    minus its aerial triangulation: how far the trajectory is off); a check-point error is estimated − surveyed.";

/// Row indices of verification segments, most interesting first, for the page of a long table: the overall
/// row (label `all`), then failed segments, insufficient ones (too few points, a stretch without any, or after adjustment a stated σ too large for the tolerance), passed ones; within each by
/// decreasing horizontal offset (missing offsets last), ties in table order.
pub fn rank_segments(rows: &[(&str, &str, Option<f64>)]) -> Vec<usize> {
    let class = |label: &str, status: &str| match (label, status) {
        ("all", _) => 0,
        (_, "fail") => 1,
        (_, "insufficient") => 2,
        (_, "pass") => 4,
        _ => 3,
    };
    let mut order: Vec<usize> = (0..rows.len()).collect();
    order.sort_by(|&a, &b| {
        let (la, sa, oa) = rows[a];
        let (lb, sb, ob) = rows[b];
        class(la, &sa.to_lowercase())
            .cmp(&class(lb, &sb.to_lowercase()))
            .then_with(|| {
                ob.unwrap_or(f64::NEG_INFINITY)
                    .total_cmp(&oa.unwrap_or(f64::NEG_INFINITY))
            })
            .then(a.cmp(&b))
    });
    order
}

/// What [`rank_segments`] shows first, for the line under a long table.
pub const RANKED_SEGMENTS: &str =
    "failed segments first, then insufficient ones (too few points, a stretch without any, or after adjustment a stated σ too large for the tolerance), each by decreasing offset";

fn segment_table(id: &str, title: &str, segments: &[SegmentLine]) -> Table {
    let mut t = Table::new(
        id,
        title,
        Origin::Skytie,
        &[
            "segment",
            "first recording",
            "last recording",
            "points",
            "mean offset 2D [m]",
            "verdict",
        ],
    );
    let keys: Vec<(&str, &str, Option<f64>)> = segments
        .iter()
        .map(|s| (s.label.as_str(), s.status.as_str(), s.offset_2d_m))
        .collect();
    let ranked = rank_segments(&keys);
    for s in segments {
        t.push(vec![
            s.label.clone(),
            s.first.clone(),
            s.last.clone(),
            s.points.to_string(),
            fmt_num(s.offset_2d_m, 3),
            match s.status.as_str() {
                "pass" => "pass".to_string(),
                "fail" => "FAIL: the mean offset exceeds the tolerance significantly".to_string(),
                "insufficient" => "not judged: too few control points".to_string(),
                other => other.to_string(),
            },
        ]);
    }
    t.rank_for_html(ranked, RANKED_SEGMENTS)
}

/// Appends the headline of `set` to `page`.
pub fn headline_section(
    b: &mut Builder,
    page: &mut Page,
    set: &ResultSet,
    prefix: &str,
) -> Result<(), String> {
    page.heading(&format!("{prefix}answer"), "Result");
    let h = match b.cache.headline(&set.dir) {
        Ok(h) => h,
        Err(e) => {
            b.note(page, format!("no result summary: {e}"));
            return Ok(());
        }
    };
    let warn = matches!(h.status, Status::NotCorrected(_) | Status::Worse(_)) || h.unverified();
    let mut lines = h.lines().into_iter();
    let status = lines.next().unwrap_or_default();
    let mut html = format!(
        "<div class=\"headline{}\" id=\"{prefix}headline\"><p class=\"status\">{}</p><ul>\n",
        if warn { " warn" } else { "" },
        escape(&status)
    );
    for l in lines {
        html.push_str(&format!("<li>{}</li>\n", escape(&l)));
    }
    html.push_str("</ul></div>\n");
    page.raw(&html);
    page.raw(&format!(
        "<p class=\"convention\">{}</p>\n",
        escape(SIGN_CONVENTION)
    ));
    // Only the segments that did not pass, so the map stays on the first screen; all segments follow in the
    // verification section.
    if let Some(v) = &h.verification_after {
        let open: Vec<SegmentLine> = v
            .segments
            .iter()
            .filter(|s| s.status != "pass")
            .cloned()
            .collect();
        if !open.is_empty() {
            b.table(
                page,
                segment_table(
                    &format!("{prefix}verification-adjusted-open"),
                    "Segments of the adjusted trajectory that did not pass (MM − aerial control, adjusted poses)",
                    &open,
                ),
            );
        }
    }
    Ok(())
}

/// The full per-segment verification of the adjusted trajectory (in the verification section).
pub fn adjusted_verification_table(
    b: &mut Builder,
    page: &mut Page,
    set: &ResultSet,
    prefix: &str,
) -> Result<(), String> {
    let Ok(h) = b.cache.headline(&set.dir) else {
        return Ok(());
    };
    if let Some(v) = &h.verification_after {
        b.table(
            page,
            segment_table(
                &format!("{prefix}verification-adjusted"),
                "Verification of the adjusted trajectory per segment (MM − aerial control, adjusted poses)",
                &v.segments,
            )
            .with_note(
                "The same aerial control points and tolerance as the verification of the recorded poses; when \
                 the adjustment used these points this shows agreement, not an independent check (the check \
                 points are).",
            ),
        );
    }
    Ok(())
}
