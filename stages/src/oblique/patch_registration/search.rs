//! Translation search between two patches of one registration level (thesis 4.4.6): exhaustive masked NCC at
//! integer shifts with a quadratic sub-pixel peak, and Mattes MI maximised by the (1+1)-ES (optionally seeded
//! by an exhaustive integer MI scan).
//!
//! Shifts are patch translations in px with the Mattes MI convention: fixed pixel `x` is compared with the
//! moving patch at `x + t` (see `matching::mattes_mi`). NaN pixels are masked in both patches.

use crate::estimators::one_plus_one::OnePlusOneParams;
use crate::imaging::GrayImage;
use crate::matching::mattes_mi::{maximize_translation, MattesMi, MiError, MiRegistration};
use crate::matching::subpixel::{refine_peak, PeakFit};

/// A found translation.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Found {
    pub shift_px: [f64; 2],
    /// NCC in [−1, 1] or MI in nats.
    pub score: f64,
}

/// Masked NCC of `fixed(x)` against `moving(x + (dx, dy))` over the pixels valid in both; `None` with fewer
/// than `min_overlap` such pixels or a flat side.
pub fn masked_ncc(
    fixed: &GrayImage,
    moving: &GrayImage,
    dx: isize,
    dy: isize,
    min_overlap: usize,
) -> Option<f64> {
    let (w, h) = (fixed.width as isize, fixed.height as isize);
    let (mw, mh) = (moving.width as isize, moving.height as isize);
    let c0 = 0.max(-dx);
    let c1 = w.min(mw - dx);
    let r0 = 0.max(-dy);
    let r1 = h.min(mh - dy);
    if c1 <= c0 || r1 <= r0 {
        return None;
    }
    let (mut n, mut sf, mut sm, mut sff, mut smm, mut sfm) = (0usize, 0.0, 0.0, 0.0, 0.0, 0.0);
    for r in r0..r1 {
        let frow = &fixed.data[(r * w) as usize..((r + 1) * w) as usize];
        let mrow = &moving.data[((r + dy) * mw) as usize..((r + dy + 1) * mw) as usize];
        for c in c0..c1 {
            let f = frow[c as usize];
            let m = mrow[(c + dx) as usize];
            if f.is_finite() && m.is_finite() {
                let (f, m) = (f64::from(f), f64::from(m));
                n += 1;
                sf += f;
                sm += m;
                sff += f * f;
                smm += m * m;
                sfm += f * m;
            }
        }
    }
    if n < min_overlap.max(2) {
        return None;
    }
    let nf = n as f64;
    let vf = sff - sf * sf / nf;
    let vm = smm - sm * sm / nf;
    let cov = sfm - sf * sm / nf;
    // Flat (relative to the signal energy) on either side: undefined.
    if !(vf > 1e-9 * sff.max(1e-30) && vm > 1e-9 * smm.max(1e-30)) {
        return None;
    }
    Some((cov / (vf * vm).sqrt()).clamp(-1.0, 1.0))
}

/// Exhaustive masked NCC over integer shifts `centre + (i, j)`, |i|, |j| ≤ `radius_px`, then the quadratic
/// sub-pixel fit on the 3 × 3 neighbourhood of the best one (no fit on the border of the search window or
/// where a neighbour is undefined). `None` if no shift has enough overlap.
pub fn ncc_search(
    fixed: &GrayImage,
    moving: &GrayImage,
    centre_px: [isize; 2],
    radius_px: usize,
    min_overlap: usize,
) -> Option<Found> {
    let r = radius_px as isize;
    let side = (2 * r + 1) as usize;
    let mut map = vec![f64::NAN; side * side];
    let mut best: Option<(usize, f64)> = None;
    for j in -r..=r {
        for i in -r..=r {
            let k = ((j + r) as usize) * side + (i + r) as usize;
            if let Some(v) = masked_ncc(
                fixed,
                moving,
                centre_px[0] + i,
                centre_px[1] + j,
                min_overlap,
            ) {
                map[k] = v;
                if best.is_none_or(|(_, b)| v > b) {
                    best = Some((k, v));
                }
            }
        }
    }
    let (k, score) = best?;
    let (bi, bj) = ((k % side) as isize, (k / side) as isize);
    // A maximum on the border of the search window is no peak: the similarity still grows outwards, so the
    // best match lies outside the searched range (beyond the expected error) and the registration failed.
    if bi == 0 || bj == 0 || bi + 1 == side as isize || bj + 1 == side as isize {
        return None;
    }
    let mut shift = [
        (centre_px[0] + bi - r) as f64,
        (centre_px[1] + bj - r) as f64,
    ];
    if bi > 0 && bj > 0 && bi + 1 < side as isize && bj + 1 < side as isize {
        let mut n = [[0.0; 3]; 3];
        let mut complete = true;
        for (y, row) in n.iter_mut().enumerate() {
            for (x, v) in row.iter_mut().enumerate() {
                let kk = ((bj + y as isize - 1) as usize) * side + (bi + x as isize - 1) as usize;
                *v = map[kk];
                complete &= v.is_finite();
            }
        }
        if complete {
            let (ddx, ddy) = refine_peak(&n, PeakFit::Quadratic);
            shift[0] += ddx;
            shift[1] += ddy;
        }
    }
    Some(Found {
        shift_px: shift,
        score,
    })
}

/// Mattes MI maximised by the (1+1)-ES ([`maximize_translation`]) from `window_centre_px`, candidates
/// restricted to ±`window_px` (per axis) around it. With `scan_step_px = Some(s)` the start is first replaced by
/// the best of an exhaustive MI scan at the shifts `window_centre + s·(i, j)` inside the window (and the ES then
/// searches ±s around it). Errors if the metric cannot be set up, or no scanned shift (without a scan: the
/// window centre) is valid. This is the MI path of the patch registration and of `skytie tool mi-register`.
#[allow(clippy::too_many_arguments)]
pub fn mi_search(
    fixed: &GrayImage,
    moving: &GrayImage,
    bins: usize,
    samples: Option<usize>,
    window_centre_px: [f64; 2],
    window_px: f64,
    scan_step_px: Option<usize>,
    es: &OnePlusOneParams,
) -> Result<MiRegistration, MiError> {
    let mut metric = MattesMi::new(fixed, moving, bins, samples, es.seed)?;
    let (mut start, mut half) = (window_centre_px, window_px);
    if let Some(step) = scan_step_px {
        let step = step.max(1) as f64;
        let k = (window_px / step).floor() as isize;
        let mut best: Option<([f64; 2], f64)> = None;
        let mut last_err = None;
        for j in -k..=k {
            for i in -k..=k {
                let t = [
                    window_centre_px[0] + i as f64 * step,
                    window_centre_px[1] + j as f64 * step,
                ];
                match metric.evaluate(t[0], t[1]) {
                    Ok(v) if best.is_none_or(|(_, b)| v > b) => best = Some((t, v)),
                    Ok(_) => {}
                    Err(e) => last_err = Some(e),
                }
            }
        }
        match (best, last_err) {
            // As in `ncc_search`: a scan maximum on the window's border is no peak.
            (Some((t, _)), _)
                if (t[0] - window_centre_px[0]).abs() >= k as f64 * step
                    || (t[1] - window_centre_px[1]).abs() >= k as f64 * step =>
            {
                return Err(MiError::MaximumOnBorder(
                    t[0] - window_centre_px[0],
                    t[1] - window_centre_px[1],
                ))
            }
            (Some((t, _)), _) => start = t,
            (None, Some(e)) => return Err(e),
            (None, None) => {
                return Err(MiError::NonFiniteTranslation(
                    window_centre_px[0],
                    window_centre_px[1],
                ))
            }
        }
        half = step;
    }
    maximize_translation(&mut metric, start, half, es)
}

impl From<MiRegistration> for Found {
    fn from(r: MiRegistration) -> Self {
        Found {
            shift_px: r.translation_px,
            score: r.mi,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::matching::mattes_mi::MiError;

    /// A smooth random texture (sum of a few seeded sinusoids) sampled at `(x + dx, y + dy)`.
    fn texture(w: usize, h: usize, dx: f64, dy: f64) -> GrayImage {
        let waves = [
            (0.31, 0.17, 0.3),
            (-0.23, 0.41, 1.1),
            (0.53, -0.29, 2.0),
            (0.11, 0.61, 0.7),
            (-0.47, -0.37, 2.9),
        ];
        let data = (0..h)
            .flat_map(|y| (0..w).map(move |x| (x as f64 + dx, y as f64 + dy)))
            .map(|(x, y)| {
                waves
                    .iter()
                    .map(|(a, b, p)| (a * x + b * y + p).sin())
                    .sum::<f64>() as f32
            })
            .collect();
        GrayImage::from_vec(w, h, data).expect("size")
    }

    #[test]
    fn ncc_finds_a_shift_inside_the_window_and_refuses_a_maximum_on_its_border() {
        // moving(x + t) = fixed(x) for t = (3, −2).
        let fixed = texture(40, 40, 0.0, 0.0);
        let moving = texture(40, 40, -3.0, 2.0);
        let found = ncc_search(&fixed, &moving, [0, 0], 5, 100).expect("inside the window");
        let [dx, dy] = found.shift_px;
        assert!(
            (dx - 3.0).abs() < 0.05 && (dy + 2.0).abs() < 0.05,
            "{dx} {dy}"
        );
        assert!(found.score > 0.999);
        // Radius 2: the best shift inside the window is (2, −2), on its border, where the NCC still grows
        // outwards; that is no peak and must not be reported as a match.
        assert!(ncc_search(&fixed, &moving, [0, 0], 2, 100).is_none());
    }

    #[test]
    fn mi_scan_refuses_a_maximum_on_the_window_border() {
        let fixed = texture(48, 48, 0.0, 0.0);
        let moving = texture(48, 48, -4.0, 1.0);
        let es = OnePlusOneParams {
            seed: 7,
            ..OnePlusOneParams::default()
        };
        let r = mi_search(&fixed, &moving, 32, None, [0.0, 0.0], 6.0, Some(2), &es)
            .expect("inside the window");
        assert!((r.translation_px[0] - 4.0).abs() < 0.2 && (r.translation_px[1] + 1.0).abs() < 0.2);
        match mi_search(&fixed, &moving, 32, None, [0.0, 0.0], 2.0, Some(2), &es) {
            Err(MiError::MaximumOnBorder(dx, _)) => assert_eq!(dx, 2.0),
            other => panic!("expected MaximumOnBorder, got {other:?}"),
        }
    }
}
