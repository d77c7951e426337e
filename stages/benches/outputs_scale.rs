//! City-scale benchmark of a run's searches and output writers on image-free synthetic results
//! ([`skytie_stages::export::synthetic_outputs`]): `outputs_scale N OUT STEP` generates N recordings with
//! their aerial images, control and check points and adjustment result, then runs one step and prints its
//! time and the process' peak resident memory (VmHWM, generation included):
//! `generate` (nothing more), `overlap` (the nadir images overlapping every recording), `oblique` (the
//! oblique candidates of every recording), `verify` (both verifications), `exports` (every export writer into
//! OUT, one time each; OUT is then an output folder for `skytie report`). `overlap-linear` and
//! `oblique-linear` run the per-image scans the indexes replace, for comparison. Run through
//! `benches/outputs_scale.sh` for the 10⁴ / 10⁵ table.

#[path = "peer_support/mod.rs"]
mod peer_support;

use peer_support::peak_rss_mib;
use skytie_stages::export::synthetic_outputs::{write_outputs, OutputsSpec};
use skytie_stages::nadir::aerial_overlap::{overlapping_nadir, NadirOverlap};
use skytie_stages::oblique::candidates::{candidate_oblique, ObliqueCandidates};
use std::path::PathBuf;
use std::time::Instant;

/// Façade search distance and height of the oblique defaults, metres.
const FACADE_M: (f64, f64) = (20.0, 15.0);
/// Overlap margin of the nadir default, metres.
const MARGIN_M: f64 = 1.5;

fn main() {
    let args: Vec<String> = std::env::args()
        .skip(1)
        .filter(|a| a != "--bench")
        .collect();
    let (Some(n), Some(out), Some(step)) = (
        args.first().and_then(|a| a.parse::<usize>().ok()),
        args.get(1).map(PathBuf::from),
        args.get(2),
    ) else {
        eprintln!("usage: outputs_scale N OUT generate|overlap|oblique|verify|exports|overlap-linear|oblique-linear");
        std::process::exit(2);
    };
    let t0 = Instant::now();
    let s = OutputsSpec {
        recordings: n,
        ..OutputsSpec::default()
    }
    .generate();
    println!(
        "generate: {n} recordings, {} nadir, {} oblique images, {} control points: {:.2} s",
        s.nadir.len(),
        s.oblique.len(),
        s.control.len(),
        t0.elapsed().as_secs_f64()
    );
    let t1 = Instant::now();
    let found: usize = match step.as_str() {
        "generate" => 0,
        "overlap" => {
            let index = NadirOverlap::new(&s.nadir, &s.recordings);
            s.recordings
                .iter()
                .map(|r| index.overlapping(r, MARGIN_M).len())
                .sum()
        }
        "overlap-linear" => s
            .recordings
            .iter()
            .map(|r| overlapping_nadir(r, &s.nadir, MARGIN_M).len())
            .sum(),
        "oblique" => {
            let index = ObliqueCandidates::new(&s.oblique, &s.recordings, FACADE_M.0, FACADE_M.1);
            s.recordings.iter().map(|r| index.candidates(r).len()).sum()
        }
        "oblique-linear" => s
            .recordings
            .iter()
            .map(|r| candidate_oblique(r, &s.oblique, FACADE_M.0, FACADE_M.1).len())
            .sum(),
        "verify" => {
            let v = s.verification(false).expect("verification");
            let va = s.verification(true).expect("verification");
            v.segments.len() + va.segments.len()
        }
        "exports" => {
            let times =
                write_outputs(&s, &out.join("campaign"), &out.join("out")).expect("exports");
            for (name, secs) in &times {
                println!("  {name}: {secs:.2} s");
            }
            times.len()
        }
        other => {
            eprintln!("unknown step {other}");
            std::process::exit(2);
        }
    };
    println!(
        "{step}: {:.2} s ({found} found); peak RSS {:.0} MiB",
        t1.elapsed().as_secs_f64(),
        peak_rss_mib()
    );
}
