//! Deterministic, stateless noise for the synthetic scene: integer hashing, a small seeded RNG
//! (SplitMix64), lattice value noise, gradient (Perlin-style) noise and fractal sums (fBm).
//!
//! Everything is a pure function of its inputs and a `seed`: no global state, so results do not depend on
//! thread count or evaluation order. Coordinates are f64 (scene-local metres times a frequency); the
//! returned values are f32.

/// SplitMix64 finaliser: a strong 64-bit mixing function.
#[inline]
pub fn mix64(mut z: u64) -> u64 {
    z = z.wrapping_add(0x9E37_79B9_7F4A_7C15);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

/// Hash of a 2-D integer lattice point and a seed (one mixing round over a linear combination).
#[inline]
pub fn hash2(ix: i64, iy: i64, seed: u64) -> u64 {
    mix64(
        (ix as u64).wrapping_mul(0x9E37_79B9_7F4A_7C15)
            ^ (iy as u64).wrapping_mul(0xC2B2_AE3D_27D4_EB4F)
            ^ seed,
    )
}

/// Hash of a 3-D integer lattice point and a seed.
#[inline]
pub fn hash3(ix: i64, iy: i64, iz: i64, seed: u64) -> u64 {
    mix64(
        (ix as u64).wrapping_mul(0x9E37_79B9_7F4A_7C15)
            ^ (iy as u64).wrapping_mul(0xC2B2_AE3D_27D4_EB4F)
            ^ (iz as u64).wrapping_mul(0x1656_67B1_9E37_79F9)
            ^ seed,
    )
}

/// Map a hash to a uniform f32 in [0, 1).
#[inline]
pub fn unit_f32(h: u64) -> f32 {
    (h >> 40) as f32 * (1.0 / (1u64 << 24) as f32)
}

/// Map a hash to a uniform f64 in [0, 1).
#[inline]
pub fn unit_f64(h: u64) -> f64 {
    (h >> 11) as f64 * (1.0 / (1u64 << 53) as f64)
}

/// A tiny seeded RNG (SplitMix64) for layout generation; sequential and deterministic.
#[derive(Clone, Debug)]
pub struct SplitMix64 {
    state: u64,
}

impl SplitMix64 {
    pub fn new(seed: u64) -> Self {
        Self {
            state: mix64(seed ^ 0x5EED_5EED_0000_0001),
        }
    }

    pub fn next_u64(&mut self) -> u64 {
        self.state = self.state.wrapping_add(0x9E37_79B9_7F4A_7C15);
        mix64(self.state)
    }

    /// Uniform in [0, 1).
    pub fn next_f64(&mut self) -> f64 {
        unit_f64(self.next_u64())
    }

    /// Uniform in [lo, hi) (returns `lo` when `hi <= lo`).
    pub fn range(&mut self, lo: f64, hi: f64) -> f64 {
        if hi <= lo {
            lo
        } else {
            lo + (hi - lo) * self.next_f64()
        }
    }

    /// `true` with probability `p`.
    pub fn chance(&mut self, p: f64) -> bool {
        self.next_f64() < p
    }

    /// Uniform integer in 0..n (0 when n == 0).
    pub fn below(&mut self, n: usize) -> usize {
        if n == 0 {
            0
        } else {
            (self.next_u64() % n as u64) as usize
        }
    }
}

#[inline]
fn smooth(t: f32) -> f32 {
    // quintic fade: C2-continuous
    t * t * t * (t * (t * 6.0 - 15.0) + 10.0)
}

#[inline]
fn lerp(a: f32, b: f32, t: f32) -> f32 {
    a + (b - a) * t
}

/// `floor` without a libm call (exact for |x| < 2^62; NaN maps to 0).
#[inline]
pub fn floor_i64(x: f64) -> i64 {
    let i = x as i64;
    if (i as f64) > x {
        i - 1
    } else {
        i
    }
}

/// `floor` as f64 via [`floor_i64`].
#[inline]
pub fn floor_f64(x: f64) -> f64 {
    floor_i64(x) as f64
}

#[inline]
fn split(x: f64) -> (i64, f32) {
    let i = floor_i64(x);
    (i, (x - i as f64) as f32)
}

#[inline]
fn lattice_value(h: u64) -> f32 {
    unit_f32(h) * 2.0 - 1.0
}

/// 2-D value noise in [-1, 1], unit lattice spacing (scale the coordinates for other frequencies).
pub fn value2(x: f64, y: f64, seed: u64) -> f32 {
    let (ix, fx) = split(x);
    let (iy, fy) = split(y);
    let (sx, sy) = (smooth(fx), smooth(fy));
    let v00 = lattice_value(hash2(ix, iy, seed));
    let v10 = lattice_value(hash2(ix + 1, iy, seed));
    let v01 = lattice_value(hash2(ix, iy + 1, seed));
    let v11 = lattice_value(hash2(ix + 1, iy + 1, seed));
    lerp(lerp(v00, v10, sx), lerp(v01, v11, sx), sy)
}

/// 3-D value noise in [-1, 1], unit lattice spacing.
pub fn value3(x: f64, y: f64, z: f64, seed: u64) -> f32 {
    let (ix, fx) = split(x);
    let (iy, fy) = split(y);
    let (iz, fz) = split(z);
    let (sx, sy, sz) = (smooth(fx), smooth(fy), smooth(fz));
    let v = |dx: i64, dy: i64, dz: i64| lattice_value(hash3(ix + dx, iy + dy, iz + dz, seed));
    let a = lerp(
        lerp(v(0, 0, 0), v(1, 0, 0), sx),
        lerp(v(0, 1, 0), v(1, 1, 0), sx),
        sy,
    );
    let b = lerp(
        lerp(v(0, 0, 1), v(1, 0, 1), sx),
        lerp(v(0, 1, 1), v(1, 1, 1), sx),
        sy,
    );
    lerp(a, b, sz)
}

/// The 8 gradient directions of [`gradient2`] (axes scaled by √2 so all have the same length).
const GRADIENTS: [(f32, f32); 8] = [
    (1.0, 1.0),
    (1.0, -1.0),
    (-1.0, 1.0),
    (-1.0, -1.0),
    (std::f32::consts::SQRT_2, 0.0),
    (-std::f32::consts::SQRT_2, 0.0),
    (0.0, std::f32::consts::SQRT_2),
    (0.0, -std::f32::consts::SQRT_2),
];

#[inline]
fn grad2(h: u64, fx: f32, fy: f32) -> f32 {
    let (gx, gy) = GRADIENTS[(h >> 61) as usize];
    gx * fx + gy * fy
}

/// 2-D gradient (Perlin-style) noise, roughly in [-1, 1], zero at lattice points, unit lattice spacing.
pub fn gradient2(x: f64, y: f64, seed: u64) -> f32 {
    let (ix, fx) = split(x);
    let (iy, fy) = split(y);
    let (sx, sy) = (smooth(fx), smooth(fy));
    let g00 = grad2(hash2(ix, iy, seed), fx, fy);
    let g10 = grad2(hash2(ix + 1, iy, seed), fx - 1.0, fy);
    let g01 = grad2(hash2(ix, iy + 1, seed), fx, fy - 1.0);
    let g11 = grad2(hash2(ix + 1, iy + 1, seed), fx - 1.0, fy - 1.0);
    lerp(lerp(g00, g10, sx), lerp(g01, g11, sx), sy) * 0.9
}

/// Fractal sum of 2-D gradient noise: `octaves` octaves starting at `base_freq` cycles per unit,
/// frequency ×2 and amplitude ×`gain` per octave; normalised to roughly [-1, 1].
pub fn fbm2(x: f64, y: f64, seed: u64, base_freq: f64, octaves: u32, gain: f32) -> f32 {
    let mut sum = 0.0f32;
    let mut norm = 0.0f32;
    let mut amp = 1.0f32;
    let mut freq = base_freq;
    for o in 0..octaves {
        sum += amp
            * gradient2(
                x * freq,
                y * freq,
                seed.wrapping_add(o as u64 * 0x1000_0001),
            );
        norm += amp;
        amp *= gain;
        freq *= 2.0;
    }
    if norm > 0.0 {
        sum / norm
    } else {
        0.0
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn value_noise_matches_lattice_values_and_is_bounded() {
        // At integer points value noise equals the hashed lattice value exactly.
        for (ix, iy) in [(0i64, 0i64), (3, -7), (-12, 5)] {
            let expect = unit_f32(hash2(ix, iy, 9)) * 2.0 - 1.0;
            assert_eq!(value2(ix as f64, iy as f64, 9), expect);
        }
        for i in 0..1000 {
            let x = i as f64 * 0.137 - 50.0;
            let v = value2(x, x * 0.71 + 3.0, 1);
            assert!((-1.0..=1.0).contains(&v));
            let g = gradient2(x, x * 0.31, 2);
            assert!((-1.0..=1.0).contains(&g), "{g}");
        }
    }

    #[test]
    fn fast_floor_matches_floor() {
        for x in [
            -2.5, -2.0, -1e-12, 0.0, 1e-12, 0.999, 1.0, 3.7, -123456.25, 98765.5,
        ] {
            assert_eq!(floor_f64(x), f64::floor(x), "{x}");
        }
    }

    #[test]
    fn gradient_noise_is_zero_on_lattice_and_continuous() {
        assert_eq!(gradient2(4.0, -2.0, 5), 0.0);
        let a = gradient2(1.5, 2.5, 5);
        let b = gradient2(1.5 + 1e-6, 2.5, 5);
        assert!((a - b).abs() < 1e-4);
    }

    #[test]
    fn different_seeds_give_different_noise_and_same_seed_same() {
        let mut diff = 0;
        for i in 0..100 {
            let x = i as f64 * 0.37 + 0.1;
            assert_eq!(fbm2(x, 0.3, 7, 1.0, 4, 0.5), fbm2(x, 0.3, 7, 1.0, 4, 0.5));
            if fbm2(x, 0.3, 7, 1.0, 4, 0.5) != fbm2(x, 0.3, 8, 1.0, 4, 0.5) {
                diff += 1;
            }
        }
        assert!(diff > 90);
    }

    #[test]
    fn splitmix_is_deterministic_and_uniformish() {
        let mut a = SplitMix64::new(42);
        let mut b = SplitMix64::new(42);
        let mut mean = 0.0;
        for _ in 0..10_000 {
            let x = a.next_f64();
            assert_eq!(x, b.next_f64());
            assert!((0.0..1.0).contains(&x));
            mean += x;
        }
        mean /= 10_000.0;
        assert!((mean - 0.5).abs() < 0.01, "{mean}");
    }
}
