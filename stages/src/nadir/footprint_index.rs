//! A spatial index of aerial images by ground footprint, so that "which aerial images may see this place" costs
//! O(log n + hits) instead of one projection per image ([`super::aerial_overlap`] for nadir images,
//! [`crate::oblique::candidates`] for oblique ones).
//!
//! For a height range `[z_lo, z_hi]` of the world points that will be asked about, each image gets a horizontal
//! box that contains every point in that range whose projection falls inside the frame. The box is made from
//! the cone of viewing rays: the frame border sampled densely and undistorted gives a box in ideal normalised
//! image coordinates (padded by [`PAD_FRACTION`] of its size against the distortion's curvature between
//! samples); the four corner rays of that box span a convex cone containing every ray of the frame, and its
//! sections with the planes `z_lo` and `z_hi` — on each plane a quadrilateral whose corners move linearly with
//! the height — bound it over the whole range. An image whose cone reaches the horizon, whose projection centre
//! is not above `z_hi` or whose border does not undistort has no bounded footprint: it is a candidate for
//! every query. The index only narrows the candidates; callers keep their exact projection test, so the
//! selected images are the same as with a linear scan, and they sort the hits as before.

use crate::campaign::AerialImage;
use crate::geometry::FrameCamera;
use nalgebra::Vector3;
use rstar::primitives::{GeomWithData, Rectangle};
use rstar::{RTree, AABB};

/// Samples per frame edge when bounding the frame in ideal image coordinates.
const EDGE_SAMPLES: usize = 64;

/// Padding of the ideal-coordinate box, as a fraction of its width and height.
pub const PAD_FRACTION: f64 = 0.02;

type Entry = GeomWithData<Rectangle<[f64; 2]>, usize>;

/// Aerial images indexed by the ground boxes of their frames over a height range.
pub struct FootprintIndex {
    tree: RTree<Entry>,
    /// Images without a bounded footprint: candidates for every query.
    unbounded: Vec<usize>,
    z_range_world: [f64; 2],
    len: usize,
}

/// The box of the frame in ideal normalised coordinates (x right, y up; `x = p.x / −p.z`), padded; `None`
/// when a border sample does not undistort.
fn ideal_box(cam: &FrameCamera) -> Option<[f64; 4]> {
    let (w, h) = (f64::from(cam.width_px), f64::from(cam.height_px));
    let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
    for k in 0..=EDGE_SAMPLES {
        let t = k as f64 / EDGE_SAMPLES as f64;
        for (u, v) in [(t * w, 0.0), (t * w, h), (0.0, t * h), (w, t * h)] {
            let xd = (u - cam.cx_px) / cam.focal_px;
            let yd = (cam.cy_px - v) / cam.focal_px;
            let (x, y) = cam.distortion.try_undistort(xd, yd)?;
            for (d, c) in [x, y].into_iter().enumerate() {
                lo[d] = lo[d].min(c);
                hi[d] = hi[d].max(c);
            }
        }
    }
    let pad = [
        PAD_FRACTION * (hi[0] - lo[0]),
        PAD_FRACTION * (hi[1] - lo[1]),
    ];
    let b = [
        lo[0] - pad[0],
        lo[1] - pad[1],
        hi[0] + pad[0],
        hi[1] + pad[1],
    ];
    b.iter().all(|v| v.is_finite()).then_some(b)
}

/// The horizontal box of the frame's cone between the heights `z_lo` and `z_hi`, or `None` when it is unbounded.
fn ground_box(img: &AerialImage, z_range_world: [f64; 2]) -> Option<[f64; 4]> {
    let cam = FrameCamera::from_aerial(img);
    let c = cam.center_world;
    if !c.iter().all(|v| v.is_finite()) || !(c.z > z_range_world[1]) {
        return None;
    }
    let [x0, y0, x1, y1] = ideal_box(&cam)?;
    let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
    for (x, y) in [(x0, y0), (x1, y0), (x1, y1), (x0, y1)] {
        let d = cam.rotation_cam_to_world * Vector3::new(x, y, -1.0);
        if !(d.z < 0.0) {
            return None;
        }
        for z in z_range_world {
            let p = c + d * ((z - c.z) / d.z);
            for k in 0..2 {
                lo[k] = lo[k].min(p[k]);
                hi[k] = hi[k].max(p[k]);
            }
        }
    }
    let b = [lo[0], lo[1], hi[0], hi[1]];
    b.iter().all(|v| v.is_finite()).then_some(b)
}

impl FootprintIndex {
    /// Indexes `images` for queries about world points with heights in `z_range_world` (lowest, highest).
    pub fn new(images: &[AerialImage], z_range_world: [f64; 2]) -> Self {
        let mut entries = Vec::with_capacity(images.len());
        let mut unbounded = Vec::new();
        let finite_range =
            z_range_world.iter().all(|z| z.is_finite()) && z_range_world[0] <= z_range_world[1];
        for (i, img) in images.iter().enumerate() {
            match ground_box(img, z_range_world).filter(|_| finite_range) {
                Some([x0, y0, x1, y1]) => {
                    entries.push(GeomWithData::new(
                        Rectangle::from_corners([x0, y0], [x1, y1]),
                        i,
                    ));
                }
                None => unbounded.push(i),
            }
        }
        Self {
            tree: RTree::bulk_load(entries),
            unbounded,
            z_range_world,
            len: images.len(),
        }
    }

    /// The height range (lowest, highest) of the world points from `heights`, for [`Self::new`]; non-finite
    /// heights are left out (`[0, 0]` when none is finite).
    pub fn height_range(heights: impl IntoIterator<Item = f64>) -> [f64; 2] {
        let (lo, hi) = heights
            .into_iter()
            .filter(|z| z.is_finite())
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), z| {
                (lo.min(z), hi.max(z))
            });
        if lo.is_finite() {
            [lo, hi]
        } else {
            [0.0, 0.0]
        }
    }

    /// Indices (ascending) of the images whose footprint box meets the horizontal box `lo`–`hi` at heights
    /// `z_lo`–`z_hi`: a superset of the images in which any such point projects inside the frame. Heights
    /// outside the indexed range give every image.
    pub fn candidates(&self, lo: [f64; 2], hi: [f64; 2], z: [f64; 2]) -> Vec<usize> {
        let inside = z[0] >= self.z_range_world[0] && z[1] <= self.z_range_world[1];
        if !inside || !lo.iter().chain(&hi).all(|v| v.is_finite()) {
            return (0..self.len).collect();
        }
        let mut out: Vec<usize> = self
            .tree
            .locate_in_envelope_intersecting(&AABB::from_corners(lo, hi))
            .map(|e| e.data)
            .chain(self.unbounded.iter().copied())
            .collect();
        out.sort_unstable();
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rng::SplitMix64;

    /// Random nadir and oblique cameras (some with distortion) over a 2 km square; for random ground points the
    /// images that see them by projection are always among the index's candidates.
    #[test]
    fn candidates_contain_every_image_that_sees_the_point() {
        let mut rng = SplitMix64::new(7);
        let mut images = Vec::new();
        for i in 0..200 {
            let oblique = i % 3 == 0;
            let centre = [
                rng.next_f64() * 2000.0,
                rng.next_f64() * 2000.0,
                300.0 + rng.next_f64() * 700.0,
            ];
            let opk = if oblique {
                [
                    45.0 * (rng.next_f64() - 0.5) * 2.0,
                    0.0,
                    rng.next_f64() * 360.0,
                ]
            } else {
                [
                    rng.next_f64() * 4.0 - 2.0,
                    rng.next_f64() * 4.0 - 2.0,
                    rng.next_f64() * 360.0,
                ]
            };
            let mut img = AerialImage::ideal(&format!("a{i}"), centre, opk, 4000.0, [1200, 900]);
            if i % 2 == 0 {
                (img.k1, img.k2, img.p1) = (-0.05, 0.01, 1e-4);
            }
            images.push(img);
        }
        let z_range = [-5.0, 30.0];
        let index = FootprintIndex::new(&images, z_range);
        let cams: Vec<FrameCamera> = images.iter().map(FrameCamera::from_aerial).collect();
        let mut seen = 0;
        for _ in 0..3000 {
            let p = Vector3::new(
                rng.next_f64() * 2000.0,
                rng.next_f64() * 2000.0,
                z_range[0] + rng.next_f64() * (z_range[1] - z_range[0]),
            );
            let cand = index.candidates([p.x, p.y], [p.x, p.y], [p.z, p.z]);
            for (i, cam) in cams.iter().enumerate() {
                if cam
                    .project_world(&p)
                    .is_some_and(|(u, v)| cam.contains(u, v))
                {
                    seen += 1;
                    assert!(cand.binary_search(&i).is_ok(), "image {i} sees {p:?}");
                }
            }
            assert!(
                cand.len() < images.len() / 2,
                "the index narrows the search"
            );
        }
        assert!(seen > 1000, "{seen}");
        // Outside the indexed heights: every image.
        assert_eq!(
            index.candidates([0.0; 2], [1.0; 2], [50.0, 50.0]).len(),
            200
        );
    }
}
