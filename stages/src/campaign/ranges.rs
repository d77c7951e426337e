//! Plausible ranges of single campaign values, shared by every table reader: a value outside them is valid as
//! a number but cannot be what the column means (a coordinate of 1e30 m, a heading of 720°, a σ of 1e-30 m, a
//! principal distance of 1e-9 px). Such a row is rejected with a message that says which range was expected.

use super::problem::ProblemKind;
use super::table::Fields;

/// Largest |x|, |y| of a projected coordinate, metres (UTM northings stay below 1e7; zone-prefixed eastings
/// below 1e8).
pub(crate) const MAX_ABS_XY_M: f64 = 1e8;
/// Largest |z|, metres: no camera or surveyed point on Earth is farther from sea level.
pub(crate) const MAX_ABS_Z_M: f64 = 1e4;
/// A-priori σ of a position, metres: below 1 µm the value is no measurement precision (a unit mistake; an
/// adjusted trajectory read back as input may carry posterior σ well below a millimetre, so the bound sits
/// lower than any survey); above 1 km the value is no position at all.
pub(crate) const SIGMA_M: (f64, f64) = (1e-6, 1e3);
/// Image measurement σ, pixels.
pub(crate) const SIGMA_PX: (f64, f64) = (1e-3, 100.0);
/// Field of view of a frame camera across its image diagonal, degrees: outside it the principal distance does
/// not belong to this image size (a wrong unit, mm instead of px, or a typo).
pub(crate) const FRAME_FOV_DEG: (f64, f64) = (0.1, 170.0);
/// Smallest and largest side of an image, pixels.
pub(crate) const IMAGE_SIDE_PX: (u32, u32) = (8, 1_000_000);

/// x, y, z must be coordinates in metres of a projected CRS (NaN = already rejected, stays silent).
pub(crate) fn coordinates(f: &mut Fields<'_>, x: f64, y: f64, z: f64) {
    for (column, v) in [("x", x), ("y", y)] {
        if v.abs() > MAX_ABS_XY_M {
            f.error_of(
                ProblemKind::Implausible,
                column,
                format!("{v} m is not a projected coordinate (|{column}| ≤ {MAX_ABS_XY_M:e} m)"),
                "write the coordinate in metres of the campaign's projected CRS (campaign.toml crs)",
            );
        }
    }
    if z.abs() > MAX_ABS_Z_M {
        f.error_of(
            ProblemKind::Implausible,
            "z",
            format!("{z} m is not a height (|z| ≤ {MAX_ABS_Z_M} m)"),
            "write the height in metres",
        );
    }
}

/// An angle in degrees within `[lo, hi]`.
pub(crate) fn angle(f: &mut Fields<'_>, column: &str, value: f64, lo: f64, hi: f64) {
    if !(lo..=hi).contains(&value) && !value.is_nan() {
        f.error_of(
            ProblemKind::Value,
            column,
            format!("{value}° is outside {lo}°…{hi}°"),
            "write the angle in degrees within that range",
        );
    }
}

/// An optional a-priori σ in metres within [`SIGMA_M`].
pub(crate) fn sigma_m(f: &mut Fields<'_>, column: &str, sigma: Option<f64>) {
    let Some(s) = sigma else { return };
    let (lo, hi) = SIGMA_M;
    if s <= 0.0 {
        f.error(
            column,
            format!("{s} is not a standard deviation"),
            "write a value > 0 m, or leave the cell empty for the default",
        );
    } else if !(lo..=hi).contains(&s) {
        f.error_of(
            ProblemKind::Implausible,
            column,
            format!("σ = {s} m is outside the plausible {lo}…{hi} m"),
            "give the standard deviation in metres (e.g. 0.05 for 5 cm), or leave the cell empty",
        );
    }
}

/// An image σ in pixels within [`SIGMA_PX`].
pub(crate) fn sigma_px(f: &mut Fields<'_>, sigma: f64) {
    let (lo, hi) = SIGMA_PX;
    if sigma <= 0.0 {
        f.error(
            "sigma_px",
            format!("{sigma} is not a standard deviation"),
            "write a value > 0 px, or leave the cell empty for the default 0.5",
        );
    } else if !(lo..=hi).contains(&sigma) {
        f.error_of(
            ProblemKind::Implausible,
            "sigma_px",
            format!("σ = {sigma} px is outside the plausible {lo}…{hi} px"),
            "give the measurement precision in pixels (default 0.5), or leave the cell empty",
        );
    }
}

/// Image size within [`IMAGE_SIDE_PX`] and a principal distance giving a field of view within
/// [`FRAME_FOV_DEG`] across the diagonal.
pub(crate) fn frame_camera(f: &mut Fields<'_>, focal_px: f64, width: u32, height: u32) {
    let (min_side, max_side) = IMAGE_SIDE_PX;
    for (column, side) in [("width", width), ("height", height)] {
        if side > 0 && !(min_side..=max_side).contains(&side) {
            f.error_of(
                ProblemKind::Implausible,
                column,
                format!("{side} px is not a frame image size ({min_side}…{max_side} px)"),
                "write the image size in pixels",
            );
        }
    }
    if focal_px <= 0.0 {
        f.error(
            "focal_px",
            format!("{focal_px} is not a principal distance"),
            "give the principal distance in pixels, > 0",
        );
        return;
    }
    if width == 0 || height == 0 || focal_px.is_nan() {
        return;
    }
    let diagonal = f64::from(width).hypot(f64::from(height));
    let fov_deg = 2.0 * (diagonal / (2.0 * focal_px)).atan().to_degrees();
    let (lo, hi) = FRAME_FOV_DEG;
    if !(lo..=hi).contains(&fov_deg) {
        f.error_of(
            ProblemKind::Implausible,
            "focal_px",
            format!(
                "{focal_px} px gives a {fov_deg:.3}° field of view across this {width}×{height} px image (plausible: {lo}…{hi}°)"
            ),
            "give the principal distance in pixels of this image (focal length in mm ÷ pixel size in mm)",
        );
    }
}
