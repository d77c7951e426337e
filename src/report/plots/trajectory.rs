//! The trajectory map (thesis Figs 4.17, 5.5–5.7): recorded, adjusted and true recording positions, the
//! recordings coloured by whether they have nadir / oblique correspondences, check points with their error
//! vectors before and after the adjustment (exaggerated by a stated factor), a metric scale bar and a
//! vector-scale bar. Equal metres per pixel on both axes; coordinates are shown relative to a round local
//! origin named in the axis labels.

// `!(x > t)` on purpose: it also rejects NaN, which `x <= t` would let through.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

use super::{
    nice_floor, plot_err, write_svg, BLUE, CAPTION_PX, DARK, FONT, GREY, LABEL_PX, ORANGE, PURPLE,
    TICK_PX, VERMILLION,
};
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};
use std::path::Path;

/// Which aerial correspondences a recording has.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
pub enum CorrespondenceKind {
    None,
    Nadir,
    Oblique,
    Both,
}

impl CorrespondenceKind {
    pub fn from_flags(nadir: bool, oblique: bool) -> Self {
        match (nadir, oblique) {
            (false, false) => Self::None,
            (true, false) => Self::Nadir,
            (false, true) => Self::Oblique,
            (true, true) => Self::Both,
        }
    }
    fn label(self) -> &'static str {
        match self {
            Self::None => "no aerial correspondence",
            Self::Nadir => "nadir correspondences",
            Self::Oblique => "oblique correspondences",
            Self::Both => "nadir + oblique correspondences",
        }
    }
    fn color(self) -> RGBColor {
        match self {
            Self::None => GREY,
            Self::Nadir => BLUE,
            Self::Oblique => ORANGE,
            Self::Both => PURPLE,
        }
    }
}

/// One recording on the map (world metres).
#[derive(Clone, Copy)]
pub struct MapRecording {
    pub recorded: [f64; 2],
    pub adjusted: Option<[f64; 2]>,
    pub truth: Option<[f64; 2]>,
    pub kind: CorrespondenceKind,
}

/// One check point with its horizontal error vectors (estimated − true, metres).
#[derive(Clone, Copy)]
pub struct MapCheckPoint {
    pub position: [f64; 2],
    pub error_before: Option<[f64; 2]>,
    pub error_after: Option<[f64; 2]>,
}

/// What the figure needs to say about its exaggeration (also used in the HTML caption).
pub struct MapScales {
    /// Error vectors are drawn this many times their length.
    pub exaggeration: f64,
    /// The metric scale bar's length, m.
    pub scale_bar_m: f64,
    /// The vector-scale bar's error length, m.
    pub vector_bar_m: f64,
}

/// The exaggeration so that the largest error vector is drawn about 8 % of the map's extent long,
/// rounded down to 1, 2 or 5 × 10^k (at least 1).
pub fn exaggeration_for(extent_m: f64, max_error_m: f64) -> f64 {
    if !(max_error_m > 0.0) || !(extent_m > 0.0) {
        return 1.0;
    }
    nice_floor(0.08 * extent_m / max_error_m).max(1.0)
}

/// Draws the map into `path` (SVG) and returns the scales used.
pub fn trajectory_map(
    path: &Path,
    title: &str,
    recordings: &[MapRecording],
    checkpoints: &[MapCheckPoint],
) -> Result<MapScales, String> {
    let fig = "trajectory map";
    let mut xs: Vec<f64> = Vec::new();
    let mut ys: Vec<f64> = Vec::new();
    for r in recordings {
        for p in [Some(r.recorded), r.adjusted, r.truth]
            .into_iter()
            .flatten()
        {
            xs.push(p[0]);
            ys.push(p[1]);
        }
    }
    for c in checkpoints {
        xs.push(c.position[0]);
        ys.push(c.position[1]);
    }
    if xs.is_empty() {
        return Err(format!("figure {fig}: no positions to draw"));
    }
    let min = |v: &[f64]| v.iter().cloned().fold(f64::INFINITY, f64::min);
    let max = |v: &[f64]| v.iter().cloned().fold(f64::NEG_INFINITY, f64::max);
    let (x0, x1, y0, y1) = (min(&xs), max(&xs), min(&ys), max(&ys));
    let extent = (x1 - x0).max(y1 - y0).max(10.0);
    let pad = 0.12 * extent;
    // Round local origin, so tick labels stay short.
    let origin = [
        ((x0 - pad) / 100.0).floor() * 100.0,
        ((y0 - pad) / 100.0).floor() * 100.0,
    ];
    let (mut lx0, mut lx1) = (x0 - pad - origin[0], x1 + pad - origin[0]);
    let (mut ly0, mut ly1) = (y0 - pad - origin[1], y1 + pad - origin[1]);
    // Equal scale: the plot area is plot_w × plot_h pixels.
    let plot_w = 820.0;
    let aspect = ((ly1 - ly0) / (lx1 - lx0)).clamp(0.45, 1.2);
    let plot_h = (plot_w * aspect).round();
    let m_per_px = ((lx1 - lx0) / plot_w).max((ly1 - ly0) / plot_h);
    let (cx, cy) = ((lx0 + lx1) / 2.0, (ly0 + ly1) / 2.0);
    lx0 = cx - m_per_px * plot_w / 2.0;
    lx1 = cx + m_per_px * plot_w / 2.0;
    ly0 = cy - m_per_px * plot_h / 2.0;
    ly1 = cy + m_per_px * plot_h / 2.0;
    let max_err = checkpoints
        .iter()
        .flat_map(|c| [c.error_before, c.error_after].into_iter().flatten())
        .map(|e| e[0].hypot(e[1]))
        .filter(|v| v.is_finite())
        .fold(0.0f64, f64::max);
    let exaggeration = exaggeration_for(extent, max_err);
    let scale_bar_m = nice_floor((lx1 - lx0) / 5.0);
    let vector_bar_m = nice_floor(if max_err > 0.0 { max_err } else { 0.1 });
    // Legend rows: recorded, true (if any), one per correspondence kind, check point + its two vectors.
    let n_kinds = {
        let mut k: Vec<CorrespondenceKind> = recordings.iter().map(|r| r.kind).collect();
        k.sort();
        k.dedup();
        k.len() as u32
    };
    let legend_rows = 1
        + u32::from(recordings.iter().any(|r| r.truth.is_some()))
        + n_kinds
        + if checkpoints.is_empty() { 0 } else { 3 };
    let (width, height) = (
        plot_w as u32 + 90 + 30,
        plot_h as u32 + 60 + 70 + 22 * legend_rows,
    );
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, (width, height)).into_drawing_area();
        root.fill(&WHITE).map_err(plot_err(fig))?;
        let (plot_area, legend_area) = root.split_vertically(height - 22 * legend_rows - 10);
        let mut chart = ChartBuilder::on(&plot_area)
            .caption(title, (FONT, CAPTION_PX))
            .margin_left(10)
            .margin_right(30)
            .margin_top(10)
            .x_label_area_size(50)
            .y_label_area_size(80)
            .build_cartesian_2d(lx0..lx1, ly0..ly1)
            .map_err(plot_err(fig))?;
        chart
            .configure_mesh()
            .x_desc(format!("easting − {:.0} [m]", origin[0]))
            .y_desc(format!("northing − {:.0} [m]", origin[1]))
            .x_label_formatter(&|v| trim(*v))
            .y_label_formatter(&|v| trim(*v))
            .axis_desc_style((FONT, LABEL_PX))
            .label_style((FONT, TICK_PX))
            .light_line_style(WHITE.mix(0.0))
            .draw()
            .map_err(plot_err(fig))?;
        let local = |p: [f64; 2]| (p[0] - origin[0], p[1] - origin[1]);
        // Recorded: hollow grey circles; true: black crosses; adjusted: filled, coloured by correspondences.
        chart
            .draw_series(
                recordings
                    .iter()
                    .map(|r| Circle::new(local(r.recorded), 6, GREY.stroke_width(1))),
            )
            .map_err(plot_err(fig))?;
        chart
            .draw_series(
                recordings
                    .iter()
                    .filter_map(|r| r.truth)
                    .map(|p| Cross::new(local(p), 4, BLACK.stroke_width(1))),
            )
            .map_err(plot_err(fig))?;
        chart
            .draw_series(recordings.iter().map(|r| {
                Circle::new(
                    local(r.adjusted.unwrap_or(r.recorded)),
                    3,
                    r.kind.color().filled(),
                )
            }))
            .map_err(plot_err(fig))?;
        // Error vectors, exaggerated.
        let arrow = |from: (f64, f64), e: [f64; 2], color: RGBColor| {
            let to = (from.0 + e[0] * exaggeration, from.1 + e[1] * exaggeration);
            let len = (to.0 - from.0).hypot(to.1 - from.1);
            let mut parts = vec![PathElement::new(vec![from, to], color.stroke_width(2))];
            if len > 0.0 {
                let head = (len * 0.3).min(8.0 * m_per_px);
                let ang = (to.1 - from.1).atan2(to.0 - from.0);
                for s in [-0.45f64, 0.45] {
                    let a = ang + std::f64::consts::PI + s;
                    parts.push(PathElement::new(
                        vec![to, (to.0 + head * a.cos(), to.1 + head * a.sin())],
                        color.stroke_width(2),
                    ));
                }
            }
            parts
        };
        let mut vectors = Vec::new();
        for c in checkpoints {
            let p = local(c.position);
            if let Some(e) = c.error_before {
                vectors.extend(arrow(p, e, GREY));
            }
            if let Some(e) = c.error_after {
                vectors.extend(arrow(p, e, VERMILLION));
            }
        }
        chart.draw_series(vectors).map_err(plot_err(fig))?;
        chart
            .draw_series(
                checkpoints
                    .iter()
                    .map(|c| TriangleMarker::new(local(c.position), 6, DARK.filled())),
            )
            .map_err(plot_err(fig))?;
        // Scale bars in the lower-right corner of the plot.
        let bar_y = ly0 + 14.0 * m_per_px;
        let bar_x1 = lx1 - 20.0 * m_per_px;
        let text = TextStyle::from((FONT, TICK_PX).into_font())
            .color(&DARK)
            .pos(Pos::new(HPos::Right, VPos::Center));
        let bars = [
            (scale_bar_m, bar_y, DARK, format!("{} m", trim(scale_bar_m))),
            (
                vector_bar_m * exaggeration,
                bar_y + 22.0 * m_per_px,
                VERMILLION,
                format!(
                    "error vector {} m (×{})",
                    trim(vector_bar_m),
                    trim(exaggeration)
                ),
            ),
        ];
        for (len, y, color, label) in bars {
            chart
                .draw_series(std::iter::once(PathElement::new(
                    vec![(bar_x1 - len, y), (bar_x1, y)],
                    color.stroke_width(4),
                )))
                .map_err(plot_err(fig))?;
            let (px, py) = chart.backend_coord(&(bar_x1 - len, y));
            root.draw(&Text::new(label, (px - 8, py), text.clone()))
                .map_err(plot_err(fig))?;
        }
        // Legend (own area below the plot: never covers data).
        let legend_font = TextStyle::from((FONT, LABEL_PX).into_font())
            .color(&DARK)
            .pos(Pos::new(HPos::Left, VPos::Center));
        let mut kinds: Vec<CorrespondenceKind> = recordings.iter().map(|r| r.kind).collect();
        kinds.sort();
        kinds.dedup();
        let mut row = 0i32;
        let x = 100i32;
        let y_of = |row: i32| 12 + 22 * row;
        let draw_text = |row: i32, s: &str| {
            legend_area.draw(&Text::new(
                s.to_string(),
                (x + 24, y_of(row)),
                legend_font.clone(),
            ))
        };
        legend_area
            .draw(&Circle::new((x + 8, y_of(row)), 6, GREY.stroke_width(1)))
            .map_err(plot_err(fig))?;
        draw_text(row, "recorded position").map_err(plot_err(fig))?;
        row += 1;
        if recordings.iter().any(|r| r.truth.is_some()) {
            legend_area
                .draw(&Cross::new((x + 8, y_of(row)), 4, BLACK.stroke_width(1)))
                .map_err(plot_err(fig))?;
            draw_text(row, "true position (truth/)").map_err(plot_err(fig))?;
            row += 1;
        }
        let adjusted_word = if recordings.iter().any(|r| r.adjusted.is_some()) {
            "adjusted position"
        } else {
            "recorded position"
        };
        for k in kinds {
            legend_area
                .draw(&Circle::new((x + 8, y_of(row)), 3, k.color().filled()))
                .map_err(plot_err(fig))?;
            draw_text(row, &format!("{adjusted_word}, {}", k.label())).map_err(plot_err(fig))?;
            row += 1;
        }
        if !checkpoints.is_empty() {
            legend_area
                .draw(&TriangleMarker::new((x + 8, y_of(row)), 6, DARK.filled()))
                .map_err(plot_err(fig))?;
            draw_text(row, "check point").map_err(plot_err(fig))?;
            row += 1;
            for (color, s) in [
                (GREY, "check-point error before adjustment (exaggerated)"),
                (
                    VERMILLION,
                    "check-point error after adjustment (exaggerated)",
                ),
            ] {
                legend_area
                    .draw(&PathElement::new(
                        vec![(x, y_of(row)), (x + 18, y_of(row))],
                        color.stroke_width(2),
                    ))
                    .map_err(plot_err(fig))?;
                draw_text(row, s).map_err(plot_err(fig))?;
                row += 1;
            }
        }
        root.present().map_err(plot_err(fig))?;
    }
    write_svg(path, &svg)?;
    Ok(MapScales {
        exaggeration,
        scale_bar_m,
        vector_bar_m,
    })
}

/// A number without trailing zeros ("0.05", "200").
pub fn trim(v: f64) -> String {
    let s = format!("{v:.6}");
    let s = s.trim_end_matches('0').trim_end_matches('.');
    s.to_string()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn exaggeration_is_nice_and_at_least_one() {
        // 200 m extent, 5 cm largest error: 16 m / 0.05 m = 320 -> 200.
        assert_eq!(exaggeration_for(200.0, 0.05), 200.0);
        assert_eq!(exaggeration_for(10.0, 5.0), 1.0);
        assert_eq!(exaggeration_for(10.0, 0.0), 1.0);
    }

    #[test]
    fn trims_numbers() {
        assert_eq!(trim(0.05), "0.05");
        assert_eq!(trim(200.0), "200");
    }
}
