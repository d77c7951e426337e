//! `synth`: the synthetic campaign generator as a cached node (`campaign = "synth:<preset>"` in a workflow).
//!
//! The node writes the whole campaign folder into its own cache folder (`<cache>/dirs/<key>/campaign`), so a
//! second run — or any workflow naming the same preset, seed and options — reuses it. Finished images are kept
//! in the node's partial folder (`<cache>/dirs/.partial-<key>`) until the campaign is complete, so an interrupted
//! generation resumes (`skytie_stages::synth::render_store`). The output records every file's size; a cached
//! folder whose files went missing or changed size is regenerated.

use crate::dag::{NodeCtx, Stage, StageError};
use serde::{Deserialize, Serialize};
use skytie_stages::params::Violation;
use skytie_stages::synth::output::{aerial_format_from, parse_size_px};
use skytie_stages::synth::{
    generate_resumable, Deterioration, Preset, SynthError, SynthOptions, SynthSummary,
};
use std::path::{Path, PathBuf};

skytie_stages::params! {
    /// Parameters of the `[synth]` workflow table (preset and seed come from `campaign = "synth:<preset>"` and
    /// `seed`).
    pub struct SynthParams {
        /// Preset: `tiny`, `demo`, `paper` or `realsize`.
        preset: String = "demo".into();
        /// Seed of the generator.
        seed: u64 = 1;
        /// Recorded-position deterioration: `thesis` (0.80 m systematic + N(0, 0.10 m), thesis 3.5.1.2) or
        /// `none`.
        deterioration: String = "thesis".into();
        /// Override of the panorama width (even; 0 = the preset's).
        panorama_width_px: u32 = 0, unit "px";
        /// Override of the number of recordings per route (0 = the preset's).
        max_recordings_per_route: usize = 0;
        /// Override of the nadir camera size, `"WIDTHxHEIGHT"` in pixels (empty = the preset's; the footprint is
        /// kept).
        nadir_size: String = String::new();
        /// Override of the oblique camera size, `"WIDTHxHEIGHT"` in pixels (empty = the preset's; the footprint is
        /// kept).
        oblique_size: String = String::new();
        /// Aerial file format: `jpeg` or `tiff` (tiled; empty = the preset's).
        aerial_format: String = String::new();
        /// Compression of tiled TIFF aerial frames: `jpeg`, `lzw`, `deflate` or `none`.
        tiff_compression: String = "jpeg".into();
        /// Bits per sample of tiled TIFF aerial frames: 8 or 16 (16-bit frames hold 12-bit data).
        aerial_bits: u8 = 8, min 8, max 16;
        /// Render images at most this wide and upsample them to the camera's size (0 = the preset's choice).
        render_max_width_px: u32 = 0, unit "px";
        /// Write the campaign at its render size (the demo-size twin of a real-size preset).
        at_render_size: bool = false;
    }
    check(p, v) {
        if let Err(violation) = p.options() {
            v.push(violation);
        }
    }
}

impl SynthParams {
    /// The generator options these parameters stand for; the error names the parameter at fault.
    pub fn options(&self) -> Result<SynthOptions, Violation> {
        let preset =
            Preset::from_name(&self.preset).map_err(|e| Violation::new("preset", e.to_string()))?;
        let mut o = SynthOptions::new(preset, self.seed);
        o.deterioration = match self.deterioration.as_str() {
            "thesis" => Deterioration::Thesis,
            "none" => Deterioration::None,
            other => {
                return Err(Violation::new(
                    "deterioration",
                    format!("unknown deterioration '{other}': use \"thesis\" or \"none\""),
                ))
            }
        };
        if self.panorama_width_px != 0 {
            o.panorama_width_px = Some(self.panorama_width_px);
        }
        if self.max_recordings_per_route != 0 {
            o.max_recordings_per_route = Some(self.max_recordings_per_route);
        }
        if !self.nadir_size.is_empty() {
            o.sizes.nadir_px =
                Some(parse_size_px(&self.nadir_size).map_err(|m| Violation::new("nadir_size", m))?);
        }
        if !self.oblique_size.is_empty() {
            o.sizes.oblique_px = Some(
                parse_size_px(&self.oblique_size).map_err(|m| Violation::new("oblique_size", m))?,
            );
        }
        if !self.aerial_format.is_empty() {
            let quality = preset.params().jpeg_quality;
            o.sizes.aerial_format = Some(
                aerial_format_from(
                    &self.aerial_format,
                    &self.tiff_compression,
                    self.aerial_bits,
                    quality,
                )
                .map_err(|m| Violation::new("aerial_format", m))?,
            );
        }
        if self.render_max_width_px != 0 {
            o.sizes.render_max_width_px = Some(self.render_max_width_px);
        }
        o.sizes.at_render_size = self.at_render_size;
        o.params().map_err(|e| match e {
            SynthError::InvalidOption { option, message } => Violation::new(option, message),
            other => Violation::new("preset", other.to_string()),
        })?;
        Ok(o)
    }
}

/// A generated campaign folder and what it holds.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct GeneratedCampaign {
    /// Absolute path of the campaign folder inside the cache.
    pub dir: String,
    /// (path relative to `dir`, size in bytes) of every file, sorted.
    pub files: Vec<(String, u64)>,
    pub summary: SynthSummary,
}
crate::serde_artifact!(GeneratedCampaign);

impl GeneratedCampaign {
    pub fn path(&self) -> PathBuf {
        PathBuf::from(&self.dir)
    }
}

/// Every file below `root` as (relative path with '/', size), sorted.
pub fn list_files(root: &Path) -> std::io::Result<Vec<(String, u64)>> {
    fn walk(root: &Path, dir: &Path, out: &mut Vec<(String, u64)>) -> std::io::Result<()> {
        for entry in std::fs::read_dir(dir)? {
            let entry = entry?;
            let path = entry.path();
            let meta = entry.metadata()?;
            if meta.is_dir() {
                walk(root, &path, out)?;
            } else {
                let rel = path.strip_prefix(root).unwrap_or(&path);
                let rel = rel
                    .components()
                    .map(|c| c.as_os_str().to_string_lossy())
                    .collect::<Vec<_>>()
                    .join("/");
                out.push((rel, meta.len()));
            }
        }
        Ok(())
    }
    let mut out = Vec::new();
    walk(root, root, &mut out)?;
    out.sort();
    Ok(out)
}

/// The generator node.
pub struct SynthCampaign;

impl Stage for SynthCampaign {
    const NAME: &'static str = skytie_stages::synth::generate::STAGE.name;
    const VERSION: &'static str = skytie_stages::synth::generate::STAGE.version;
    type Params = SynthParams;
    type Output = GeneratedCampaign;
    type Inputs = ();

    fn run(&self, p: &SynthParams, _: (), ctx: &NodeCtx) -> Result<GeneratedCampaign, StageError> {
        let options = p
            .options()
            .map_err(|v| StageError::new(format!("synth parameter {v}")))?;
        let tmp = ctx.output_dir_tmp()?;
        let (summary, reused) =
            generate_resumable(&options, &tmp.join("campaign"), &ctx.partial_dir()).map_err(|e| {
                StageError::new(format!(
                    "synthetic campaign generation failed: {e} (the images rendered so far are kept in {}; \
                     the next run resumes from them)",
                    ctx.partial_dir().display()
                ))
            })?;
        if reused > 0 {
            eprintln!(
                "synth: resumed an interrupted generation: {reused} images taken from {}",
                ctx.partial_dir().display()
            );
        }
        let files = list_files(&tmp.join("campaign"))?;
        let dir = ctx.output_dir().join("campaign");
        Ok(GeneratedCampaign {
            dir: dir.to_string_lossy().into_owned(),
            files,
            summary,
        })
    }

    fn cached_output_ok(&self, out: &GeneratedCampaign, _ctx: &NodeCtx) -> bool {
        match list_files(&out.path()) {
            Ok(files) => files == out.files,
            Err(_) => false,
        }
    }
}
