//! The report's figures, drawn with plotters' SVG backend (no system fonts or C libraries: text is SVG
//! `<text>`, laid out by the browser). One file per figure kind; every figure is written atomically as
//! an `.svg` file next to the page, so identical inputs give byte-identical files.

// `!(x > t)` on purpose: it also rejects NaN, which `x <= t` would let through.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

pub mod bars;
pub mod histogram;
pub mod trajectory;

use plotters::style::RGBColor;
use std::path::Path;

/// Font family and sizes used in every figure.
pub const FONT: &str = "sans-serif";
pub const CAPTION_PX: u32 = 20;
pub const LABEL_PX: u32 = 15;
pub const TICK_PX: u32 = 13;

/// Colours shared by the figures (colour-blind friendly Okabe–Ito palette).
pub const BLUE: RGBColor = RGBColor(0, 114, 178);
pub const ORANGE: RGBColor = RGBColor(230, 159, 0);
pub const GREEN: RGBColor = RGBColor(0, 158, 115);
pub const VERMILLION: RGBColor = RGBColor(213, 94, 0);
pub const PURPLE: RGBColor = RGBColor(204, 121, 167);
pub const GREY: RGBColor = RGBColor(150, 150, 150);
pub const DARK: RGBColor = RGBColor(40, 40, 40);

/// Writes an SVG document atomically.
pub fn write_svg(path: &Path, svg: &str) -> Result<(), String> {
    skytie_util::fsutil::atomic_write(path, svg.as_bytes())
        .map_err(|e| format!("{}: cannot write: {e}", path.display()))
}

/// A "nice" number (1, 2 or 5 × 10^k) close to `x` (x > 0), rounding down.
pub fn nice_floor(x: f64) -> f64 {
    if !(x > 0.0) || !x.is_finite() {
        return 1.0;
    }
    let p = 10f64.powf(x.log10().floor());
    let m = x / p;
    let n = if m >= 5.0 {
        5.0
    } else if m >= 2.0 {
        2.0
    } else {
        1.0
    };
    n * p
}

/// Converts a plotters error to a message naming the figure.
pub fn plot_err<E: std::fmt::Debug>(figure: &str) -> impl Fn(E) -> String + '_ {
    move |e| format!("figure {figure}: drawing failed: {e:?}")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn nice_numbers() {
        assert_eq!(nice_floor(7.0), 5.0);
        assert_eq!(nice_floor(0.34), 0.2);
        assert_eq!(nice_floor(100.0), 100.0);
        assert_eq!(nice_floor(1.9), 1.0);
        assert_eq!(nice_floor(-1.0), 1.0);
    }
}
