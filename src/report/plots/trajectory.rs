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
use plotters::coord::types::RangedCoordf64;
use plotters::coord::Shift;
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

/// The map's extent in local coordinates (relative to a round origin), at equal metres per pixel on both axes.
struct MapFrame {
    /// The round local origin, world metres.
    origin: [f64; 2],
    /// Local x and y ranges of the plot area, m.
    x: (f64, f64),
    y: (f64, f64),
    /// Size of the plot area, px.
    plot_w: f64,
    plot_h: f64,
    m_per_px: f64,
    /// The larger side of the drawn positions' bounding box (at least 10 m), m.
    extent_m: f64,
}

impl MapFrame {
    /// The frame around every position of `recordings` and `checkpoints` (an error when there is none).
    fn around(
        recordings: &[MapRecording],
        checkpoints: &[MapCheckPoint],
        fig: &str,
    ) -> Result<MapFrame, String> {
        let points: Vec<[f64; 2]> = recordings
            .iter()
            .flat_map(|r| {
                [Some(r.recorded), r.adjusted, r.truth]
                    .into_iter()
                    .flatten()
            })
            .chain(checkpoints.iter().map(|c| c.position))
            .collect();
        if points.is_empty() {
            return Err(format!("figure {fig}: no positions to draw"));
        }
        let min = |k: usize| points.iter().map(|p| p[k]).fold(f64::INFINITY, f64::min);
        let max = |k: usize| {
            points
                .iter()
                .map(|p| p[k])
                .fold(f64::NEG_INFINITY, f64::max)
        };
        let (x0, x1, y0, y1) = (min(0), max(0), min(1), max(1));
        let extent_m = (x1 - x0).max(y1 - y0).max(10.0);
        let pad = 0.12 * extent_m;
        // Round local origin, so tick labels stay short.
        let origin = [
            ((x0 - pad) / 100.0).floor() * 100.0,
            ((y0 - pad) / 100.0).floor() * 100.0,
        ];
        let (lx0, lx1) = (x0 - pad - origin[0], x1 + pad - origin[0]);
        let (ly0, ly1) = (y0 - pad - origin[1], y1 + pad - origin[1]);
        // Equal scale: the plot area is plot_w × plot_h pixels.
        let plot_w = 820.0;
        let aspect = ((ly1 - ly0) / (lx1 - lx0)).clamp(0.45, 1.2);
        let plot_h = (plot_w * aspect).round();
        let m_per_px = ((lx1 - lx0) / plot_w).max((ly1 - ly0) / plot_h);
        let (cx, cy) = ((lx0 + lx1) / 2.0, (ly0 + ly1) / 2.0);
        let (half_w, half_h) = (m_per_px * plot_w / 2.0, m_per_px * plot_h / 2.0);
        Ok(MapFrame {
            origin,
            x: (cx - half_w, cx + half_w),
            y: (cy - half_h, cy + half_h),
            plot_w,
            plot_h,
            m_per_px,
            extent_m,
        })
    }

    /// A world position in local coordinates.
    fn local(&self, p: [f64; 2]) -> (f64, f64) {
        (p[0] - self.origin[0], p[1] - self.origin[1])
    }
}

/// The correspondence kinds present among `recordings`, in order.
fn kinds_of(recordings: &[MapRecording]) -> Vec<CorrespondenceKind> {
    let mut kinds: Vec<CorrespondenceKind> = recordings.iter().map(|r| r.kind).collect();
    kinds.sort();
    kinds.dedup();
    kinds
}

/// Legend rows: recorded, true (if any), one per correspondence kind, check point + its two vectors.
fn legend_rows(recordings: &[MapRecording], checkpoints: &[MapCheckPoint]) -> u32 {
    1 + u32::from(recordings.iter().any(|r| r.truth.is_some()))
        + kinds_of(recordings).len() as u32
        + if checkpoints.is_empty() { 0 } else { 3 }
}

/// An error vector `e` from `from`, drawn `exaggeration` times its length, with an arrow head.
fn error_arrow(
    from: (f64, f64),
    e: [f64; 2],
    color: RGBColor,
    exaggeration: f64,
    m_per_px: f64,
) -> Vec<PathElement<(f64, f64)>> {
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
}

type MapChart<'a, 'b> =
    ChartContext<'a, SVGBackend<'b>, Cartesian2d<RangedCoordf64, RangedCoordf64>>;

/// Recorded positions (hollow grey circles), true ones (black crosses), adjusted ones (filled, coloured by
/// correspondences), the check points and their exaggerated error vectors before and after.
fn draw_positions(
    chart: &mut MapChart<'_, '_>,
    frame: &MapFrame,
    recordings: &[MapRecording],
    checkpoints: &[MapCheckPoint],
    exaggeration: f64,
    fig: &str,
) -> Result<(), String> {
    let local = |p: [f64; 2]| frame.local(p);
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
    let mut vectors = Vec::new();
    for c in checkpoints {
        let p = local(c.position);
        for (e, color) in [(c.error_before, GREY), (c.error_after, VERMILLION)] {
            if let Some(e) = e {
                vectors.extend(error_arrow(p, e, color, exaggeration, frame.m_per_px));
            }
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
    Ok(())
}

/// The metric and the vector scale bars in the lower-right corner of the plot.
fn draw_scale_bars(
    root: &DrawingArea<SVGBackend<'_>, Shift>,
    chart: &mut MapChart<'_, '_>,
    frame: &MapFrame,
    scales: &MapScales,
    fig: &str,
) -> Result<(), String> {
    let m_per_px = frame.m_per_px;
    let bar_y = frame.y.0 + 14.0 * m_per_px;
    let bar_x1 = frame.x.1 - 20.0 * m_per_px;
    let text = TextStyle::from((FONT, TICK_PX).into_font())
        .color(&DARK)
        .pos(Pos::new(HPos::Right, VPos::Center));
    let vector_label = format!(
        "error vector {} m (×{})",
        trim(scales.vector_bar_m),
        trim(scales.exaggeration)
    );
    let bars = [
        (
            scales.scale_bar_m,
            bar_y,
            DARK,
            format!("{} m", trim(scales.scale_bar_m)),
        ),
        (
            scales.vector_bar_m * scales.exaggeration,
            bar_y + 22.0 * m_per_px,
            VERMILLION,
            vector_label,
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
    Ok(())
}

/// The legend, in its own area below the plot (it never covers data): one row per symbol drawn.
fn draw_legend(
    area: &DrawingArea<SVGBackend<'_>, Shift>,
    recordings: &[MapRecording],
    checkpoints: &[MapCheckPoint],
    fig: &str,
) -> Result<(), String> {
    let font = TextStyle::from((FONT, LABEL_PX).into_font())
        .color(&DARK)
        .pos(Pos::new(HPos::Left, VPos::Center));
    let x = 100i32;
    let y_of = |row: i32| 12 + 22 * row;
    let mut row = 0i32;
    // Draws one row: its symbol (drawn by `symbol` at the row's symbol position) and its text.
    let mut add = |symbol: &dyn Fn((i32, i32)) -> Result<(), String>, s: &str| {
        symbol((x + 8, y_of(row)))?;
        area.draw(&Text::new(s.to_string(), (x + 24, y_of(row)), font.clone()))
            .map_err(plot_err(fig))?;
        row += 1;
        Ok::<(), String>(())
    };
    let circle = |r: i32, style: ShapeStyle| {
        move |at: (i32, i32)| area.draw(&Circle::new(at, r, style)).map_err(plot_err(fig))
    };
    add(&circle(6, GREY.stroke_width(1)), "recorded position")?;
    if recordings.iter().any(|r| r.truth.is_some()) {
        let cross = |at| {
            area.draw(&Cross::new(at, 4, BLACK.stroke_width(1)))
                .map_err(plot_err(fig))
        };
        add(&cross, "true position (truth/)")?;
    }
    let adjusted_word = if recordings.iter().any(|r| r.adjusted.is_some()) {
        "adjusted position"
    } else {
        "recorded position"
    };
    for k in kinds_of(recordings) {
        add(
            &circle(3, k.color().filled()),
            &format!("{adjusted_word}, {}", k.label()),
        )?;
    }
    if !checkpoints.is_empty() {
        let triangle = |at| {
            area.draw(&TriangleMarker::new(at, 6, DARK.filled()))
                .map_err(plot_err(fig))
        };
        add(&triangle, "check point")?;
        for (color, s) in [
            (GREY, "check-point error before adjustment (exaggerated)"),
            (
                VERMILLION,
                "check-point error after adjustment (exaggerated)",
            ),
        ] {
            let line = |(sx, sy): (i32, i32)| {
                area.draw(&PathElement::new(
                    vec![(sx - 8, sy), (sx + 10, sy)],
                    color.stroke_width(2),
                ))
                .map_err(plot_err(fig))
            };
            add(&line, s)?;
        }
    }
    Ok(())
}

/// Draws the map into `path` (SVG) and returns the scales used.
pub fn trajectory_map(
    path: &Path,
    title: &str,
    recordings: &[MapRecording],
    checkpoints: &[MapCheckPoint],
) -> Result<MapScales, String> {
    let fig = "trajectory map";
    let frame = MapFrame::around(recordings, checkpoints, fig)?;
    let max_err = checkpoints
        .iter()
        .flat_map(|c| [c.error_before, c.error_after].into_iter().flatten())
        .map(|e| e[0].hypot(e[1]))
        .filter(|v| v.is_finite())
        .fold(0.0f64, f64::max);
    let scales = MapScales {
        exaggeration: exaggeration_for(frame.extent_m, max_err),
        scale_bar_m: nice_floor((frame.x.1 - frame.x.0) / 5.0),
        vector_bar_m: nice_floor(if max_err > 0.0 { max_err } else { 0.1 }),
    };
    let legend_rows = legend_rows(recordings, checkpoints);
    let (width, height) = (
        frame.plot_w as u32 + 90 + 30,
        frame.plot_h as u32 + 60 + 70 + 22 * legend_rows,
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
            .build_cartesian_2d(frame.x.0..frame.x.1, frame.y.0..frame.y.1)
            .map_err(plot_err(fig))?;
        chart
            .configure_mesh()
            .x_desc(format!("easting − {:.0} [m]", frame.origin[0]))
            .y_desc(format!("northing − {:.0} [m]", frame.origin[1]))
            .x_label_formatter(&|v| trim(*v))
            .y_label_formatter(&|v| trim(*v))
            .axis_desc_style((FONT, LABEL_PX))
            .label_style((FONT, TICK_PX))
            .light_line_style(WHITE.mix(0.0))
            .draw()
            .map_err(plot_err(fig))?;
        draw_positions(
            &mut chart,
            &frame,
            recordings,
            checkpoints,
            scales.exaggeration,
            fig,
        )?;
        draw_scale_bars(&root, &mut chart, &frame, &scales, fig)?;
        draw_legend(&legend_area, recordings, checkpoints, fig)?;
        root.present().map_err(plot_err(fig))?;
    }
    write_svg(path, &svg)?;
    Ok(scales)
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
