//! DAISY local descriptor (Tola, Lepetit, Fua 2010; OpenCV xfeatures2d defaults; Mair et al. 2010; Tola, Lepetit & Fua 2010) for matching
//! AGAST corners between perspective views rendered from the panoramas (façade sparse cloud, thesis 4.4.1).
//!
//! 1. Gradient by central differences (intensity per pixel, x right, y down); H orientation maps
//!    G_o = max(0, cos θ_o·Ix + sin θ_o·Iy), θ_o = 2πo/H (angles measured from +x towards +y, i.e. clockwise
//!    on screen).
//! 2. Layers: every G_o is smoothed once with σ₀ = √(1.6² − 0.5²) ≈ 1.52 (OpenCV's "from 0.5 to 1.6") and then
//!    with the ring Gaussians σ_r = R·r/(2Q), r = 1..Q (2.5, 5, 7.5 px by default), incrementally: layer 1 uses
//!    √(σ₀² + σ₁²) in one pass (Gaussian semigroup), layer r > 1 adds √(σ_r² − σ_(r−1)²) to layer r − 1.
//!    The layers are computed ONCE per image by [`DaisyExtractor::new`] and stored pixel-interleaved (the H values
//!    of a pixel are contiguous), so a descriptor is 4·(Q·T + 1) contiguous reads.
//! 3. Sample points: the centre (layer 1) and, for ring r, T points at radius R·r/Q and angles 2πj/T (same angle
//!    convention), on layer r; each gives one H-histogram by bilinear interpolation. Order: centre, then ring 1
//!    j = 0..T−1, ring 2, … — length (Q·T + 1)·H = 200 by default.
//! 4. Normalisation ([`DaisyNormalization`]): Partial (each histogram to unit L2, Tola's choice; the default),
//!    None (OpenCV's effective default), Full (whole vector), Sift (unit L2, clip 0.154, renormalise).
//!
//! Border: [`DaisyExtractor::describe`] refuses (returns false) a point whose outermost sample would leave the grid
//! of pixel centres, i.e. unless R ≤ x − 0.5 ≤ W − 1 − R and R ≤ y − 0.5 ≤ H − 1 − R (continuous pixel
//! coordinates, pixel (c, r) centred at (c + 0.5, r + 0.5)). Layers near the image edge are computed with
//! reflective borders, so descriptors within ≈ R + 3σ_Q of the edge see mirrored content.

use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use crate::imaging::gaussian::gaussian_blur;
use crate::imaging::gradient::central_gradient;
use crate::imaging::GrayImage;

/// OpenCV's initial smoothing of the orientation maps, "from σ 0.5 to 1.6": √(1.6² − 0.5²).
const SIGMA_BASE_PX: f64 = 1.519_868_415_357_066;
/// SIFT-style clipping value of [`DaisyNormalization::Sift`].
const SIFT_CLIP: f32 = 0.154;

/// How a descriptor is normalised.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum DaisyNormalization {
    /// No normalisation (OpenCV `NRM_NONE`): values scale with the image contrast.
    None,
    /// Each histogram to unit L2 (OpenCV `NRM_PARTIAL`, Tola's choice): invariant to gain and offset.
    Partial,
    /// The whole descriptor to unit L2 (`NRM_FULL`).
    Full,
    /// Unit L2, clip at 0.154, renormalise (`NRM_SIFT`).
    Sift,
}

crate::params! {
    /// Descriptor parameters (OpenCV `DAISY::create` defaults except the normalisation: Partial, see the module
    /// doc).
    pub struct DaisyParams {
        /// Radius of the outermost ring.
        radius_px: f64 = 15.0, unit "px", min 1.0, max 200.0;
        /// Number of rings Q.
        rings: usize = 3, min 1, max 16;
        /// Histograms per ring T.
        histograms: usize = 8, min 1, max 64;
        /// Orientation bins per histogram H.
        orientations: usize = 8, min 1, max 64;
        /// Normalisation of the descriptor.
        normalization: DaisyNormalization = DaisyNormalization::Partial;
    }
}

impl DaisyParams {
    /// The parameters brought into the valid ranges (used by [`DaisyExtractor::new`], which cannot fail).
    fn clamped(&self) -> Self {
        Self {
            radius_px: if self.radius_px.is_finite() {
                self.radius_px.clamp(1.0, 200.0)
            } else {
                15.0
            },
            rings: self.rings.clamp(1, 16),
            histograms: self.histograms.clamp(1, 64),
            orientations: self.orientations.clamp(1, 64),
            normalization: self.normalization,
        }
    }

    /// Descriptor length (Q·T + 1)·H.
    pub fn descriptor_len(&self) -> usize {
        (self.rings * self.histograms + 1) * self.orientations
    }
}

/// One sample point of the descriptor pattern, relative to the keypoint.
#[derive(Clone, Copy, Debug)]
struct SamplePoint {
    dx_px: f64,
    dy_px: f64,
    layer: usize,
}

/// The smoothed orientation layers of one image, ready to describe any number of points.
pub struct DaisyExtractor {
    width: usize,
    height: usize,
    params: DaisyParams,
    /// `layers[r][(row·W + col)·H + o]`: orientation o smoothed for ring r + 1.
    layers: Vec<Vec<f32>>,
    pattern: Vec<SamplePoint>,
}

impl DaisyExtractor {
    /// Compute the layers of `img` (the expensive part, parallel). Parameters outside the ranges of
    /// [`Params::validate`](crate::params::Params::validate) are clamped into them (validate first to report them).
    pub fn new(img: &GrayImage, p: &DaisyParams) -> Self {
        let params = p.clamped();
        let (w, h) = (img.width, img.height);
        let (q, hn) = (params.rings, params.orientations);
        let n = w * h;
        let valid = n > 0 && img.data.len() == n;
        let mut layers = vec![vec![0.0f32; if valid { n * hn } else { 0 }]; q];
        if valid {
            let grad = central_gradient(img);
            let sigma_ring = |r: usize| params.radius_px * r as f64 / (2.0 * q as f64);
            let mut incr = Vec::with_capacity(q);
            incr.push((SIGMA_BASE_PX.powi(2) + sigma_ring(1).powi(2)).sqrt());
            for r in 2..=q {
                incr.push((sigma_ring(r).powi(2) - sigma_ring(r - 1).powi(2)).sqrt());
            }
            for o in 0..hn {
                let theta = 2.0 * std::f64::consts::PI * o as f64 / hn as f64;
                let (c, s) = (theta.cos() as f32, theta.sin() as f32);
                let data: Vec<f32> = grad
                    .dx
                    .data
                    .par_iter()
                    .zip(grad.dy.data.par_iter())
                    .map(|(&gx, &gy)| (c * gx + s * gy).max(0.0))
                    .collect();
                let mut map = GrayImage {
                    width: w,
                    height: h,
                    data,
                };
                for (r, &sigma) in incr.iter().enumerate() {
                    map = gaussian_blur(&map, sigma as f32);
                    scatter_orientation(&mut layers[r], &map.data, o, hn);
                }
            }
        }
        let pattern = sample_pattern(&params);
        Self {
            width: w,
            height: h,
            params,
            layers,
            pattern,
        }
    }

    /// Descriptor length (Q·T + 1)·H (200 by default).
    pub fn descriptor_len(&self) -> usize {
        self.params.descriptor_len()
    }

    /// The (clamped) parameters in use.
    pub fn params(&self) -> &DaisyParams {
        &self.params
    }

    /// Describe the point (x_px, y_px) (continuous pixel coordinates) into `out`. Returns false, leaving `out`
    /// unspecified, when the pattern does not fit inside the image (see the module doc: the point must be at
    /// least `radius_px` from the outermost pixel centres), when the point is not finite, or when
    /// `out.len() != self.descriptor_len()`.
    pub fn describe(&self, x_px: f64, y_px: f64, out: &mut [f32]) -> bool {
        if out.len() != self.descriptor_len() || !self.fits(x_px, y_px) {
            return false;
        }
        let hn = self.params.orientations;
        let (w, h) = (self.width, self.height);
        for (k, sp) in self.pattern.iter().enumerate() {
            let ax = x_px - 0.5 + sp.dx_px;
            let ay = y_px - 0.5 + sp.dy_px;
            // `fits` guarantees 0 ≤ ax ≤ W − 1 (up to rounding, hence the clamps).
            let x0 = (ax.floor().max(0.0) as usize).min(w - 1);
            let y0 = (ay.floor().max(0.0) as usize).min(h - 1);
            let (fx, fy) = ((ax - x0 as f64) as f32, (ay - y0 as f64) as f32);
            let x1 = (x0 + 1).min(w - 1);
            let y1 = (y0 + 1).min(h - 1);
            let layer = &self.layers[sp.layer];
            let (w00, w10) = ((1.0 - fx) * (1.0 - fy), fx * (1.0 - fy));
            let (w01, w11) = ((1.0 - fx) * fy, fx * fy);
            let p00 = &layer[(y0 * w + x0) * hn..][..hn];
            let p10 = &layer[(y0 * w + x1) * hn..][..hn];
            let p01 = &layer[(y1 * w + x0) * hn..][..hn];
            let p11 = &layer[(y1 * w + x1) * hn..][..hn];
            let hist = &mut out[k * hn..(k + 1) * hn];
            for o in 0..hn {
                hist[o] = w00 * p00[o] + w10 * p10[o] + w01 * p01[o] + w11 * p11[o];
            }
        }
        normalise(out, hn, self.params.normalization);
        true
    }

    /// Whether the whole sample pattern around (x_px, y_px) lies on the grid of pixel centres.
    fn fits(&self, x_px: f64, y_px: f64) -> bool {
        let r = self.params.radius_px;
        let (ax, ay) = (x_px - 0.5, y_px - 0.5);
        ax.is_finite()
            && ay.is_finite()
            && !self.layers.is_empty()
            && !self.layers[0].is_empty()
            && ax >= r
            && ay >= r
            && ax <= (self.width as f64 - 1.0) - r
            && ay <= (self.height as f64 - 1.0) - r
    }
}

/// Describe many points of one image (layers computed once; points in parallel, output in input order).
/// None for points too close to the border (see [`DaisyExtractor::describe`]).
pub fn describe_points(
    img: &GrayImage,
    points: &[(f64, f64)],
    p: &DaisyParams,
) -> Vec<Option<Vec<f32>>> {
    let ex = DaisyExtractor::new(img, p);
    let len = ex.descriptor_len();
    points
        .par_iter()
        .map(|&(x, y)| {
            let mut d = vec![0.0f32; len];
            ex.describe(x, y, &mut d).then_some(d)
        })
        .collect()
}

/// Write one orientation map into the pixel-interleaved layer (parallel over rows of the layer).
fn scatter_orientation(layer: &mut [f32], map: &[f32], o: usize, hn: usize) {
    const CHUNK_PX: usize = 4096;
    layer
        .par_chunks_mut(CHUNK_PX * hn)
        .zip(map.par_chunks(CHUNK_PX))
        .for_each(|(dst, src)| {
            for (px, &v) in src.iter().enumerate() {
                dst[px * hn + o] = v;
            }
        });
}

/// Centre, then ring r = 1..Q with T points at radius R·r/Q, angles 2πj/T.
fn sample_pattern(p: &DaisyParams) -> Vec<SamplePoint> {
    let mut pts = vec![SamplePoint {
        dx_px: 0.0,
        dy_px: 0.0,
        layer: 0,
    }];
    for r in 1..=p.rings {
        let rho = p.radius_px * r as f64 / p.rings as f64;
        for j in 0..p.histograms {
            let a = 2.0 * std::f64::consts::PI * j as f64 / p.histograms as f64;
            pts.push(SamplePoint {
                dx_px: rho * a.cos(),
                dy_px: rho * a.sin(),
                layer: r - 1,
            });
        }
    }
    pts
}

/// Apply the normalisation in place (histograms of `hn` values).
fn normalise(d: &mut [f32], hn: usize, mode: DaisyNormalization) {
    let unit = |v: &mut [f32]| {
        let n = v.iter().map(|x| x * x).sum::<f32>().sqrt();
        if n > 1e-12 {
            let inv = 1.0 / n;
            v.iter_mut().for_each(|x| *x *= inv);
        }
    };
    match mode {
        DaisyNormalization::None => {}
        DaisyNormalization::Partial => d.chunks_mut(hn).for_each(unit),
        DaisyNormalization::Full => unit(d),
        DaisyNormalization::Sift => {
            unit(d);
            d.iter_mut().for_each(|x| *x = x.min(SIFT_CLIP));
            unit(d);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::params::Params;

    fn ramp(w: usize, h: usize, gx: f32, gy: f32) -> GrayImage {
        let data = (0..w * h)
            .map(|k| 0.2 + gx * (k % w) as f32 + gy * (k / w) as f32)
            .collect();
        GrayImage::from_vec(w, h, data).unwrap()
    }

    #[test]
    fn length_pattern_and_constant_image() {
        let p = DaisyParams::default();
        assert_eq!(p.descriptor_len(), 200);
        let pat = sample_pattern(&p);
        assert_eq!(pat.len(), 25);
        assert!((pat[1].dx_px - 5.0).abs() < 1e-12 && pat[1].dy_px.abs() < 1e-12);
        assert!((pat[17].dx_px - 15.0).abs() < 1e-12 && pat[17].layer == 2);
        // j = 2 of ring 1 is at +90°, i.e. straight down (y grows downwards).
        assert!(pat[3].dx_px.abs() < 1e-12 && (pat[3].dy_px - 5.0).abs() < 1e-12);
        let ex = DaisyExtractor::new(&GrayImage::filled(60, 60, 0.3), &p);
        let mut d = vec![1.0f32; 200];
        assert!(ex.describe(30.0, 30.0, &mut d));
        assert!(d.iter().all(|&v| v == 0.0));
    }

    #[test]
    fn ramp_gives_the_projected_gradient_in_every_histogram() {
        // I = 0.01·x: Ix = 0.01, Iy = 0 everywhere (inside), so G_o = 0.01·max(0, cos θ_o).
        let p = DaisyParams {
            normalization: DaisyNormalization::None,
            ..DaisyParams::default()
        };
        let ex = DaisyExtractor::new(&ramp(140, 140, 0.01, 0.0), &p);
        let mut d = vec![0.0f32; 200];
        assert!(ex.describe(70.0, 70.0, &mut d));
        for hist in d.chunks(8) {
            for (o, &v) in hist.iter().enumerate() {
                let want = 0.01 * (2.0 * std::f32::consts::PI * o as f32 / 8.0).cos().max(0.0);
                assert!((v - want).abs() < 1e-5, "o {o}: {v} vs {want}");
            }
        }
        // Partial: every histogram has unit norm.
        let ex = DaisyExtractor::new(&ramp(100, 100, 0.01, 0.02), &DaisyParams::default());
        assert!(ex.describe(50.0, 50.0, &mut d));
        for hist in d.chunks(8) {
            let n: f32 = hist.iter().map(|v| v * v).sum::<f32>().sqrt();
            assert!((n - 1.0).abs() < 1e-5);
        }
    }

    #[test]
    fn border_rule_and_wrong_buffer() {
        let ex = DaisyExtractor::new(&ramp(60, 50, 0.01, 0.0), &DaisyParams::default());
        let mut d = vec![0.0f32; 200];
        // Pixel-centre grid 0..59 × 0..49 (as x − 0.5): needs 15 ≤ x − 0.5 ≤ 44, 15 ≤ y − 0.5 ≤ 34.
        assert!(ex.describe(15.5, 15.5, &mut d));
        assert!(ex.describe(44.5, 34.5, &mut d));
        assert!(!ex.describe(15.4, 20.0, &mut d));
        assert!(!ex.describe(44.6, 20.0, &mut d));
        assert!(!ex.describe(20.0, 34.6, &mut d));
        assert!(!ex.describe(f64::NAN, 20.0, &mut d));
        assert!(!ex.describe(20.0, 20.0, &mut [0.0f32; 199]));
        let tiny = DaisyExtractor::new(&GrayImage::filled(0, 0, 0.0), &DaisyParams::default());
        assert!(!tiny.describe(0.5, 0.5, &mut d));
    }

    #[test]
    fn validate_names_bad_fields() {
        assert!(DaisyParams::default().validate().is_ok());
        let bad = DaisyParams {
            radius_px: 0.0,
            rings: 0,
            histograms: 8,
            orientations: 100,
            normalization: DaisyNormalization::None,
        };
        let fields = crate::params::violated_fields(&bad);
        assert_eq!(fields, ["radius_px", "rings", "orientations"]);
    }
}
