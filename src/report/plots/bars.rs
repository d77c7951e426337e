//! Horizontal grouped bar charts: one row per category (e.g. a sweep variant), one bar per series (e.g.
//! inliers / outliers / non-matchable, or RMSE before / after), like thesis Figs 4.12, 4.14, 4.19. The
//! category names are drawn left of the plot in a label column sized to the longest name, so long variant
//! names never overlap.

use super::trajectory::trim;
use super::{plot_err, write_svg, CAPTION_PX, DARK, FONT, LABEL_PX, TICK_PX};
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};
use std::path::Path;

/// One series: its legend name, colour and one value per category (None = missing, no bar).
pub struct BarSeries {
    pub name: String,
    pub color: RGBColor,
    pub values: Vec<Option<f64>>,
}

/// Draws the chart into `path` (SVG). `x_desc` names the value axis with its unit.
pub fn grouped_bars(
    path: &Path,
    title: &str,
    x_desc: &str,
    categories: &[String],
    series: &[BarSeries],
) -> Result<(), String> {
    let fig = "bars";
    let n = categories.len().max(1);
    let groups = series.len().max(1);
    let row_px = (14 * groups as u32 + 10).max(26);
    let legend_px = 24 * groups as u32 + 20;
    let label_col_px = categories
        .iter()
        .map(|c| c.chars().count() as u32)
        .max()
        .unwrap_or(4)
        * 8
        + 16;
    let width = (label_col_px + 760).max(700);
    let height = 60 + 60 + row_px * n as u32 + legend_px;
    let max_v = series
        .iter()
        .flat_map(|s| s.values.iter().flatten())
        .fold(0.0f64, |a, &b| if b.is_finite() { a.max(b) } else { a });
    let x_max = if max_v > 0.0 { max_v * 1.08 } else { 1.0 };
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, (width, height)).into_drawing_area();
        root.fill(&WHITE).map_err(plot_err(fig))?;
        let (plot_area, legend_area) = root.split_vertically(height - legend_px);
        let mut chart = ChartBuilder::on(&plot_area)
            .caption(title, (FONT, CAPTION_PX))
            .margin(12)
            .x_label_area_size(50)
            .y_label_area_size(label_col_px)
            .build_cartesian_2d(0.0..x_max, -0.5..(n as f64 - 0.5))
            .map_err(plot_err(fig))?;
        chart
            .configure_mesh()
            .disable_y_mesh()
            .y_labels(0)
            .x_desc(x_desc)
            .x_label_formatter(&|v| trim(*v))
            .axis_desc_style((FONT, LABEL_PX))
            .label_style((FONT, TICK_PX))
            .draw()
            .map_err(plot_err(fig))?;
        let band = 0.8 / groups as f64;
        for (si, s) in series.iter().enumerate() {
            let style = s.color.filled();
            chart
                .draw_series(s.values.iter().enumerate().filter_map(|(ci, v)| {
                    let v = (*v)?;
                    if !v.is_finite() {
                        return None;
                    }
                    // Category ci is centred at y = n-1-ci (first category on top).
                    let yc = (n - 1 - ci) as f64;
                    let y0 = yc + 0.4 - band * (si as f64 + 1.0);
                    Some(Rectangle::new([(0.0, y0), (v, y0 + band * 0.9)], style))
                }))
                .map_err(plot_err(fig))?;
        }
        // Category names, right-aligned against the plot's left edge.
        let label_style = TextStyle::from((FONT, TICK_PX).into_font())
            .color(&DARK)
            .pos(Pos::new(HPos::Right, VPos::Center));
        for (ci, name) in categories.iter().enumerate() {
            let (px, py) = chart.backend_coord(&(0.0, (n - 1 - ci) as f64));
            root.draw(&Text::new(name.clone(), (px - 6, py), label_style.clone()))
                .map_err(plot_err(fig))?;
        }
        // Legend below the plot: one swatch and name per series.
        for (si, s) in series.iter().enumerate() {
            let y = 10 + 24 * si as i32;
            let x = label_col_px as i32;
            legend_area
                .draw(&Rectangle::new(
                    [(x, y), (x + 18, y + 14)],
                    s.color.filled(),
                ))
                .map_err(plot_err(fig))?;
            legend_area
                .draw(&Text::new(
                    s.name.clone(),
                    (x + 26, y + 7),
                    TextStyle::from((FONT, LABEL_PX).into_font())
                        .color(&DARK)
                        .pos(Pos::new(HPos::Left, VPos::Center)),
                ))
                .map_err(plot_err(fig))?;
        }
        root.present().map_err(plot_err(fig))?;
    }
    write_svg(path, &svg)
}
