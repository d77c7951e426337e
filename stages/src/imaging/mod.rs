//! Image buffers and the low-level operations on them (sampling, filters, I/O).
//!
//! Pixel convention everywhere (campaign-format.md): continuous coordinates, the image's top-left corner is
//! (0, 0), u grows right, v down, the centre of the first pixel is (0.5, 0.5).

/// Huge-page advice for large image buffers (from `skytie-util`, shared with the engine).
pub use skytie_util::huge_pages;
pub mod budget;
pub mod decode;
pub mod equirect;
pub mod georef;
pub mod image;
pub mod ingest;
pub mod io;
pub mod io_error;
pub mod partial;
pub mod probe;
pub mod pyramid;
pub mod tiff_write;

pub mod bilinear_many;
pub mod border;
pub mod convolve;
pub mod gaussian;
pub mod gradient;
pub mod sample;

pub use border::Border;
pub use gaussian::gaussian_blur;
pub use image::{GrayImage, RgbImage};
pub mod resample;
pub mod wallis;
pub mod window;

/// Whether this CPU has AVX2, so that a test can compare an AVX2 path with the scalar one (it says so when
/// not).
#[cfg(all(test, target_arch = "x86_64"))]
pub(crate) fn avx2_to_compare() -> bool {
    let has = std::arch::is_x86_feature_detected!("avx2");
    if !has {
        eprintln!("no AVX2 on this CPU: nothing to compare");
    }
    has
}
