//! What the adjustment made of each aerial control point — used, rejected as a gross error, left out by its
//! checks — so that every export says it the same way (`status` in `correspondences.csv` and
//! `ground_control/control_points.csv`) and only used control is handed to other software.

use crate::adjustment::{AdjustmentRun, PointKind};
use std::collections::HashMap;

/// What the adjustment made of a control point (the word in the `status` columns).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ControlStatus {
    /// The adjustment used it as aerial control.
    Used,
    /// The adjustment's gross-error test rejected one of its aerial observations (or its ground control).
    Rejected,
    /// The adjustment left it out (its checks of the control), or did not include it.
    LeftOut,
    /// No adjustment to judge it (written without a run).
    NotAdjusted,
}

impl ControlStatus {
    /// The word written to the `status` columns.
    pub fn as_str(self) -> &'static str {
        match self {
            Self::Used => "used",
            Self::Rejected => "rejected",
            Self::LeftOut => "left_out",
            Self::NotAdjusted => "not_adjusted",
        }
    }

    /// The status a `status` column's word names (`None` for any other word).
    pub fn parse(word: &str) -> Option<Self> {
        [Self::Used, Self::Rejected, Self::LeftOut, Self::NotAdjusted]
            .into_iter()
            .find(|s| s.as_str() == word)
    }

    /// Whether the point may be handed to other software as ground control.
    pub fn delivered(self) -> bool {
        matches!(self, Self::Used | Self::NotAdjusted)
    }
}

/// The status of every control point of one adjustment, looked up by tie point id.
pub struct ControlStatuses<'a> {
    by_id: Option<HashMap<&'a str, ControlStatus>>,
}

impl<'a> ControlStatuses<'a> {
    /// The statuses under `run` (every point `NotAdjusted` without one).
    pub fn of(run: Option<&'a AdjustmentRun>) -> Self {
        let by_id = run.map(|run| {
            run.points
                .iter()
                .map(|p| {
                    let status = if p.point.kind == PointKind::Tie {
                        ControlStatus::LeftOut
                    } else if p.control_rejected {
                        ControlStatus::Rejected
                    } else {
                        ControlStatus::Used
                    };
                    (p.point.id.as_str(), status)
                })
                .collect()
        });
        Self { by_id }
    }

    /// The status of the control point of tie point `tie_point_id` (`LeftOut` when the adjustment does not
    /// know it).
    pub fn get(&self, tie_point_id: &str) -> ControlStatus {
        match &self.by_id {
            None => ControlStatus::NotAdjusted,
            Some(m) => m
                .get(tie_point_id)
                .copied()
                .unwrap_or(ControlStatus::LeftOut),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::adjustment::AdjustConfig;
    use crate::correction::fixture;

    /// A determined point `id` of `kind`, its control rejected or not.
    fn point(id: &str, kind: PointKind, control_rejected: bool) -> crate::adjustment::RunPoint {
        let mut p = fixture::point(kind, &[0]);
        p.point.id = id.into();
        p.control_rejected = control_rejected;
        p
    }

    #[test]
    fn each_point_gets_what_the_adjustment_made_of_it() {
        let run = fixture::run(
            AdjustConfig::default(),
            Vec::new(),
            vec![
                point("used", PointKind::Control, false),
                point("single", PointKind::SingleAerial, false),
                point("rejected", PointKind::Control, true),
                point("left out", PointKind::Tie, false),
            ],
        );
        let s = ControlStatuses::of(Some(&run));
        for status in [
            ControlStatus::Used,
            ControlStatus::Rejected,
            ControlStatus::LeftOut,
            ControlStatus::NotAdjusted,
        ] {
            assert_eq!(ControlStatus::parse(status.as_str()), Some(status));
        }
        assert_eq!(ControlStatus::parse(""), None);
        assert_eq!(s.get("used"), ControlStatus::Used);
        assert_eq!(s.get("single"), ControlStatus::Used);
        assert_eq!(s.get("rejected"), ControlStatus::Rejected);
        assert_eq!(s.get("left out"), ControlStatus::LeftOut);
        assert_eq!(s.get("unknown"), ControlStatus::LeftOut);
        assert_eq!(
            ControlStatuses::of(None).get("used"),
            ControlStatus::NotAdjusted
        );
        let delivered: Vec<bool> = [
            ControlStatus::Used,
            ControlStatus::Rejected,
            ControlStatus::LeftOut,
            ControlStatus::NotAdjusted,
        ]
        .map(ControlStatus::delivered)
        .to_vec();
        assert_eq!(delivered, [true, false, false, true]);
    }
}
