//! A small, self-contained, deterministic PRNG (SplitMix64, Steele/Lea/Flood 2014) for everything random in
//! skytie (RANSAC, MLESAC, sampling): explicit seeds only, no global state, identical sequences on every
//! platform. Per-item streams for parallel code come from [`mix_seed`]`(seed, item_index)`.

/// SplitMix64 generator: 64-bit state advanced by a Weyl increment, output through a bit mixer.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct SplitMix64 {
    state: u64,
}

const GOLDEN_GAMMA: u64 = 0x9E37_79B9_7F4A_7C15;

/// The SplitMix64 output function (a strong 64-bit mixer, bijective).
pub fn mix64(mut z: u64) -> u64 {
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

/// A seed for item `index` of a computation seeded with `seed` (decorrelated streams per item, so parallel
/// code gives the same result whatever the thread count).
pub fn mix_seed(seed: u64, index: u64) -> u64 {
    mix64(seed ^ mix64(index.wrapping_add(GOLDEN_GAMMA)))
}

/// FNV-1a offset basis and prime (64 bit).
const FNV_OFFSET: u64 = 0xcbf2_9ce4_8422_2325;
const FNV_PRIME: u64 = 0x0000_0100_0000_01b3;

/// FNV-1a of `bytes`, continued from `hash`.
fn fnv1a(hash: u64, bytes: impl IntoIterator<Item = u8>) -> u64 {
    bytes
        .into_iter()
        .fold(hash, |h, b| (h ^ u64::from(b)).wrapping_mul(FNV_PRIME))
}

/// A stable 64-bit hash (FNV-1a) of a name: the same on every platform, run and Rust version (unlike
/// `DefaultHasher`), for deriving per-item seeds from item ids.
pub fn stable_hash(text: &str) -> u64 {
    fnv1a(FNV_OFFSET, text.bytes())
}

/// [`stable_hash`] of several names, each followed by the byte 0xff (so `["ab", "c"]` and `["a", "bc"]` differ).
pub fn stable_hash_parts(parts: &[&str]) -> u64 {
    parts.iter().fold(FNV_OFFSET, |h, part| {
        fnv1a(h, part.bytes().chain(std::iter::once(0xff)))
    })
}

/// The seed of one pair of named items (a recording and an image, two recordings) in a computation seeded
/// with `seed`: derived from the seed and both names only, so it does not depend on the order of work.
pub fn pair_seed(seed: u64, first: &str, second: &str) -> u64 {
    mix_seed(
        seed,
        stable_hash(first) ^ stable_hash(second).rotate_left(29),
    )
}

impl SplitMix64 {
    /// A generator with the given seed.
    pub fn new(seed: u64) -> Self {
        Self { state: seed }
    }

    /// Next 64 random bits.
    pub fn next_u64(&mut self) -> u64 {
        self.state = self.state.wrapping_add(GOLDEN_GAMMA);
        mix64(self.state)
    }

    /// Uniform in [0, 1) with 53 random bits.
    pub fn next_f64(&mut self) -> f64 {
        (self.next_u64() >> 11) as f64 * (1.0 / (1u64 << 53) as f64)
    }

    /// Uniform integer in [0, n) without modulo bias (Lemire's multiply-and-reject); 0 if n = 0.
    pub fn below(&mut self, n: u64) -> u64 {
        if n == 0 {
            return 0;
        }
        let threshold = n.wrapping_neg() % n;
        loop {
            let m = u128::from(self.next_u64()) * u128::from(n);
            if (m as u64) >= threshold {
                return (m >> 64) as u64;
            }
        }
    }

    /// Standard normal deviate (Box–Muller, one value per call; no hidden cached state).
    pub fn next_gaussian(&mut self) -> f64 {
        // 1 − U ∈ (0, 1] keeps the logarithm finite.
        let u1 = 1.0 - self.next_f64();
        let u2 = self.next_f64();
        (-2.0 * u1.ln()).sqrt() * (std::f64::consts::TAU * u2).cos()
    }

    /// Fills `out` with distinct indices drawn uniformly from [0, n) (in draw order); `false` (and `out`
    /// unspecified) if `out.len() > n`. Rejection sampling: meant for small samples (RANSAC minimal sets).
    pub fn sample_distinct(&mut self, n: usize, out: &mut [usize]) -> bool {
        if out.len() > n {
            return false;
        }
        for i in 0..out.len() {
            loop {
                let candidate = self.below(n as u64) as usize;
                if !out[..i].contains(&candidate) {
                    out[i] = candidate;
                    break;
                }
            }
        }
        true
    }
}

/// The successive states (after `seed`) of Knuth's MMIX linear congruential generator,
/// `s ← 6364136223846793005·s + 1442695040888963407`: the data of the tests of image kernels.
#[cfg(test)]
pub(crate) fn mmix_states(seed: u64) -> impl Iterator<Item = u64> {
    std::iter::successors(Some(seed), |s| {
        Some(
            s.wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407),
        )
    })
    .skip(1)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn stable_hashes_are_fnv1a_and_parts_are_separated() {
        // The FNV-1a 64-bit test vectors.
        assert_eq!(stable_hash(""), 0xcbf2_9ce4_8422_2325);
        assert_eq!(stable_hash("a"), 0xaf63_dc4c_8601_ec8c);
        assert_ne!(
            stable_hash_parts(&["ab", "c"]),
            stable_hash_parts(&["a", "bc"])
        );
        assert_eq!(pair_seed(7, "x", "y"), pair_seed(7, "x", "y"));
        assert_ne!(pair_seed(7, "x", "y"), pair_seed(7, "y", "x"));
    }
}
