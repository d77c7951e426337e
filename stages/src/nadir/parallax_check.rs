//! Does a neighbouring recording see the corner's template the same way? A check of the MM template before it
//! is located in an aerial image (an addition to thesis 3.4.5.3).
//!
//! The ortho-projection puts everything on one horizontal plane (3.4.3). Content at another height than the
//! corner — the road next to a raised kerb corner, the kerb's vertical face — is displaced radially from each
//! panorama's foot point by `distance × Δh / camera height`, so its position relative to the corner depends on
//! the viewpoint: for recordings 5 m apart and a 0.11 m kerb, about 0.25 m (2.5 px at 10 cm). The aerial image
//! shows all of it in place, so phase correlation of such a template settles on a compromise and puts the
//! corner 2–3 px off — in every aerial image alike, where no aerial-side check can see it (measured on the demo
//! campaigns).
//!
//! The test: the neighbour's ortho image (same GSD and orientation) is sampled on the template grid, aligned at
//! the corner as the neighbour saw it (MM-to-MM matching, 3.4.4). Both templates are smoothed (3 × 3 box) and
//! normalised to zero mean and unit deviation; a pixel disagrees when the two differ by more than
//! [`DISAGREEMENT_STD`]. The returned share weights each pixel by its gradient magnitude, so it measures how
//! much of the template's *structure* — what phase correlation locks onto — the other view places differently.
//! Content on the corner's own surface agrees (the plane projection of one plane is the same from both views);
//! content at other heights, occluded or vehicle-masked content does not.

use crate::imaging::border::Border;
use crate::imaging::sample::sample_bilinear;
use crate::imaging::GrayImage;

use super::ortho::OrthoImage;

/// Two normalised, smoothed templates disagree at a pixel when they differ by more than this many standard
/// deviations of the template.
pub const DISAGREEMENT_STD: f64 = 0.6;

/// Reusable buffers of [`parallax_share`] (one per worker thread, so the check allocates nothing per call).
#[derive(Default)]
pub struct ParallaxScratch {
    mine: Vec<f64>,
    other: Vec<f64>,
    known: Vec<bool>,
    a: Vec<f64>,
    b: Vec<f64>,
}

/// Share (0..1, gradient-weighted) of the structure of `template` that the neighbour's ortho image `neighbour`
/// shows differently, with the template's top-left pixel corner at (`nx0`, `ny0`) in the neighbour's ortho
/// (continuous pixels). Neighbour pixels outside its image or masked give no vote; `None` when fewer than half
/// of the template's pixels have a vote, or the template has no structure.
pub fn parallax_share(
    template: &GrayImage,
    neighbour: &OrthoImage,
    nx0: f64,
    ny0: f64,
    scratch: &mut ParallaxScratch,
) -> Option<f64> {
    let (w, h) = (template.width, template.height);
    if w < 3 || h < 3 || template.data.len() != w * h {
        return None;
    }
    let (nw, nh) = (neighbour.image.width, neighbour.image.height);
    let ParallaxScratch {
        mine,
        other,
        known,
        a,
        b,
    } = scratch;
    other.clear();
    known.clear();
    for r in 0..h {
        for c in 0..w {
            let (x, y) = (nx0 + c as f64 + 0.5, ny0 + r as f64 + 0.5);
            let (xi, yi) = ((x - 0.5).floor(), (y - 0.5).floor());
            let inside = xi >= 0.0 && yi >= 0.0 && xi + 1.0 < nw as f64 && yi + 1.0 < nh as f64;
            let valid = inside && {
                let (xi, yi) = (xi as usize, yi as usize);
                [(xi, yi), (xi + 1, yi), (xi, yi + 1), (xi + 1, yi + 1)]
                    .iter()
                    .all(|&(a, b)| neighbour.valid.get(b * nw + a) == Some(&1))
            };
            known.push(valid);
            other.push(if valid {
                sample_bilinear(&neighbour.image, x, y, Border::Clamp) as f64
            } else {
                f64::NAN
            });
        }
    }
    let n_known = known.iter().filter(|&&k| k).count();
    if 2 * n_known < w * h {
        return None;
    }
    // Unknown neighbour pixels take the mean of the known ones (they are excluded from the vote below).
    let fill = other.iter().filter(|v| v.is_finite()).sum::<f64>() / n_known as f64;
    other
        .iter_mut()
        .filter(|v| !v.is_finite())
        .for_each(|v| *v = fill);
    mine.clear();
    mine.extend(template.data.iter().map(|&g| g as f64));
    box3(mine, w, h, a);
    normalise(a);
    box3(other, w, h, b);
    normalise(b);
    let (mut differing, mut total) = (0.0, 0.0);
    for r in 1..h - 1 {
        for c in 1..w - 1 {
            let k = r * w + c;
            if !known[k] {
                continue;
            }
            let g = (a[k + 1] - a[k - 1]).hypot(a[k + w] - a[k - w]);
            total += g;
            if (a[k] - b[k]).abs() > DISAGREEMENT_STD {
                differing += g;
            }
        }
    }
    (total > 0.0).then(|| differing / total)
}

/// 3 × 3 box filter of `v` into `out` (border pixels copied).
fn box3(v: &[f64], w: usize, h: usize, out: &mut Vec<f64>) {
    out.clear();
    out.extend_from_slice(v);
    for r in 1..h - 1 {
        for c in 1..w - 1 {
            let mut acc = 0.0;
            for dr in 0..3 {
                let row = (r + dr - 1) * w;
                acc += v[row + c - 1] + v[row + c] + v[row + c + 1];
            }
            out[r * w + c] = acc / 9.0;
        }
    }
}

/// Zero mean, unit standard deviation, in place (a flat input stays flat).
fn normalise(v: &mut [f64]) {
    let n = v.len().max(1) as f64;
    let mean = v.iter().sum::<f64>() / n;
    let sd = (v.iter().map(|a| (a - mean).powi(2)).sum::<f64>() / n).sqrt();
    let sd = if sd > 1e-9 { sd } else { 1.0 };
    v.iter_mut().for_each(|a| *a = (*a - mean) / sd);
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::nadir::ortho::{OrthoGeoref, OrthoParams};

    /// A ground pattern: a raised square (x, y ≥ `corner`) with a stripe pattern elsewhere, seen with the raised
    /// part displaced by `raised_shift` px (the parallax of the other view).
    fn scene(size: usize, corner: f64, raised_shift: (f64, f64)) -> Vec<f32> {
        let mut img = vec![0.0f32; size * size];
        for r in 0..size {
            for c in 0..size {
                let (x, y) = (c as f64 + 0.5, r as f64 + 0.5);
                let (xs, ys) = (x - raised_shift.0, y - raised_shift.1);
                img[r * size + c] = if xs >= corner && ys >= corner {
                    0.8 + 0.05 * ((xs * 0.7).sin() as f32)
                } else if ((x / 3.0).floor() as i64) % 2 == 0 {
                    0.2
                } else {
                    0.5
                };
            }
        }
        img
    }

    fn ortho(data: Vec<f32>, size: usize) -> OrthoImage {
        OrthoImage {
            image: GrayImage {
                width: size,
                height: size,
                data,
            },
            valid: vec![1; size * size],
            georef: OrthoGeoref::new([0.0, 0.0, 0.0], &OrthoParams::default()),
        }
    }

    fn template(img: &[f32], size: usize, x0: usize, y0: usize, n: usize) -> GrayImage {
        let mut data = Vec::with_capacity(n * n);
        for r in y0..y0 + n {
            data.extend_from_slice(&img[r * size + x0..r * size + x0 + n]);
        }
        GrayImage {
            width: n,
            height: n,
            data,
        }
    }

    #[test]
    fn one_surface_agrees_and_two_heights_disagree() {
        let size = 96;
        let t = template(&scene(size, 48.0, (0.0, 0.0)), size, 32, 32, 32);
        // The other view sees the same single-height scene (shifted as a whole: the alignment takes it out).
        let same = ortho(scene(size, 48.0, (0.0, 0.0)), size);
        let share_same =
            parallax_share(&t, &same, 32.0, 32.0, &mut ParallaxScratch::default()).unwrap();
        // The other view displaces the raised square (and its corner, where the views are aligned) by 2 px
        // against the road stripes.
        let moved = ortho(scene(size, 48.0, (2.0, 0.0)), size);
        let share_moved =
            parallax_share(&t, &moved, 34.0, 32.0, &mut ParallaxScratch::default()).unwrap();
        assert!(share_same < 0.01, "{share_same}");
        assert!(share_moved > 0.3, "{share_moved}");
    }

    #[test]
    fn masked_or_outside_neighbour_gives_no_verdict() {
        let size = 96;
        let img = scene(size, 48.0, (0.0, 0.0));
        let t = template(&img, size, 32, 32, 32);
        let mut masked = ortho(img, size);
        masked.valid.iter_mut().for_each(|v| *v = 0);
        assert_eq!(
            parallax_share(&t, &masked, 32.0, 32.0, &mut ParallaxScratch::default()),
            None
        );
        let inside = ortho(scene(size, 48.0, (0.0, 0.0)), size);
        assert_eq!(
            parallax_share(&t, &inside, 80.0, 80.0, &mut ParallaxScratch::default()),
            None
        );
    }
}
