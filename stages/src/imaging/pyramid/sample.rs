//! The two sample types a pyramid stores (u8, u16): their byte encoding, the 2 × 2 box average that makes
//! the next level, and rows of one depth stored at the other.

/// A stored sample type.
pub trait Sample: Copy + Default + PartialEq + Send + Sync + 'static {
    /// Bytes per sample in the file.
    const BYTES: usize;
    /// Average of four samples, rounded to nearest (halves up).
    fn average4(a: Self, b: Self, c: Self, d: Self) -> Self;
    /// Append the little-endian bytes of `samples` to `out`.
    fn extend_le(samples: &[Self], out: &mut Vec<u8>);
    /// The sample at `index` of little-endian `bytes`.
    fn read_le(bytes: &[u8], index: usize) -> Self;
    /// As u16 (for the white level).
    fn as_u16(self) -> u16;
    /// `row` as 8-bit samples: itself, or narrowed ([`narrow_row`]) into `scratch`.
    fn row_as_u8<'a>(row: &'a [Self], scratch: &'a mut Vec<u8>) -> &'a [u8];
    /// `row` as 16-bit samples: itself, or widened ([`widen_row`]) into `scratch`.
    fn row_as_u16<'a>(row: &'a [Self], scratch: &'a mut Vec<u16>) -> &'a [u16];
}

impl Sample for u8 {
    const BYTES: usize = 1;

    #[inline]
    fn average4(a: u8, b: u8, c: u8, d: u8) -> u8 {
        ((u16::from(a) + u16::from(b) + u16::from(c) + u16::from(d) + 2) >> 2) as u8
    }

    fn extend_le(samples: &[u8], out: &mut Vec<u8>) {
        out.extend_from_slice(samples);
    }

    #[inline]
    fn read_le(bytes: &[u8], index: usize) -> u8 {
        bytes[index]
    }

    fn as_u16(self) -> u16 {
        u16::from(self)
    }

    fn row_as_u8<'a>(row: &'a [u8], _: &'a mut Vec<u8>) -> &'a [u8] {
        row
    }

    fn row_as_u16<'a>(row: &'a [u8], scratch: &'a mut Vec<u16>) -> &'a [u16] {
        widen_row(row, scratch);
        scratch
    }
}

impl Sample for u16 {
    const BYTES: usize = 2;

    #[inline]
    fn average4(a: u16, b: u16, c: u16, d: u16) -> u16 {
        ((u32::from(a) + u32::from(b) + u32::from(c) + u32::from(d) + 2) >> 2) as u16
    }

    fn extend_le(samples: &[u16], out: &mut Vec<u8>) {
        out.reserve(samples.len() * 2);
        for s in samples {
            out.extend_from_slice(&s.to_le_bytes());
        }
    }

    #[inline]
    fn read_le(bytes: &[u8], index: usize) -> u16 {
        u16::from_le_bytes([bytes[2 * index], bytes[2 * index + 1]])
    }

    fn as_u16(self) -> u16 {
        self
    }

    fn row_as_u8<'a>(row: &'a [u16], scratch: &'a mut Vec<u8>) -> &'a [u8] {
        narrow_row(row, scratch);
        scratch
    }

    fn row_as_u16<'a>(row: &'a [u16], _: &'a mut Vec<u16>) -> &'a [u16] {
        row
    }
}

/// One row of the next level from rows `a` and `b` (same length `w`) of this level: `out[i]` averages columns
/// `2i` and `2i + 1` of both rows; an odd last column pairs with itself. `out` gets `w.div_ceil(2)` samples.
pub fn reduce_rows<S: Sample>(a: &[S], b: &[S], out: &mut Vec<S>) {
    out.clear();
    let w = a.len().min(b.len());
    let pairs = w / 2;
    out.reserve(w.div_ceil(2));
    // Whole pairs as exact chunks: no bounds checks, so the loop vectorises.
    out.extend(
        a[..2 * pairs]
            .chunks_exact(2)
            .zip(b[..2 * pairs].chunks_exact(2))
            .map(|(x, y)| S::average4(x[0], x[1], y[0], y[1])),
    );
    if w % 2 == 1 {
        let i = w - 1;
        out.push(S::average4(a[i], a[i], b[i], b[i]));
    }
}

/// An 8-bit row as 16-bit samples (`v · 257`, so 255 becomes 65535), into `out`.
pub fn widen_row(row: &[u8], out: &mut Vec<u16>) {
    out.clear();
    out.extend(row.iter().map(|&v| u16::from(v) * 257));
}

/// A 16-bit row as 8-bit samples (`v / 257`, rounded), into `out`.
pub fn narrow_row(row: &[u16], out: &mut Vec<u8>) {
    out.clear();
    out.extend(row.iter().map(|&v| ((u32::from(v) + 128) / 257) as u8));
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn averages_round_to_nearest() {
        assert_eq!(u8::average4(0, 0, 1, 1), 1); // 0.5 rounds up
        assert_eq!(u8::average4(0, 0, 0, 1), 0); // 0.25 rounds down
        assert_eq!(u8::average4(255, 255, 255, 255), 255);
        assert_eq!(u16::average4(65535, 65535, 65535, 65534), 65535);
        assert_eq!(u16::average4(1000, 2000, 3000, 4000), 2500);
    }

    #[test]
    fn odd_rows_pair_the_last_column_with_itself() {
        let mut out = Vec::new();
        reduce_rows(&[0u8, 4, 8], &[4u8, 8, 12], &mut out);
        assert_eq!(out, vec![4, 10]);
        let mut bytes = Vec::new();
        u16::extend_le(&[1, 258], &mut bytes);
        assert_eq!(bytes, vec![1, 0, 2, 1]);
        assert_eq!(u16::read_le(&bytes, 1), 258);
    }
}
