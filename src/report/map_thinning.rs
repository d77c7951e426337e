//! Which recordings the interactive map carries when a campaign has more than [`MAP_DETAIL_LIMIT`] of them:
//! every flagged recording (not corrected, or in a segment whose verification failed), the two ends of every
//! run of equal verification status (so the status bands start and end where they do in the full trajectory),
//! the first and the last recording, and recordings at an even stride along the trajectory that fill the rest
//! of the budget. The map's data file then grows with the number of flagged recordings only, not with the
//! campaign: at most [`MAP_DETAIL_LIMIT`] + flagged + run ends recordings (about 150 bytes each) whatever the
//! campaign's length. Campaigns within the limit keep every recording.

/// Most recordings the map carries besides the flagged ones and the ends of status runs.
pub const MAP_DETAIL_LIMIT: usize = 10_000;

/// A run of consecutive recordings (indices `from..=to` in trajectory order) whose verification segments have
/// the same status.
#[derive(Clone, Debug, PartialEq)]
pub struct StatusRun {
    pub from: usize,
    pub to: usize,
    pub status: String,
}

/// Merges segments `(from, to, status)` (trajectory order) into runs: a segment that starts right after the
/// previous one and has its status extends it.
pub fn status_runs(spans: &[(usize, usize, String)]) -> Vec<StatusRun> {
    let mut out: Vec<StatusRun> = Vec::new();
    for (a, b, s) in spans {
        match out.last_mut() {
            Some(last) if last.status == *s && last.to + 1 == *a => last.to = *b,
            _ => out.push(StatusRun {
                from: *a,
                to: *b,
                status: s.clone(),
            }),
        }
    }
    out
}

/// Indices (ascending) of the recordings the map keeps out of `n`: all when `n ≤ limit`, else the flagged
/// ones, `must` (run ends), the first and last, and an even stride filling `limit`.
pub fn kept_recordings(n: usize, flagged: &[bool], must: &[usize], limit: usize) -> Vec<usize> {
    if n <= limit {
        return (0..n).collect();
    }
    let mut keep = vec![false; n];
    for (i, &f) in flagged.iter().enumerate().take(n) {
        keep[i] |= f;
    }
    for &i in must.iter().filter(|&&i| i < n) {
        keep[i] = true;
    }
    keep[0] = true;
    keep[n - 1] = true;
    let fixed = keep.iter().filter(|&&k| k).count();
    let budget = limit.saturating_sub(fixed).max(1);
    let stride = n.div_ceil(budget).max(1);
    for i in (0..n).step_by(stride) {
        keep[i] = true;
    }
    (0..n).filter(|&i| keep[i]).collect()
}

/// Position of each kept index among the kept ones, for indices into the full trajectory: the first kept
/// index ≥ `i` (for the start of a run) or the last ≤ `i` (for its end).
pub fn kept_position(kept: &[usize], i: usize, at_or_after: bool) -> Option<usize> {
    match kept.binary_search(&i) {
        Ok(k) => Some(k),
        Err(k) if at_or_after => (k < kept.len()).then_some(k),
        Err(k) => k.checked_sub(1),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn small_campaigns_keep_everything() {
        assert_eq!(
            kept_recordings(5, &[false; 5], &[], 10),
            vec![0, 1, 2, 3, 4]
        );
    }

    #[test]
    fn large_campaigns_keep_flagged_run_ends_and_a_stride() {
        let n = 100_000;
        let mut flagged = vec![false; n];
        for i in (777..n).step_by(997) {
            flagged[i] = true;
        }
        let kept = kept_recordings(n, &flagged, &[12_345, 54_321], 1000);
        assert!(kept.windows(2).all(|w| w[0] < w[1]));
        for i in (0..n).filter(|&i| flagged[i]) {
            assert!(kept.binary_search(&i).is_ok());
        }
        for i in [0, n - 1, 12_345, 54_321] {
            assert!(kept.binary_search(&i).is_ok());
        }
        assert!(kept.len() <= 1000 + 100 + 4, "{}", kept.len());
        assert!(kept.len() >= 900, "{}", kept.len());
    }

    #[test]
    fn runs_merge_adjacent_segments_of_one_status() {
        let spans = vec![
            (0, 9, "pass".to_string()),
            (10, 19, "pass".to_string()),
            (20, 29, "fail".to_string()),
            (35, 39, "fail".to_string()),
        ];
        let runs = status_runs(&spans);
        assert_eq!(runs.len(), 3);
        assert_eq!((runs[0].from, runs[0].to), (0, 19));
        assert_eq!((runs[2].from, runs[2].to), (35, 39));
    }

    #[test]
    fn positions_among_kept() {
        let kept = [0, 10, 20];
        assert_eq!(kept_position(&kept, 10, true), Some(1));
        assert_eq!(kept_position(&kept, 11, true), Some(2));
        assert_eq!(kept_position(&kept, 11, false), Some(1));
        assert_eq!(kept_position(&kept, 21, true), None);
    }
}
