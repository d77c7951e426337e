//! The triplet's driving direction (thesis 4.4.2): the collinearity criterion on the three recording locations
//! and the reference vector for plane fitting (horizontal, perpendicular to the driving direction = the
//! `heading` of the centre recording).

use crate::campaign::Recording;
use crate::oblique::types::StreetSide;
use nalgebra::Vector3;

/// Why a triplet defines no usable driving direction.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum TrajectoryRejection {
    /// A position or heading is not finite.
    NonFinite,
    /// The outer two recordings are closer than the minimum span (horizontal, metres).
    TooShort { span_m: f64 },
    /// The centre lies farther than allowed from the line through the outer two (horizontal, metres).
    NotCollinear { deviation_m: f64 },
}

/// Horizontal distance of the centre recording from the line through the outer two, metres, and the outer
/// two's horizontal span; checked against the limits (thesis 4.4.2 collinearity criterion).
pub fn check_collinearity(
    triplet: [&Recording; 3],
    max_deviation_m: f64,
    min_span_m: f64,
) -> Result<f64, TrajectoryRejection> {
    let finite = triplet.iter().all(|r| {
        r.x.is_finite() && r.y.is_finite() && r.z.is_finite() && r.heading_deg.is_finite()
    });
    if !finite {
        return Err(TrajectoryRejection::NonFinite);
    }
    let (a, b, c) = (triplet[0], triplet[1], triplet[2]);
    let chord = [c.x - a.x, c.y - a.y];
    let span_m = chord[0].hypot(chord[1]);
    if !(span_m >= min_span_m) || span_m == 0.0 {
        return Err(TrajectoryRejection::TooShort { span_m });
    }
    let rel = [b.x - a.x, b.y - a.y];
    let deviation_m = (chord[0] * rel[1] - chord[1] * rel[0]).abs() / span_m;
    if deviation_m > max_deviation_m {
        return Err(TrajectoryRejection::NotCollinear { deviation_m });
    }
    Ok(deviation_m)
}

/// Unit vector to the right of the driving direction (heading clockwise from grid north; x east, y north).
pub fn right_of_heading(heading_deg: f64) -> Vector3<f64> {
    let h = heading_deg.to_radians();
    Vector3::new(h.cos(), -h.sin(), 0.0)
}

/// Reference vector of a side's façade normal: horizontal, perpendicular to the driving direction, pointing
/// from that side's façades towards the street (left façades face right, right façades face left).
pub fn reference_normal(centre: &Recording, side: StreetSide) -> Vector3<f64> {
    let right = right_of_heading(centre.heading_deg);
    match side {
        StreetSide::Left => right,
        StreetSide::Right => -right,
    }
}
