//! Which tie points located in the orthophoto are kept: the refinement's peak criterion relaxed where the
//! orthophoto's geometry corroborates the location. An orthophoto and the north-up ortho differ by a
//! translation only, so every correctly located tie point of one recording has the same correction (observed −
//! predicted) up to a fraction of a pixel, while a wrong peak falls anywhere in the ± `search_margin_px` search
//! window. A template partly hidden in the orthophoto (a tree crown over the road, a car parked in the
//! aerial epoch) correlates weaker than `min_peak` at its correct place; such a weak peak is kept when it lies
//! within `corroboration_px` of the correction most located tie points agree on and at least
//! `min_corroborating` tie points (weak or strong) agree there. A chance peak meets one given pixel disc of
//! radius r in a (2m + 1)² window with probability ≈ πr²/(2m + 1)² (0.5 % for r = 1, m = 12), so agreeing weak
//! peaks are not chance. Strong peaks (≥ `min_peak`) keep the refinement's own shift-consistency check.

use crate::estimators::median_consensus::median_consensus;
use crate::nadir::AerialMatch;

/// The correction (observed − predicted) of `m` in working pixels (`scale` full pixels per working pixel).
fn correction(m: &AerialMatch, scale: f64) -> [f64; 2] {
    [
        (m.observation.u_px - m.predicted_u_px) / scale,
        (m.observation.v_px - m.predicted_v_px) / scale,
    ]
}

/// What [`corroborated`] kept and dropped.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Corroboration {
    pub kept: Vec<AerialMatch>,
    /// Weak peaks (below `min_peak`) kept because their correction agrees with the others'.
    pub weak_kept: usize,
    /// Weak peaks dropped: away from the agreed correction, or too few agreeing.
    pub weak_dropped: usize,
}

/// The matches to keep among `matches` (one recording, one orthophoto): every one with a peak ≥ `min_peak`,
/// and those with a weaker peak whose correction lies within `radius_px` (working pixels; `scale` full pixels
/// each) of the median correction of all matches, when at least `min_agreeing` matches lie there. The order of
/// `matches` is kept.
pub fn corroborated(
    matches: Vec<AerialMatch>,
    min_peak: f64,
    radius_px: f64,
    min_agreeing: usize,
    scale: f64,
) -> Corroboration {
    let n_weak = matches
        .iter()
        .filter(|m| !(m.observation.score >= min_peak))
        .count();
    let corrections: Vec<[f64; 2]> = matches.iter().map(|m| correction(m, scale)).collect();
    let agreeing = median_consensus(&corrections, radius_px)
        .map(|c| c.inliers)
        .filter(|inliers| inliers.iter().filter(|&&i| i).count() >= min_agreeing.max(1));
    let mut out = Corroboration::default();
    for (k, m) in matches.into_iter().enumerate() {
        let strong = m.observation.score >= min_peak;
        let agrees = agreeing.as_ref().is_some_and(|a| a[k]);
        if strong || agrees {
            out.weak_kept += usize::from(!strong);
            out.kept.push(m);
        }
    }
    out.weak_dropped = n_weak - out.weak_kept;
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::campaign::AerialKind;
    use crate::correspondence::AerialObservation;

    fn located(id: &str, shift: (f64, f64), peak: f64) -> AerialMatch {
        AerialMatch {
            tie_point_id: id.into(),
            observation: AerialObservation {
                image_id: "ortho".into(),
                kind: AerialKind::Nadir,
                u_px: 500.0 + shift.0,
                v_px: 700.0 + shift.1,
                score: peak,
                sigma_px: None,
            },
            predicted_u_px: 500.0,
            predicted_v_px: 700.0,
            level: 0,
        }
    }

    fn ids(c: &Corroboration) -> Vec<&str> {
        c.kept.iter().map(|m| m.tie_point_id.as_str()).collect()
    }

    #[test]
    fn weak_peaks_at_the_agreed_correction_are_kept_and_stray_ones_dropped() {
        let m = vec![
            located("weak_a", (2.1, -0.4), 0.55),
            located("strong", (2.3, -0.5), 0.9),
            located("weak_b", (1.8, -0.2), 0.62),
            located("stray", (-7.0, 5.0), 0.58),
            located("weak_c", (2.4, -0.6), 0.51),
        ];
        let c = corroborated(m, 0.75, 1.0, 3, 1.0);
        assert_eq!(ids(&c), ["weak_a", "strong", "weak_b", "weak_c"]);
        assert_eq!((c.weak_kept, c.weak_dropped), (3, 1));
    }

    #[test]
    fn weak_peaks_without_enough_agreement_are_dropped_strong_ones_kept() {
        let m = vec![
            located("weak_a", (2.0, 0.0), 0.6),
            located("strong", (9.0, 3.0), 0.8),
            located("weak_b", (-4.0, 6.0), 0.6),
        ];
        let c = corroborated(m, 0.75, 1.0, 3, 1.0);
        assert_eq!(ids(&c), ["strong"]);
        assert_eq!((c.weak_kept, c.weak_dropped), (0, 2));
    }

    #[test]
    fn the_radius_is_in_working_pixels() {
        // At pyramid level 1 (2 full pixels per working pixel) 1.2 full pixels from the median are 0.6 working
        // pixels: all three agree; at level 0 only the median one does, too few.
        let m = vec![
            located("a", (0.0, 0.0), 0.6),
            located("b", (2.4, 0.0), 0.6),
            located("c", (1.2, 0.0), 0.6),
        ];
        assert_eq!(corroborated(m.clone(), 0.75, 1.0, 3, 2.0).kept.len(), 3);
        assert!(corroborated(m, 0.75, 1.0, 3, 1.0).kept.is_empty());
    }
}
