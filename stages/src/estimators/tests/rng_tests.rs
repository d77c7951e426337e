//! SplitMix64: reference values, determinism, distributions.

use crate::rng::{mix_seed, SplitMix64};

#[test]
fn matches_reference_splitmix64_sequence() {
    // Reference output of Vigna's splitmix64.c with state 0.
    let mut rng = SplitMix64::new(0);
    assert_eq!(rng.next_u64(), 0xE220_A839_7B1D_CDAF);
    assert_eq!(rng.next_u64(), 0x6E78_9E6A_A1B9_65F4);
    assert_eq!(rng.next_u64(), 0x06C4_5D18_8009_454F);
}

#[test]
fn same_seed_same_sequence() {
    let a: Vec<u64> = {
        let mut r = SplitMix64::new(42);
        (0..100).map(|_| r.next_u64()).collect()
    };
    let mut r = SplitMix64::new(42);
    assert!(a.iter().all(|&x| x == r.next_u64()));
    let mut other = SplitMix64::new(43);
    assert_ne!(a[0], other.next_u64());
    assert_ne!(mix_seed(7, 0), mix_seed(7, 1));
    assert_ne!(mix_seed(7, 0), mix_seed(8, 0));
    assert_eq!(mix_seed(7, 3), mix_seed(7, 3));
}

#[test]
fn uniform_and_gaussian_moments() {
    let mut r = SplitMix64::new(1);
    let n = 200_000;
    let (mut s, mut s2) = (0.0, 0.0);
    for _ in 0..n {
        let x = r.next_f64();
        assert!((0.0..1.0).contains(&x));
        s += x;
        s2 += x * x;
    }
    let mean = s / n as f64;
    assert!((mean - 0.5).abs() < 0.005);
    assert!((s2 / n as f64 - mean * mean - 1.0 / 12.0).abs() < 0.002);
    let (mut g, mut g2) = (0.0, 0.0);
    for _ in 0..n {
        let x = r.next_gaussian();
        g += x;
        g2 += x * x;
    }
    assert!((g / n as f64).abs() < 0.01);
    assert!((g2 / n as f64 - 1.0).abs() < 0.02);
}

#[test]
fn below_is_unbiased_and_in_range() {
    let mut r = SplitMix64::new(5);
    let mut counts = [0usize; 7];
    for _ in 0..70_000 {
        let k = r.below(7) as usize;
        counts[k] += 1;
    }
    // χ² with 6 degrees of freedom; 22.46 is the 0.999 quantile.
    let chi2: f64 = counts
        .iter()
        .map(|&c| (c as f64 - 10_000.0).powi(2) / 10_000.0)
        .sum();
    assert!(chi2 < 22.46, "chi2 {chi2}, counts {counts:?}");
    assert_eq!(r.below(0), 0);
    assert_eq!(r.below(1), 0);
}

#[test]
fn sample_distinct_gives_distinct_indices() {
    let mut r = SplitMix64::new(9);
    let mut out = [0usize; 4];
    for _ in 0..1000 {
        assert!(r.sample_distinct(6, &mut out));
        for i in 0..4 {
            assert!(out[i] < 6);
            for j in 0..i {
                assert_ne!(out[i], out[j]);
            }
        }
    }
    assert!(r.sample_distinct(4, &mut out));
    let mut sorted = out;
    sorted.sort_unstable();
    assert_eq!(sorted, [0, 1, 2, 3]);
    assert!(!r.sample_distinct(3, &mut out));
}
