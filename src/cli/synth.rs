//! `skytie synth --preset P --seed N [--profile thesis+outage…] --out DIR`: write a synthetic campaign
//! (campaign format + `truth/`) with the named error profile.

use clap::Args;
use skytie_stages::synth::orthophoto::OrthophotoOptions;
use skytie_stages::synth::output::{aerial_format_from, parse_size_px};
use skytie_stages::synth::profile::COMPONENTS;
use skytie_stages::synth::sizes::SizeOptions;
use skytie_stages::synth::{generate, Preset, Profile, SynthOptions};
use std::path::PathBuf;

/// Arguments of `skytie synth`.
#[derive(Args, Debug)]
pub struct SynthArgs {
    /// Preset: tiny (CI smoke), demo (README default), paper (four areas, full resolution), realsize (real
    /// sensor sizes on a short street), street (320 panoramas along 1.6 km at tiny's image sizes, for sharded
    /// runs).
    #[arg(long, default_value = "demo")]
    pub preset: String,
    /// Seed of the scene, noise and errors (same seed ⇒ byte-identical folder).
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Output folder (created; an existing synthetic campaign there is replaced, anything else is refused).
    #[arg(long, required_unless_present = "list_profiles")]
    pub out: Option<PathBuf>,
    /// Print the error-profile components and what each does, then exit.
    #[arg(long)]
    pub list_profiles: bool,
    /// Error profile: components joined by '+' (thesis, outage, ins, vertical, aerial, lens, lens-unknown,
    /// epoch), or none, or all; `--list-profiles` prints what each does.
    #[arg(long, default_value = "thesis")]
    pub profile: String,
    /// Rayon threads (default: all cores). The output does not depend on it.
    #[arg(long)]
    pub threads: Option<usize>,
    /// Nadir camera size WIDTHxHEIGHT, px (the footprint is kept: the GSD scales with the width).
    #[arg(long, value_name = "WxH")]
    pub nadir_size: Option<String>,
    /// Oblique camera size WIDTHxHEIGHT, px (footprint and distortion coefficients kept).
    #[arg(long, value_name = "WxH")]
    pub oblique_size: Option<String>,
    /// Panorama width, px (even; height = width / 2).
    #[arg(long)]
    pub panorama_width: Option<u32>,
    /// Aerial frames as jpeg or tiff (tiled, 256-px tiles; BigTIFF when larger than 3 GiB).
    #[arg(long)]
    pub aerial_format: Option<String>,
    /// Compression of tiled TIFF frames: jpeg, lzw, deflate or none.
    #[arg(long, default_value = "jpeg")]
    pub tiff_compression: String,
    /// Bits per sample of tiled TIFF frames: 8 or 16 (16-bit frames hold 12-bit data).
    #[arg(long, default_value_t = 8)]
    pub bits: u8,
    /// Render images at most this wide and upsample them to the camera's size (0: render at full size).
    #[arg(long)]
    pub render_max_width: Option<u32>,
    /// Write the campaign at the size it is rendered at (a real-size preset's demo-size twin).
    #[arg(long)]
    pub at_render_size: bool,
    /// Also write an orthophoto of this GSD, m, and a 1 m DTM (GeoTIFFs under orthophoto/, declared in
    /// campaign.toml).
    #[arg(long, value_name = "M")]
    pub orthophoto_gsd: Option<f64>,
    /// RMS planimetric error of the orthophoto, m: a known smooth warp (truth/orthophoto.toml).
    #[arg(
        long,
        value_name = "M",
        default_value_t = 0.0,
        requires = "orthophoto_gsd"
    )]
    pub orthophoto_error: f64,
    /// Leave the nadir frames out: the orthophoto is the campaign's only nadir source.
    #[arg(long, requires = "orthophoto_gsd")]
    pub without_nadir: bool,
}

/// The size options of the command line.
fn size_options(a: &SynthArgs, preset: Preset) -> Result<SizeOptions, String> {
    let mut s = SizeOptions {
        nadir_px: a.nadir_size.as_deref().map(parse_size_px).transpose()?,
        oblique_px: a.oblique_size.as_deref().map(parse_size_px).transpose()?,
        render_max_width_px: a.render_max_width,
        at_render_size: a.at_render_size,
        ..SizeOptions::default()
    };
    if let Some(f) = &a.aerial_format {
        let quality = preset.params().jpeg_quality;
        s.aerial_format = Some(aerial_format_from(f, &a.tiff_compression, a.bits, quality)?);
    }
    Ok(s)
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
    let Some(out) = a.out.as_ref().filter(|_| !a.list_profiles) else {
        for (_, name, what) in COMPONENTS {
            println!("{name:14} {what}");
        }
        return 0;
    };
    let mut options = SynthOptions::new(preset, a.seed);
    options.panorama_width_px = a.panorama_width;
    options.sizes = match size_options(a, preset) {
        Ok(s) => s,
        Err(e) => {
            eprintln!("error: {e}");
            return 2;
        }
    };
    options.profile = match Profile::parse(&a.profile) {
        Ok(p) => p,
        Err(e) => {
            eprintln!("error: --profile: {e}");
            return 2;
        }
    };
    options.orthophoto = a.orthophoto_gsd.map(|gsd_m| OrthophotoOptions {
        gsd_m,
        error_m: a.orthophoto_error,
        without_nadir: a.without_nadir,
    });
    let run = || generate(&options, out);
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
                out.display()
            );
            0
        }
        Err(e) => {
            eprintln!("error: {e}");
            1
        }
    }
}
