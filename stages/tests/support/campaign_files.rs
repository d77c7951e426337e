//! Image files for the campaign reader's tests: any readable image of a given size will do.

use skytie_stages::imaging::io::save_rgb;
use skytie_stages::imaging::RgbImage;
use std::path::Path;

/// Writes a `width × height` JPEG at `path`: blue-grey with a white line across the middle row.
pub fn image(path: &Path, width: usize, height: usize) {
    let mut img = RgbImage::filled(width, height, [0.2, 0.5, 0.7]);
    for x in 0..width {
        img.set(x, height / 2, [1.0, 1.0, 1.0]);
    }
    save_rgb(path, &img, 90).unwrap();
}
