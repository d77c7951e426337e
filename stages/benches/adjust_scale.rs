//! City-scale benchmark of the adjustment on image-free street-network blocks
//! ([`skytie_stages::adjustment::synthetic_streets`]): N recordings (first argument, default 10⁴) on a grid of
//! streets driven in both directions, 20 panorama observations and 0.375 control points per recording,
//! relative constraints, recorded positions off by a slowly varying GNSS bias. Prints the generation and
//! adjustment times, LM iterations, the peak resident memory (VmHWM) and the RMS horizontal error before and
//! after. `--structure` also prints the size of the reduced camera matrix and of its sparse factor.
//! Run through `benches/adjust_scale.sh` for the 10⁴ / 10⁵ / 10⁶ table.
//! `--write-positions=FILE` writes the adjusted positions and their a-priori σ (one line per recording, full
//! precision); `--compare-positions=FILE` prints the largest difference to such a file in millimetres (to
//! check that a change of the solver leaves the result unchanged). `--relative-release=T` adjusts with the
//! relative release at χ² threshold T (the shipped `default.toml` uses 9.21), which adds a solve without the
//! relative constraints and its covariance before the adjustment proper.

#[path = "peer_support/mod.rs"]
mod peer_support;

use peer_support::{peak_rss_mib, timed};
use skytie_stages::adjustment::layout::ReducedStructure;
use skytie_stages::adjustment::prepared::{Prepared, Rejected};
use skytie_stages::adjustment::residuals::State;
use skytie_stages::adjustment::synthetic_streets::StreetBlockSpec;
use skytie_stages::adjustment::{adjust, AdjustOptions, Block};

fn rms_xy(
    positions: impl Iterator<Item = nalgebra::Vector3<f64>>,
    truth: &[nalgebra::Vector3<f64>],
) -> f64 {
    let (sum, n) = positions.zip(truth).fold((0.0, 0usize), |(s, n), (p, t)| {
        (s + (p - t).xy().norm_squared(), n + 1)
    });
    (sum / n.max(1) as f64).sqrt()
}

fn structure(block: &Block, options: &AdjustOptions) -> ReducedStructure {
    let state = State::initial(block).unwrap();
    Prepared::new(block, options, &state, &Rejected::none(block))
        .unwrap()
        .structure
}

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let n: usize = args
        .iter()
        .find(|a| !a.starts_with("--"))
        .and_then(|a| a.parse().ok())
        .unwrap_or(10_000);
    let crossing_points = args
        .iter()
        .find_map(|a| a.strip_prefix("--crossing-points="))
        .and_then(|v| v.parse().ok())
        .unwrap_or(StreetBlockSpec::default().crossing_points);
    let spec = StreetBlockSpec {
        recordings: n,
        crossing_points,
        seed: 42,
        ..StreetBlockSpec::default()
    };
    let (t_gen, synth) = timed(|| spec.generate());
    let b = &synth.block;
    let options = AdjustOptions {
        relative_release_threshold: args
            .iter()
            .find_map(|a| a.strip_prefix("--relative-release="))
            .and_then(|v| v.parse().ok()),
        ..AdjustOptions::default()
    };
    let before = rms_xy(
        b.recordings.iter().map(|r| r.camera.center_world),
        &synth.true_centers_world,
    );
    if args.iter().any(|a| a == "--structure-only") {
        print_structure(b, &options);
        return;
    }
    let (t_adjust, adj) = timed(|| adjust(b, &options).expect("adjustment"));
    let after = rms_xy(
        adj.recordings.iter().map(|r| r.position_world),
        &synth.true_centers_world,
    );
    let sigma_mean = adj
        .recordings
        .iter()
        .map(|r| r.sigma_a_priori_m.xy().norm())
        .sum::<f64>()
        / adj.recordings.len() as f64;
    println!(
        "adjust_scale: {n} recordings, {} points ({} at crossings), {} pano obs, {} control, {} relative ({} released); \
         generate {t_gen:.2} s; adjust {t_adjust:.2} s ({} iterations, {:?}); peak RSS {:.0} MiB; \
         RMS horizontal error {before:.3} m -> {after:.4} m; mean a-priori sigma_xy {sigma_mean:.4} m",
        b.points_initial_world.len(),
        synth.crossing_points,
        b.pano_observations.len(),
        b.control_points.len(),
        b.relative_constraints.len(),
        adj.released_relative,
        adj.iterations,
        adj.termination,
        peak_rss_mib(),
    );
    if let Some(path) = args
        .iter()
        .find_map(|a| a.strip_prefix("--write-positions="))
    {
        std::fs::write(path, positions_text(&adj)).expect("write the positions file");
    }
    if let Some(path) = args
        .iter()
        .find_map(|a| a.strip_prefix("--compare-positions="))
    {
        let text = std::fs::read_to_string(path).expect("read the positions file");
        compare_positions(&text, &adj);
    }
    if args.iter().any(|a| a == "--structure") {
        drop(adj);
        print_structure(b, &options);
    }
}

fn print_structure(b: &Block, options: &AdjustOptions) {
    let s = structure(b, options);
    println!(
        "structure: reduced matrix {} blocks (lower), factor {} blocks (lower, incl. diagonal); fill ratio {:.2}",
        s.rows.len(),
        s.symbolic.lower_blocks() + s.symbolic.dim(),
        (s.symbolic.lower_blocks() + s.symbolic.dim()) as f64 / s.rows.len() as f64
    );
    let lens: Vec<usize> = (0..s.symbolic.dim())
        .map(|j| s.symbolic.column(j).len())
        .collect();
    let updates: usize = lens.iter().map(|l| l * (l + 1) / 2).sum();
    println!(
        "factor: longest column {} blocks, {updates} block updates per factorisation",
        lens.iter().max().unwrap_or(&0)
    );
}

/// One line per recording: x y z σx σy σz (world, metres), shortest round-trip formatting.
fn positions_text(adj: &skytie_stages::adjustment::Adjustment) -> String {
    adj.recordings
        .iter()
        .map(|r| {
            let (p, s) = (r.position_world, r.sigma_a_priori_m);
            format!("{} {} {} {} {} {}\n", p.x, p.y, p.z, s.x, s.y, s.z)
        })
        .collect()
}

/// Prints the largest position and σ difference (mm) between `text` (from [`positions_text`]) and `adj`.
fn compare_positions(text: &str, adj: &skytie_stages::adjustment::Adjustment) {
    let rows: Vec<Vec<f64>> = text
        .lines()
        .map(|l| {
            l.split_whitespace()
                .map(|v| v.parse().expect("a number"))
                .collect()
        })
        .collect();
    assert_eq!(
        rows.len(),
        adj.recordings.len(),
        "positions file of another block"
    );
    let (mut dp, mut ds) = (0.0f64, 0.0f64);
    for (row, r) in rows.iter().zip(&adj.recordings) {
        for k in 0..3 {
            dp = dp.max((row[k] - r.position_world[k]).abs());
            ds = ds.max((row[3 + k] - r.sigma_a_priori_m[k]).abs());
        }
    }
    println!(
        "compared with the positions file: max position difference {:.3e} mm, max sigma difference {:.3e} mm",
        dp * 1e3,
        ds * 1e3
    );
}
