//! Raster drawing for the registration views: grey crops scaled to a display height, side-by-side
//! composition, lines and ring markers in colour. Pixel coordinates are continuous (first pixel centre at
//! (0.5, 0.5)) as everywhere in skytie.

use skytie_stages::imaging::image::{GrayImage, RgbImage};
use skytie_stages::imaging::pyramid::ScaledWindow;

pub type Rgb = [f32; 3];
pub const GREEN: Rgb = [0.0, 0.85, 0.2];
pub const RED: Rgb = [1.0, 0.1, 0.1];
pub const YELLOW: Rgb = [1.0, 0.85, 0.0];
pub const BLUE: Rgb = [0.15, 0.45, 1.0];

/// A grey raster sampled bilinearly at array coordinates of its full-resolution pixels (pixel centres at
/// integers), 0 outside it: a whole image, or a window of an image's pyramid level that covers every position
/// asked for.
pub trait Raster {
    fn bilinear(&self, x: f64, y: f64) -> f32;
}

/// A raster that is black everywhere (an image a view misses entirely).
pub struct Black;

impl Raster for Black {
    fn bilinear(&self, _x: f64, _y: f64) -> f32 {
        0.0
    }
}

impl Raster for GrayImage {
    fn bilinear(&self, x: f64, y: f64) -> f32 {
        bilinear(self, x, y)
    }
}

impl Raster for ScaledWindow {
    /// Samples the window's level at the full-resolution array position (x, y); 0 outside the whole image
    /// at that level. Level pixels outside the window repeat its nearest edge pixel (the window is read to
    /// cover the positions asked for, so this happens only at the image's own edges, as for a whole image).
    fn bilinear(&self, x: f64, y: f64) -> f32 {
        let s = self.scale();
        // Level 0 as given (the same arithmetic as for a whole image).
        let (lx, ly) = if self.level == 0 {
            (x, y)
        } else {
            ((x + 0.5) / s - 0.5, (y + 0.5) / s - 0.5)
        };
        let (lw, lh) = self.level_size;
        let img = &self.image;
        if img.width == 0 || img.height == 0 {
            return 0.0;
        }
        if !(lx >= 0.0 && ly >= 0.0) || lx > (lw - 1) as f64 || ly > (lh - 1) as f64 {
            return 0.0;
        }
        let (x0, y0) = (lx.floor() as usize, ly.floor() as usize);
        let (x1, y1) = ((x0 + 1).min(lw - 1), (y0 + 1).min(lh - 1));
        let (fx, fy) = ((lx - x0 as f64) as f32, (ly - y0 as f64) as f32);
        let at = |c: usize, r: usize| {
            let wc = (c as i64 - self.rect.x0).clamp(0, img.width as i64 - 1) as usize;
            let wr = (r as i64 - self.rect.y0).clamp(0, img.height as i64 - 1) as usize;
            img.get(wc, wr)
        };
        let top = at(x0, y0) * (1.0 - fx) + at(x1, y0) * fx;
        let bottom = at(x0, y1) * (1.0 - fx) + at(x1, y1) * fx;
        top * (1.0 - fy) + bottom * fy
    }
}

/// A crop of `img` with top-left corner (x0, y0) and size (w, h) source pixels, scaled by `scale` with
/// bilinear sampling; outside the source is black. Returns the RGB image.
pub fn crop_scaled<R: Raster + ?Sized>(
    img: &R,
    x0: f64,
    y0: f64,
    w: f64,
    h: f64,
    scale: f64,
) -> RgbImage {
    let (ow, oh) = (
        ((w * scale).round() as usize).max(1),
        ((h * scale).round() as usize).max(1),
    );
    let mut out = RgbImage::filled(ow, oh, [0.0; 3]);
    for row in 0..oh {
        let sy = y0 + (row as f64 + 0.5) / scale - 0.5;
        for col in 0..ow {
            let sx = x0 + (col as f64 + 0.5) / scale - 0.5;
            let v = img.bilinear(sx, sy);
            out.set(col, row, [v, v, v]);
        }
    }
    out
}

/// A `w × h` image whose pixel (col, row) samples `img` at `source(col + 0.5, row + 0.5)` (continuous pixel
/// coordinates, centres at +0.5) bilinearly; black where `source` is `None` or outside `img`.
pub fn resample_on_ground<R: Raster + ?Sized>(
    img: &R,
    w: usize,
    h: usize,
    source: impl Fn(f64, f64) -> Option<(f64, f64)>,
) -> RgbImage {
    let mut out = RgbImage::filled(w.max(1), h.max(1), [0.0; 3]);
    for row in 0..h {
        for col in 0..w {
            if let Some((u, v)) = source(col as f64 + 0.5, row as f64 + 0.5) {
                let s = img.bilinear(u - 0.5, v - 0.5);
                out.set(col, row, [s, s, s]);
            }
        }
    }
    out
}

/// Bilinear sample at array coordinates (pixel centres at integers); 0 outside.
fn bilinear(img: &GrayImage, x: f64, y: f64) -> f32 {
    if !(x >= 0.0 && y >= 0.0) || x > (img.width - 1) as f64 || y > (img.height - 1) as f64 {
        return 0.0;
    }
    let (x0, y0) = (x.floor() as usize, y.floor() as usize);
    let (x1, y1) = ((x0 + 1).min(img.width - 1), (y0 + 1).min(img.height - 1));
    let (fx, fy) = ((x - x0 as f64) as f32, (y - y0 as f64) as f32);
    let top = img.get(x0, y0) * (1.0 - fx) + img.get(x1, y0) * fx;
    let bottom = img.get(x0, y1) * (1.0 - fx) + img.get(x1, y1) * fx;
    top * (1.0 - fy) + bottom * fy
}

/// `left` and `right` side by side with a `gap`-pixel white band; the taller height wins.
pub fn side_by_side(left: &RgbImage, right: &RgbImage, gap: usize) -> RgbImage {
    let w = left.width + gap + right.width;
    let h = left.height.max(right.height);
    let mut out = RgbImage::filled(w, h, [1.0; 3]);
    for (img, x_off) in [(left, 0), (right, left.width + gap)] {
        for row in 0..img.height {
            for col in 0..img.width {
                out.set(col + x_off, row, img.get(col, row));
            }
        }
    }
    out
}

fn put(img: &mut RgbImage, x: i64, y: i64, c: Rgb) {
    if x >= 0 && y >= 0 && (x as usize) < img.width && (y as usize) < img.height {
        img.set(x as usize, y as usize, c);
    }
}

/// A line between two continuous pixel positions, `width` pixels thick (square brush).
pub fn line(img: &mut RgbImage, a: (f64, f64), b: (f64, f64), c: Rgb, width: i64) {
    let len = (b.0 - a.0).hypot(b.1 - a.1);
    let steps = (len.ceil() as usize).max(1) * 2;
    let r = width / 2;
    for i in 0..=steps {
        let t = i as f64 / steps as f64;
        let x = (a.0 + (b.0 - a.0) * t - 0.5).round() as i64;
        let y = (a.1 + (b.1 - a.1) * t - 0.5).round() as i64;
        for dy in -r..=(width - 1 - r) {
            for dx in -r..=(width - 1 - r) {
                put(img, x + dx, y + dy, c);
            }
        }
    }
}

/// A ring of radius `radius` px around a continuous pixel position, 2 px thick.
pub fn ring(img: &mut RgbImage, centre: (f64, f64), radius: f64, c: Rgb) {
    let (cx, cy) = (centre.0 - 0.5, centre.1 - 0.5);
    let r = radius.ceil() as i64 + 2;
    let (x0, y0) = (cx.round() as i64, cy.round() as i64);
    for y in (y0 - r)..=(y0 + r) {
        for x in (x0 - r)..=(x0 + r) {
            let d = (x as f64 - cx).hypot(y as f64 - cy);
            if (d - radius).abs() <= 1.0 {
                put(img, x, y, c);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn crop_scales_and_pads_with_black() {
        // A ramp g = column index (array coordinates) is reproduced exactly by bilinear sampling.
        let mut g = GrayImage::filled(4, 4, 0.0);
        for row in 0..4 {
            for col in 0..4 {
                g.set(col, row, col as f32);
            }
        }
        // Continuous (1, 1)–(3, 3) at scale 2: output column c has its centre at continuous 1 + (c + 0.5) / 2,
        // i.e. array coordinate 0.75 + c / 2.
        let c = crop_scaled(&g, 1.0, 1.0, 2.0, 2.0, 2.0);
        assert_eq!((c.width, c.height), (4, 4));
        for col in 0..4 {
            let want = 0.75 + col as f32 / 2.0;
            assert!((c.get(col, 2)[0] - want).abs() < 1e-6, "col {col}");
        }
        let outside = crop_scaled(&g, 10.0, 10.0, 2.0, 2.0, 1.0);
        assert_eq!(outside.get(0, 0), [0.0; 3]);
    }

    #[test]
    fn a_window_samples_like_the_whole_image() {
        let mut g = GrayImage::filled(40, 30, 0.0);
        for row in 0..30 {
            for col in 0..40 {
                g.set(col, row, ((col * 7 + row * 11) % 17) as f32 / 17.0);
            }
        }
        let window = ScaledWindow {
            image: GrayImage::from_vec(
                20,
                12,
                (0..12)
                    .flat_map(|r| (0..20).map(move |c| (c + 15, r + 10)))
                    .map(|(c, r)| g.get(c, r))
                    .collect(),
            )
            .unwrap(),
            level: 0,
            rect: skytie_stages::imaging::pyramid::PixelRect::new(15, 10, 20, 12),
            level_size: (40, 30),
            full_size: (40, 30),
        };
        for (x, y) in [(16.25, 11.5), (20.0, 15.75), (33.9, 20.1)] {
            assert_eq!(Raster::bilinear(&window, x, y), Raster::bilinear(&g, x, y));
        }
        assert_eq!(Raster::bilinear(&window, -0.5, 3.0), 0.0);
        assert_eq!(Raster::bilinear(&window, 39.5, 3.0), 0.0);
    }

    #[test]
    fn side_by_side_places_both() {
        let a = RgbImage::filled(2, 3, [0.0; 3]);
        let b = RgbImage::filled(3, 2, [0.5; 3]);
        let s = side_by_side(&a, &b, 1);
        assert_eq!((s.width, s.height), (6, 3));
        assert_eq!(s.get(2, 0), [1.0; 3]);
        assert_eq!(s.get(3, 1), [0.5; 3]);
        assert_eq!(s.get(3, 2), [1.0; 3]);
    }

    #[test]
    fn line_and_ring_draw_where_asked() {
        let mut img = RgbImage::filled(20, 20, [0.0; 3]);
        line(&mut img, (0.5, 10.5), (19.5, 10.5), RED, 1);
        assert_eq!(img.get(5, 10), RED);
        assert_eq!(img.get(5, 12), [0.0; 3]);
        ring(&mut img, (10.5, 5.5), 3.0, GREEN);
        assert_eq!(img.get(13, 5), GREEN);
        assert_eq!(img.get(10, 5), [0.0; 3]);
    }
}
