//! `atan2` by a polynomial, for dense direction → pixel maps (the ortho-projection's sampling map, thesis 3.4.3),
//! where libm's `atan2` was two thirds of the time (perf, 3 cm ortho of a 4000 × 2000 panorama).
//!
//! Range reduction to |r| ≤ tan(π/8) (octant swap, then `atan(t) = π/4 + atan((t − 1)/(t + 1))`), then an odd
//! degree-15 polynomial fitted near-minimax (iteratively reweighted least squares on Chebyshev nodes). Maximum
//! error against libm ≈ 1.5e-13 rad (the test checks < 4e-13 on 10⁶ directions): for a 4800-px panorama that is
//! 1e-10 px. Measurements (the exact ortho → panorama inverse, triangulation) keep libm's `atan2`.

use std::f64::consts::{FRAC_PI_2, FRAC_PI_4, PI};

/// tan(π/8): above it the argument is reduced by the π/4 identity.
const TAN_PI_8: f64 = 0.414_213_562_373_095_03;

/// atan(r) = r · P(r²) on |r| ≤ tan(π/8); coefficients of P in increasing powers of r².
const ATAN_COEFFS: [f64; 8] = [
    0.9999999999940337,
    -0.33333333164202966,
    0.1999998600162583,
    -0.14285191786160345,
    0.11100693028359351,
    -0.08971534242626426,
    0.06892754580481245,
    -0.0363922929826468,
];

/// `y.atan2(x)` for finite arguments (same quadrant and sign conventions, including ±0 and ±π), max error
/// ≈ 1.5e-13 rad. One division, no libm call.
#[inline]
pub fn atan2_poly(y: f64, x: f64) -> f64 {
    // Written with selects rather than branches so that loops over many directions vectorise.
    let (ax, ay) = (x.abs(), y.abs());
    let swap = ay > ax;
    let num = if swap { ax } else { ay };
    let den = if swap { ay } else { ax };
    // num/den ∈ [0, 1]; above tan(π/8) use (num − den)/(num + den) = (t − 1)/(t + 1) and add π/4.
    let big = num > TAN_PI_8 * den;
    let n = if big { num - den } else { num };
    let d = if big { num + den } else { den };
    let base = if big { FRAC_PI_4 } else { 0.0 };
    let r = if d > 0.0 { n / d } else { 0.0 };
    // Estrin's scheme (shorter dependency chain than Horner's).
    let c = &ATAN_COEFFS;
    let s = r * r;
    let s2 = s * s;
    let s4 = s2 * s2;
    let p01 = c[0] + c[1] * s;
    let p23 = c[2] + c[3] * s;
    let p45 = c[4] + c[5] * s;
    let p67 = c[6] + c[7] * s;
    let p = (p01 + p23 * s2) + (p45 + p67 * s2) * s4;
    let a = base + r * p;
    let a = if swap { FRAC_PI_2 - a } else { a };
    let a = if x.is_sign_negative() { PI - a } else { a };
    a.copysign(y)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn agrees_with_libm_within_4e_13_rad_everywhere() {
        let mut worst = 0.0f64;
        let n = 1_000_000;
        for i in 0..n {
            // Directions all around the circle at varied radii, plus axis-aligned and near-octant-boundary ones.
            let phi = -PI + 2.0 * PI * (i as f64 + 0.37) / n as f64;
            let radius = 10f64.powi(i % 7 - 3);
            let (y, x) = (radius * phi.sin(), radius * phi.cos());
            worst = worst.max((atan2_poly(y, x) - y.atan2(x)).abs());
        }
        assert!(worst < 4e-13, "worst error {worst:e} rad");
    }

    #[test]
    fn signed_zeros_axes_and_octant_boundaries_follow_libm() {
        let cases = [
            (0.0, 0.0),
            (-0.0, 0.0),
            (0.0, -0.0),
            (-0.0, -0.0),
            (1.0, 0.0),
            (-1.0, 0.0),
            (0.0, 1.0),
            (0.0, -1.0),
            (1.0, 1.0),
            (-1.0, -1.0),
            (TAN_PI_8, 1.0),
            (1.0, TAN_PI_8),
            (-3.0, 1e-300),
            (1e-300, -3.0),
        ];
        for (y, x) in cases {
            let (got, want) = (atan2_poly(y, x), f64::atan2(y, x));
            assert!(
                (got - want).abs() < 4e-13 && got.is_sign_negative() == want.is_sign_negative(),
                "atan2({y}, {x}): {got} vs {want}"
            );
        }
    }
}
