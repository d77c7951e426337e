//! Benchmark of the bundle adjustment core: a synthetic block of N recordings (default 1000; first argument)
//! with 0.5 px pixel noise, 0.8 m + 0.1 m deteriorated poses; prints the time, iterations and accuracy, and
//! writes the problem (local frame, whitened) with the final cost to `$TMPDIR/adjust_bench_problem.json`
//! (or the second argument) for the peer `benches/peers/adjust_scipy.py`.

#[path = "peer_support/mod.rs"]
mod peer_support;

use nalgebra::Vector3;
use peer_support::timed;
use skytie_stages::adjustment::prepared::{Prepared, Rejected};
use skytie_stages::adjustment::residuals::State;
use skytie_stages::adjustment::{adjust, AdjustOptions, SyntheticBlockSpec};

fn main() {
    let args: Vec<String> = std::env::args()
        .skip(1)
        .filter(|a| !a.starts_with("--"))
        .collect();
    let n: usize = args.first().and_then(|a| a.parse().ok()).unwrap_or(1000);
    let out = args.get(1).cloned().unwrap_or_else(|| {
        let p = std::env::temp_dir().join("adjust_bench_problem.json");
        p.to_string_lossy().into_owned()
    });
    let spec = SyntheticBlockSpec {
        recordings: n,
        control_points: n * 15 / 40,
        pixel_noise_px: 0.5,
        sigma_px: 0.5,
        seed: 42,
        ..SyntheticBlockSpec::default()
    };
    let (t_gen, synth) = timed(|| spec.generate());
    let b = &synth.block;
    let options = AdjustOptions::default();
    let (t_solve, adj) = timed(|| adjust(b, &options).expect("adjustment"));
    let max_err = adj
        .recordings
        .iter()
        .zip(&synth.true_centers_world)
        .map(|(r, t)| (r.position_world - t).norm())
        .fold(0.0, f64::max);
    println!(
        "adjust bench: {n} recordings, {} points, {} pano obs, {} control; generate {t_gen:.3} s; adjust {t_solve:.3} s \
         ({} iterations, {:?}, final cost {:.10e}, σ̂0² {:.4}); max position error {max_err:.4} m",
        b.points_initial_world.len(),
        b.pano_observations.len(),
        b.control_points.len(),
        adj.iterations,
        adj.termination,
        adj.final_cost,
        adj.variance_factor.unwrap_or(f64::NAN)
    );
    // Export the same problem for the scipy peer.
    let state = State::initial(b).unwrap();
    let prep = Prepared::new(b, &options, &state, &Rejected::none(b)).unwrap();
    let v3 = |v: &Vector3<f64>| serde_json::json!([v.x, v.y, v.z]);
    let json = serde_json::json!({
        "final_cost_rust": adj.final_cost,
        "time_rust_s": t_solve,
        "centers_local": state.centers_local.iter().map(v3).collect::<Vec<_>>(),
        "rotations0": prep.rotations0.iter().map(|m| (0..3).map(|i| (0..3).map(|j| m[(i, j)]).collect::<Vec<_>>()).collect::<Vec<_>>()).collect::<Vec<_>>(),
        "prior_inv_sigma": b.recordings.iter().map(|r| [1.0 / r.prior_sigma_xy_m.unwrap(), 1.0 / r.prior_sigma_z_m.unwrap()]).collect::<Vec<_>>(),
        "points_local": state.points_local.iter().map(v3).collect::<Vec<_>>(),
        "pano": prep.pano.iter().map(|o| serde_json::json!([o.recording, o.point, o.observed_rad.0, o.observed_rad.1, o.whitening * o.weight_factor])).collect::<Vec<_>>(),
        "control": prep.control.iter().map(|c| serde_json::json!({"point": c.point, "position": v3(&c.position_local),
            "whitening": (0..3).map(|i| (0..3).map(|j| c.whitening[(i, j)]).collect::<Vec<_>>()).collect::<Vec<_>>()})).collect::<Vec<_>>(),
    });
    match std::fs::write(&out, serde_json::to_vec(&json).unwrap()) {
        Ok(()) => println!("problem written to {out}"),
        Err(e) => eprintln!("could not write {out}: {e}"),
    }
}
