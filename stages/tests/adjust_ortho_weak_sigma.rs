//! Known-answer test of weak orthophoto control weighted by its σ measured against the strong control of the
//! same recordings (`[adjust] weak_control_sigma_estimated`): on a synthetic block whose weak control points
//! are all displaced alike by a known amount, the measured σ is that displacement's, and a stretch of
//! recordings controlled only by such weak points is carried by the tie points and the strong control around
//! it instead of following its weak control.

mod common_adjust;

use common_adjust::{runs_without_and_with, weak_prior_campaign};
use skytie_stages::adjustment::synthetic_campaign::SyntheticCampaign;
use skytie_stages::correspondence::{HeightSource, MapControl};

/// The displacement of every weak control point (north), metres.
const WEAK_OFFSET_M: f64 = 0.20;

/// Marks control point `k` as an orthophoto peak with correlation `score`, moved north by `offset_m`.
fn as_orthophoto(c: &mut SyntheticCampaign, k: usize, score: f64, offset_m: f64) {
    let cp = &mut c.control[k];
    cp.map = Some(MapControl {
        orthophoto: "ortho.tif".to_string(),
        u_px: 0.0,
        v_px: 0.0,
        score,
        height: HeightSource::Dtm,
    });
    cp.aerial.clear();
    let p = cp.point_world.as_mut().expect("triangulated");
    p[1] += offset_m;
}

#[test]
fn weak_control_displaced_alike_is_weighted_by_its_measured_sigma() {
    // The recorded poses share one offset and no random part, so every correction is exact and each sample
    // is the weak points' displacement alone.
    let mut c = weak_prior_campaign(30, 0.0, 0.0, 11);
    // Recordings 10–17 are controlled only by weak peaks, all 0.20 m north of their content; elsewhere every
    // other control point is such a weak peak beside exact strong ones (the samples of the estimate).
    let stretch = 10..=17;
    let mut weak_in_stretch = 0;
    let mut elsewhere = 0;
    for k in 0..c.control.len() {
        let recs = c.control_observed_from(k);
        if recs.iter().any(|r| stretch.contains(r)) {
            if recs.iter().all(|r| stretch.contains(r)) {
                as_orthophoto(&mut c, k, 0.6, WEAK_OFFSET_M);
                weak_in_stretch += 1;
            } else {
                // Points reaching out of the stretch are left out: the stretch has weak control only.
                c.control[k].point_world = None;
            }
        } else if k % 2 == 0 {
            as_orthophoto(&mut c, k, 0.6, WEAK_OFFSET_M);
            elsewhere += 1;
        } else {
            as_orthophoto(&mut c, k, 0.9, 0.0);
        }
    }
    c.control.retain(|cp| cp.point_world.is_some());
    assert!(
        weak_in_stretch >= 4 && elsewhere >= 5,
        "{weak_in_stretch} {elsewhere}"
    );
    let (plain, weighted) = runs_without_and_with(&c.adjust_inputs(), |config| {
        config.weak_control_sigma_estimated = true
    });
    let estimate = weighted.build.weak_control_sigma.expect("estimated");
    // Every sample is the 0.20 m displacement (the strong points and the triangulation exact to millimetres):
    // σ = 0.20 / √2 per axis.
    assert!(estimate.samples >= 5, "{estimate:?}");
    let sigma = estimate.sigma_m.expect("enough samples");
    assert!(
        (sigma - WEAK_OFFSET_M / 2f64.sqrt()).abs() < 0.01,
        "{sigma}"
    );
    assert!(plain.build.weak_control_sigma.is_none());
    let (before, after) = (
        c.horizontal_errors_m(&plain),
        c.horizontal_errors_m(&weighted),
    );
    let rms = |e: &[f64]| (e.iter().map(|v| v * v).sum::<f64>() / e.len() as f64).sqrt();
    let (b, a) = (rms(&before[10..=17]), rms(&after[10..=17]));
    println!("recordings 10–17: RMS error {b:.3} m with the stated σ, {a:.3} m with the measured σ ({sigma:.3} m)");
    // With the stated σ the stretch follows its weak control almost all the way.
    assert!(b > 0.6 * WEAK_OFFSET_M, "{before:?}");
    // Weighted by the measured σ, the tie points and the strong control around it carry it back.
    assert!(a < 0.5 * b, "{after:?}");
}
