//! Residual histograms: the distribution of one quantity (e.g. check-point 2D error, metres) for up to a
//! few series (before / after the adjustment) on shared bins, bars of a bin side by side.

use super::trajectory::trim;
use super::{nice_floor, plot_err, write_svg, CAPTION_PX, FONT, LABEL_PX, TICK_PX};
use plotters::prelude::*;
use std::path::Path;

/// One series of samples with its legend name and colour.
pub struct HistSeries {
    pub name: String,
    pub color: RGBColor,
    pub samples: Vec<f64>,
}

/// Bin edges for non-negative samples: a nice bin width giving about `target_bins` bins from 0.
pub fn bin_width(max_value: f64, target_bins: usize) -> f64 {
    let w = nice_floor(max_value / target_bins.max(1) as f64);
    // Make sure the bins cover the maximum with at most 2·target bins.
    if max_value / w > 2.0 * target_bins as f64 {
        w * 2.0
    } else {
        w
    }
}

/// Counts per bin [k·w, (k+1)·w) for k = 0..bins; values beyond the last bin go into the last one.
pub fn bin_counts(samples: &[f64], width: f64, bins: usize) -> Vec<usize> {
    let mut c = vec![0usize; bins];
    for &s in samples {
        if !s.is_finite() || bins == 0 {
            continue;
        }
        let k = ((s.max(0.0) / width).floor() as usize).min(bins - 1);
        c[k] += 1;
    }
    c
}

/// Draws the histogram into `path` (SVG). Samples are absolute values (errors), `x_desc` with unit.
pub fn histogram(
    path: &Path,
    title: &str,
    x_desc: &str,
    series: &[HistSeries],
) -> Result<(), String> {
    let fig = "histogram";
    let max_v = series
        .iter()
        .flat_map(|s| s.samples.iter())
        .fold(0.0f64, |a, &b| if b.is_finite() { a.max(b) } else { a });
    let width = bin_width(if max_v > 0.0 { max_v } else { 1.0 }, 10);
    let bins = ((max_v / width).floor() as usize + 1).max(1);
    let counts: Vec<Vec<usize>> = series
        .iter()
        .map(|s| bin_counts(&s.samples, width, bins))
        .collect();
    let max_count = counts.iter().flatten().copied().max().unwrap_or(0).max(1);
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, (800, 420)).into_drawing_area();
        root.fill(&WHITE).map_err(plot_err(fig))?;
        let mut chart = ChartBuilder::on(&root)
            .caption(title, (FONT, CAPTION_PX))
            .margin(14)
            .x_label_area_size(50)
            .y_label_area_size(60)
            .build_cartesian_2d(0.0..(bins as f64 * width), 0.0..(max_count as f64 * 1.15))
            .map_err(plot_err(fig))?;
        chart
            .configure_mesh()
            .x_desc(x_desc)
            .x_label_formatter(&|v| trim(*v))
            .y_desc("count")
            .y_label_formatter(&|v| {
                if (v - v.round()).abs() < 1e-9 {
                    format!("{v:.0}")
                } else {
                    String::new()
                }
            })
            .axis_desc_style((FONT, LABEL_PX))
            .label_style((FONT, TICK_PX))
            .disable_x_mesh()
            .draw()
            .map_err(plot_err(fig))?;
        let groups = series.len().max(1) as f64;
        for (si, s) in series.iter().enumerate() {
            let style = s.color.filled();
            let sub = width * 0.9 / groups;
            chart
                .draw_series(counts[si].iter().enumerate().filter(|(_, &c)| c > 0).map(
                    |(k, &c)| {
                        let x0 = k as f64 * width + width * 0.05 + sub * si as f64;
                        Rectangle::new([(x0, 0.0), (x0 + sub, c as f64)], style)
                    },
                ))
                .map_err(plot_err(fig))?
                .label(s.name.clone())
                .legend(move |(x, y)| Rectangle::new([(x, y - 6), (x + 14, y + 6)], style));
        }
        chart
            .configure_series_labels()
            .position(SeriesLabelPosition::UpperRight)
            .label_font((FONT, LABEL_PX))
            .background_style(WHITE.mix(0.9))
            .border_style(BLACK)
            .draw()
            .map_err(plot_err(fig))?;
        root.present().map_err(plot_err(fig))?;
    }
    write_svg(path, &svg)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn counts_fall_into_the_right_bins() {
        let c = bin_counts(&[0.0, 0.009, 0.01, 0.035, 0.5, f64::NAN], 0.01, 4);
        assert_eq!(c, vec![2, 1, 0, 2]);
    }

    #[test]
    fn bin_width_is_nice_and_covers_the_range() {
        let w = bin_width(0.34, 10);
        assert_eq!(w, 0.02);
        assert!(0.34 / w <= 20.0);
    }
}
