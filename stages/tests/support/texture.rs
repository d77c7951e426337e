//! Random grey textures for known-answer tests of image resolution: a texture and its copies enlarged by
//! pixel repetition carry the same content at different pixel sizes.

use skytie_stages::estimators::SplitMix64;
use skytie_stages::imaging::GrayImage;

/// A random texture of `width × height` grey values, each repeated `repeat × repeat` times.
pub fn repeated_texture(width: usize, height: usize, repeat: usize, seed: u64) -> GrayImage {
    let mut rng = SplitMix64::new(seed);
    let base: Vec<f32> = (0..width * height).map(|_| rng.next_f64() as f32).collect();
    let (w, h) = (width * repeat, height * repeat);
    let data = (0..w * h)
        .map(|i| base[(i / w / repeat) * width + (i % w) / repeat])
        .collect();
    GrayImage::from_vec(w, h, data).expect("w × h values")
}
