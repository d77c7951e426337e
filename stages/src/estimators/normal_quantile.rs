//! Quantiles of the standard normal and of the χ² distribution with two degrees of freedom, for tests whose
//! thresholds follow from a significance level instead of being picked.
//!
//! The normal quantile is Acklam's rational approximation (Acklam 2003; relative error below 1.2·10⁻⁹ over the
//! whole open interval), far below anything a significance level is known to; χ²₂ has the closed form
//! `−2·ln(1 − p)`.

/// The `p` quantile of the standard normal distribution, `Φ⁻¹(p)`; `None` outside the open interval (0, 1).
pub fn normal_quantile(p: f64) -> Option<f64> {
    if !(p > 0.0 && p < 1.0) {
        return None;
    }
    const A: [f64; 6] = [
        -3.969_683_028_665_376e1,
        2.209_460_984_245_205e2,
        -2.759_285_104_469_687e2,
        1.383_577_518_672_69e2,
        -3.066_479_806_614_716e1,
        2.506_628_277_459_239,
    ];
    const B: [f64; 5] = [
        -5.447_609_879_822_406e1,
        1.615_858_368_580_409e2,
        -1.556_989_798_598_866e2,
        6.680_131_188_771_972e1,
        -1.328_068_155_288_572e1,
    ];
    const C: [f64; 6] = [
        -7.784_894_002_430_293e-3,
        -3.223_964_580_411_365e-1,
        -2.400_758_277_161_838,
        -2.549_732_539_343_734,
        4.374_664_141_464_968,
        2.938_163_982_698_783,
    ];
    const D: [f64; 4] = [
        7.784_695_709_041_462e-3,
        3.224_671_290_700_398e-1,
        2.445_134_137_142_996,
        3.754_408_661_907_416,
    ];
    const P_LOW: f64 = 0.024_25;
    let tail = |q: f64| {
        (((((C[0] * q + C[1]) * q + C[2]) * q + C[3]) * q + C[4]) * q + C[5])
            / ((((D[0] * q + D[1]) * q + D[2]) * q + D[3]) * q + 1.0)
    };
    Some(if p < P_LOW {
        tail((-2.0 * p.ln()).sqrt())
    } else if p > 1.0 - P_LOW {
        -tail((-2.0 * (1.0 - p).ln()).sqrt())
    } else {
        let q = p - 0.5;
        let r = q * q;
        (((((A[0] * r + A[1]) * r + A[2]) * r + A[3]) * r + A[4]) * r + A[5]) * q
            / (((((B[0] * r + B[1]) * r + B[2]) * r + B[3]) * r + B[4]) * r + 1.0)
    })
}

/// The `p` quantile of the χ² distribution with two degrees of freedom; `None` outside [0, 1).
pub fn chi2_2_quantile(p: f64) -> Option<f64> {
    (0.0..1.0).contains(&p).then(|| -2.0 * (1.0 - p).ln())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn normal_quantiles_match_the_tables() {
        // Values from standard tables (to the digits given there).
        for (p, z) in [
            (0.5, 0.0),
            (0.841_344_746, 1.0),
            (0.975, 1.959_963_985),
            (0.995, 2.575_829_304),
            (0.999, 3.090_232_306),
            (0.999_968_328_758_166_9, 4.0),
            (0.01, -2.326_347_874),
            (1e-10, -6.361_340_902),
        ] {
            let got = normal_quantile(p).unwrap();
            assert!((got - z).abs() < 1e-7, "Φ⁻¹({p}) = {got}, want {z}");
        }
    }

    #[test]
    fn normal_quantile_is_odd_about_one_half() {
        for p in [0.001, 0.02, 0.1, 0.3, 0.49] {
            let lo = normal_quantile(p).unwrap();
            let hi = normal_quantile(1.0 - p).unwrap();
            assert!((lo + hi).abs() < 1e-8, "p = {p}: {lo} vs {hi}");
        }
    }

    #[test]
    fn quantiles_refuse_probabilities_outside_their_domain() {
        for p in [0.0, 1.0, -0.1, 1.5, f64::NAN] {
            assert_eq!(normal_quantile(p), None, "{p}");
        }
        assert_eq!(chi2_2_quantile(1.0), None);
        assert_eq!(chi2_2_quantile(f64::NAN), None);
        assert_eq!(chi2_2_quantile(0.0), Some(0.0));
    }

    #[test]
    fn chi2_with_two_degrees_of_freedom_matches_the_tables() {
        for (p, x) in [
            (0.95, 5.991_464_547),
            (0.99, 9.210_340_372),
            (0.5, 1.386_294_361),
        ] {
            let got = chi2_2_quantile(p).unwrap();
            assert!((got - x).abs() < 1e-8, "χ²₂({p}) = {got}, want {x}");
        }
    }
}
