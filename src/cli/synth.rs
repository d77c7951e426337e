//! `skytie synth --preset P --seed N --out DIR`: write a synthetic campaign (campaign-format.md + `truth/`).

use clap::Args;
use skytie_stages::synth::{generate, Deterioration, Preset, SynthOptions};
use std::path::PathBuf;

/// Arguments of `skytie synth`.
#[derive(Args, Debug)]
pub struct SynthArgs {
    /// Preset: tiny (CI smoke), demo (README default), paper (four areas, full resolution).
    #[arg(long, default_value = "demo")]
    pub preset: String,
    /// Seed of the scene, noise and deterioration (same seed ⇒ byte-identical folder).
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Output folder (created; an existing synthetic campaign there is replaced, anything else is refused).
    #[arg(long)]
    pub out: PathBuf,
    /// Recorded-position deterioration: thesis (0.80 m systematic + N(0, 0.10 m)) or none.
    #[arg(long, default_value = "thesis")]
    pub deterioration: String,
    /// Rayon threads (default: all cores). The output does not depend on it.
    #[arg(long)]
    pub threads: Option<usize>,
}

/// Run `skytie synth`; returns the exit code.
pub fn main(a: &SynthArgs) -> i32 {
    let preset = match Preset::from_name(&a.preset) {
        Ok(p) => p,
        Err(e) => {
            eprintln!("error: {e}");
            return 2;
        }
    };
    let mut options = SynthOptions::new(preset, a.seed);
    options.deterioration = match a.deterioration.as_str() {
        "thesis" => Deterioration::Thesis,
        "none" => Deterioration::None,
        other => {
            eprintln!("error: unknown --deterioration '{other}': use thesis or none");
            return 2;
        }
    };
    let run = || generate(&options, &a.out);
    let result = match a.threads {
        Some(n) => match rayon::ThreadPoolBuilder::new()
            .num_threads(n.max(1))
            .build()
        {
            Ok(pool) => pool.install(run),
            Err(e) => {
                eprintln!("error: cannot start {n} threads: {e}");
                return 2;
            }
        },
        None => run(),
    };
    match result {
        Ok(s) => {
            println!(
                "{}: {} recordings, {} nadir, {} oblique images, {} check points ({} observations) in {:.1} s \
                 ({:.2} M primary rays/s) -> {}",
                s.name,
                s.recordings,
                s.nadir_images,
                s.oblique_images,
                s.checkpoints,
                s.observations,
                s.seconds,
                s.rays_per_second() / 1e6,
                a.out.display()
            );
            0
        }
        Err(e) => {
            eprintln!("error: {e}");
            1
        }
    }
}
