//! Colour samples to grey: the JPEG/JFIF luma `Y = 0.299 R + 0.587 G + 0.114 B`, in the 16-bit fixed point
//! of the JFIF reference code (weights 19595, 38470, 7471 of 65536, rounded to nearest).

/// Luma of 8-bit R, G, B.
#[inline]
pub fn luma8(r: u8, g: u8, b: u8) -> u8 {
    ((19595 * u32::from(r) + 38470 * u32::from(g) + 7471 * u32::from(b) + 32768) >> 16) as u8
}

/// Luma of 16-bit R, G, B.
#[inline]
pub fn luma16(r: u16, g: u16, b: u16) -> u16 {
    ((19595 * u64::from(r) + 38470 * u64::from(g) + 7471 * u64::from(b) + 32768) >> 16) as u16
}

/// How the samples of one pixel are laid out in a decoded row.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Channels {
    /// Grey, optionally followed by `extra` samples (alpha) per pixel.
    Grey { extra: usize },
    /// R, G, B, optionally followed by `extra` samples per pixel.
    Rgb { extra: usize },
    /// Y, Cb, Cr: grey is the Y sample.
    YCbCr,
}

impl Channels {
    /// Samples per pixel.
    pub fn samples(self) -> usize {
        match self {
            Channels::Grey { extra } => 1 + extra,
            Channels::Rgb { extra } => 3 + extra,
            Channels::YCbCr => 3,
        }
    }
}

/// Grey of every pixel of 8-bit `samples` (whole pixels) into `out`.
pub fn grey_row8(samples: &[u8], channels: Channels, out: &mut Vec<u8>) {
    grey_row(samples, channels, out, luma8);
}

/// Grey of every pixel of 16-bit `samples` into `out`.
pub fn grey_row16(samples: &[u16], channels: Channels, out: &mut Vec<u16>) {
    grey_row(samples, channels, out, luma16);
}

/// Grey of every pixel of `samples` into `out`: the first sample of grey and YCbCr pixels, `luma` of RGB ones.
fn grey_row<T: Copy>(samples: &[T], channels: Channels, out: &mut Vec<T>, luma: fn(T, T, T) -> T) {
    out.clear();
    let n = channels.samples();
    match channels {
        Channels::Grey { extra: 0 } => out.extend_from_slice(samples),
        Channels::Grey { .. } | Channels::YCbCr => {
            out.extend(samples.chunks_exact(n).map(|p| p[0]))
        }
        Channels::Rgb { .. } => out.extend(samples.chunks_exact(n).map(|p| luma(p[0], p[1], p[2]))),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn luma_weights_and_extremes() {
        assert_eq!(luma8(255, 255, 255), 255);
        assert_eq!(luma8(0, 0, 0), 0);
        assert_eq!(luma8(255, 0, 0), 76); // 0.299 · 255 = 76.2
        assert_eq!(luma8(0, 255, 0), 150); // 0.587 · 255 = 149.7
        assert_eq!(luma8(0, 0, 255), 29); // 0.114 · 255 = 29.1
        assert_eq!(luma16(65535, 65535, 65535), 65535);
        assert_eq!(luma16(0, 65535, 0), 38469); // 0.587 · 65535 = 38469.0
    }

    #[test]
    fn rows_pick_or_mix_channels() {
        let mut out = Vec::new();
        grey_row8(
            &[10, 20, 30, 99, 40, 50, 60, 99],
            Channels::Rgb { extra: 1 },
            &mut out,
        );
        assert_eq!(out, vec![luma8(10, 20, 30), luma8(40, 50, 60)]);
        grey_row8(&[7, 1, 2, 8, 3, 4], Channels::YCbCr, &mut out);
        assert_eq!(out, vec![7, 8]);
        let mut out16 = Vec::new();
        grey_row16(&[1000, 5, 2000, 6], Channels::Grey { extra: 1 }, &mut out16);
        assert_eq!(out16, vec![1000, 2000]);
    }
}
