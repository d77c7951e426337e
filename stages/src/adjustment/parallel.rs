//! Deterministic data parallelism for the adjustment: work is cut into chunks whose boundaries depend only on
//! the problem size, never on the thread count, and partial sums are combined in chunk order — so every
//! result is bit-identical whether rayon runs on one thread or many.

use rayon::prelude::*;

/// Items per chunk of a parallel loop.
pub const CHUNK: usize = 512;

/// Σ f(i) for i in 0..n: per chunk in index order, the chunk sums in chunk order.
pub fn ordered_sum(n: usize, f: impl Fn(usize) -> f64 + Sync) -> f64 {
    let parts: Vec<f64> = (0..n.div_ceil(CHUNK))
        .into_par_iter()
        .map(|c| (c * CHUNK..((c + 1) * CHUNK).min(n)).map(&f).sum::<f64>())
        .collect();
    parts.iter().sum()
}

/// Splits `values` into consecutive pieces that end at the ascending `ends` (the last must be
/// `values.len()`), e.g. the values of chunks of rows of a compressed-row structure.
pub fn split_at_ends<'a, T>(mut values: &'a mut [T], ends: &[usize]) -> Vec<&'a mut [T]> {
    let mut pieces = Vec::with_capacity(ends.len());
    let mut at = 0;
    for &end in ends {
        let (head, tail) = values.split_at_mut(end - at);
        pieces.push(head);
        values = tail;
        at = end;
    }
    pieces
}

/// Chunk boundaries over `items` items: `(first, end)` per chunk.
pub fn chunks(items: usize) -> Vec<(usize, usize)> {
    (0..items.div_ceil(CHUNK))
        .map(|c| (c * CHUNK, ((c + 1) * CHUNK).min(items)))
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sums_and_splits_do_not_depend_on_the_thread_count() {
        let f = |i: usize| 1.0 / (1.0 + i as f64).powf(1.3);
        let run = |threads| {
            rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap()
                .install(|| ordered_sum(100_000, f))
        };
        assert_eq!(run(1).to_bits(), run(3).to_bits());
        let mut v = [0, 1, 2, 3, 4, 5];
        let pieces = split_at_ends(&mut v, &[2, 2, 5, 6]);
        assert_eq!(
            pieces.iter().map(|p| p.len()).collect::<Vec<_>>(),
            [2, 0, 3, 1]
        );
        assert_eq!(chunks(CHUNK + 1), vec![(0, CHUNK), (CHUNK, CHUNK + 1)]);
    }
}
