//! What carries each recording's correction: its own aerial control, control on both sides of it along the
//! trajectory, control on one side only, or none at all. The adjustment moves every recording, but only a
//! recording linked to aerial control — directly, or through tie points and relative constraints to a
//! recording that has some — is corrected; the others keep their recorded position (thesis 3.5.3: the
//! recorded positions enter as weak priors). Users downstream must know which is which, so every export
//! carries this classification in words.
//!
//! Links are the ones the adjustment used: a tie or control point observed from several recordings, and,
//! with `relative_constraints`, consecutive recordings at most `relative_max_gap_m` apart (the same rule as
//! the block builder).

use crate::adjustment::{AdjustmentRun, PointKind};
use serde::{Deserialize, Serialize};

/// How a recording's correction is supported, strongest first.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash, Serialize, Deserialize)]
pub enum Support {
    /// The recording observes aerial control points itself.
    Controlled,
    /// No own control, but linked to controlled recordings before and after it along the trajectory.
    Bridged,
    /// Linked to controlled recordings on one side only (before the first or after the last one).
    Extrapolated,
    /// Not linked to any aerial control: the recorded position is kept.
    Uncorrected,
}

impl Support {
    /// The word used in CSV files and the GeoPackage.
    pub fn label(&self) -> &'static str {
        match self {
            Support::Controlled => "controlled",
            Support::Bridged => "bridged",
            Support::Extrapolated => "extrapolated",
            Support::Uncorrected => "uncorrected",
        }
    }

    /// A sentence for people (report, warnings).
    pub fn explanation(&self) -> &'static str {
        match self {
            Support::Controlled => "corrected by aerial control points it observes itself",
            Support::Bridged => {
                "no control point of its own; corrected through its neighbours, which have control on both sides"
            }
            Support::Extrapolated => {
                "no control point of its own; corrected through neighbours with control on one side only"
            }
            Support::Uncorrected => {
                "not corrected: no aerial control point is linked to its stretch of trajectory"
            }
        }
    }

    /// Parses [`Support::label`].
    pub fn from_label(s: &str) -> Option<Self> {
        [
            Support::Controlled,
            Support::Bridged,
            Support::Extrapolated,
            Support::Uncorrected,
        ]
        .into_iter()
        .find(|k| k.label() == s)
    }

    /// The weaker of two supports (what an interpolation between them can claim).
    pub fn weaker(self, other: Self) -> Self {
        self.max(other)
    }
}

/// One recording's support and the evidence for it.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct RecordingSupport {
    pub support: Support,
    /// Aerial control points the recording observes and the adjustment kept (a point whose control the
    /// gross-error test rejected is only a tie point: it does not count).
    pub control_points: usize,
    /// Index of the linked group of recordings (recordings of one group move together).
    pub group: usize,
}

/// Does a point of this kind tie the block to the aerial images in this run?
fn is_control(kind: PointKind, run: &AdjustmentRun) -> bool {
    match kind {
        PointKind::Control => true,
        PointKind::SingleAerial => run.config.aerial_observations,
        PointKind::Tie => false,
    }
}

fn find(parent: &mut [usize], mut i: usize) -> usize {
    while parent[i] != i {
        parent[i] = parent[parent[i]];
        i = parent[i];
    }
    i
}

fn union(parent: &mut [usize], a: usize, b: usize) {
    let (ra, rb) = (find(parent, a), find(parent, b));
    if ra != rb {
        parent[ra.max(rb)] = ra.min(rb);
    }
}

/// Groups of recordings the adjustment linked (union of tie/control points and relative constraints);
/// returns the group index of every recording, groups numbered by their first recording.
pub fn linked_groups(run: &AdjustmentRun) -> Vec<usize> {
    let n = run.recordings.len();
    let mut parent: Vec<usize> = (0..n).collect();
    for p in run.points.iter().filter(|p| p.determined) {
        let mut recs = p.point.pano.iter().map(|o| o.0).filter(|&r| r < n);
        if let Some(first) = recs.next() {
            for r in recs {
                union(&mut parent, first, r);
            }
        }
    }
    if run.config.relative_constraints {
        for i in 1..n {
            let (a, b) = (
                run.recordings[i - 1].recorded_world,
                run.recordings[i].recorded_world,
            );
            if (a[0] - b[0]).hypot(a[1] - b[1]) <= run.config.relative_max_gap_m {
                union(&mut parent, i - 1, i);
            }
        }
    }
    let mut number = vec![usize::MAX; n];
    let mut next = 0;
    (0..n)
        .map(|i| {
            let root = find(&mut parent, i);
            if number[root] == usize::MAX {
                number[root] = next;
                next += 1;
            }
            number[root]
        })
        .collect()
}

/// The support of every recording of `run` (run order, i.e. time order).
pub fn recording_support(run: &AdjustmentRun) -> Vec<RecordingSupport> {
    let n = run.recordings.len();
    let mut control = vec![0usize; n];
    for p in run
        .points
        .iter()
        .filter(|p| p.determined && !p.control_rejected && is_control(p.point.kind, run))
    {
        for &(r, _, _) in &p.point.pano {
            if r < n {
                control[r] += 1;
            }
        }
    }
    let groups = linked_groups(run);
    // Per group: first and last controlled recording (time order).
    let n_groups = groups.iter().copied().max().map_or(0, |g| g + 1);
    let mut span: Vec<Option<(usize, usize)>> = vec![None; n_groups];
    for i in (0..n).filter(|&i| control[i] > 0) {
        let s = &mut span[groups[i]];
        *s = Some(s.map_or((i, i), |(a, _)| (a, i)));
    }
    (0..n)
        .map(|i| {
            let support = if control[i] > 0 {
                Support::Controlled
            } else {
                match span[groups[i]] {
                    None => Support::Uncorrected,
                    Some((first, last)) if first < i && i < last => Support::Bridged,
                    Some(_) => Support::Extrapolated,
                }
            };
            RecordingSupport {
                support,
                control_points: control[i],
                group: groups[i],
            }
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::adjustment::AdjustConfig;
    use crate::correction::fixture::{point, recording};

    /// Recordings 5 m apart except a 100 m gap before recording 6; control at 1 and 3.
    fn run(relative: bool) -> AdjustmentRun {
        let xs = [0.0, 5.0, 10.0, 15.0, 20.0, 25.0, 125.0, 130.0];
        crate::correction::fixture::run(
            AdjustConfig {
                relative_constraints: relative,
                ..AdjustConfig::default()
            },
            xs.iter()
                .enumerate()
                .map(|(i, &x)| recording(i, x, [0.0; 3]))
                .collect(),
            vec![
                point(PointKind::Control, &[1]),
                point(PointKind::Control, &[3]),
                point(PointKind::Tie, &[6, 7]),
                point(PointKind::SingleAerial, &[7]),
            ],
        )
    }

    #[test]
    fn classifies_by_links_and_position_along_the_trajectory() {
        let s: Vec<Support> = recording_support(&run(true))
            .iter()
            .map(|s| s.support)
            .collect();
        use Support::*;
        assert_eq!(
            s,
            [
                Extrapolated,
                Controlled,
                Bridged,
                Controlled,
                Extrapolated,
                Extrapolated,
                // Beyond the gap: linked to each other by a tie point, but the single-aerial point does not
                // count without aerial observations in the bundle.
                Uncorrected,
                Uncorrected
            ]
        );
    }

    #[test]
    fn without_relative_constraints_only_points_link() {
        let s = recording_support(&run(false));
        assert_eq!(s[0].support, Support::Uncorrected);
        assert_eq!(s[1].support, Support::Controlled);
        assert_eq!(s[2].support, Support::Uncorrected);
        assert_eq!(s[6].group, s[7].group);
        assert_ne!(s[1].group, s[3].group);
    }

    #[test]
    fn single_aerial_points_count_with_aerial_observations() {
        let mut r = run(true);
        r.config.aerial_observations = true;
        let s = recording_support(&r);
        assert_eq!(s[7].support, Support::Controlled);
        assert_eq!(s[6].support, Support::Extrapolated);
    }

    #[test]
    fn control_the_adjustment_rejected_does_not_count() {
        let mut r = run(true);
        r.points[1].control_rejected = true;
        let s = recording_support(&r);
        assert_eq!(s[3].support, Support::Extrapolated);
        assert_eq!(s[3].control_points, 0);
        assert_eq!(s[2].support, Support::Extrapolated);
        assert_eq!(s[1].support, Support::Controlled);
    }

    #[test]
    fn labels_round_trip_and_order_by_strength() {
        for s in [
            Support::Controlled,
            Support::Bridged,
            Support::Extrapolated,
            Support::Uncorrected,
        ] {
            assert_eq!(Support::from_label(s.label()), Some(s));
        }
        assert_eq!(
            Support::Controlled.weaker(Support::Uncorrected),
            Support::Uncorrected
        );
    }
}
