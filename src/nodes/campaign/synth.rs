//! The synthetic campaign generator as two cached nodes (`campaign = "synth:<preset>"` in a workflow):
//! `render` renders the error-free campaign of a preset and seed (the images depend only on the render
//! identity: preset, seed, size overrides and the `lens`/`epoch` profile components), and `synth` applies the
//! error profile of the `[synth]` table to it, writing new tables and hard-linking the images. So a workflow or
//! an evaluation that runs one scene under several table-only profiles renders it once.
//!
//! Each node writes its folder into its own cache folder (`<cache>/dirs/<key>/campaign`), so a second run — or
//! any workflow naming the same options — reuses it. Finished images are kept in the render node's partial
//! folder (`<cache>/dirs/.partial-<key>`) until the rendering is complete, so an interrupted generation resumes
//! (`skytie_stages::synth::render_store`). The outputs record every file's size; a cached folder whose files
//! went missing or changed size is regenerated.

use crate::dag::{Handle, InputsOf, NodeCtx, RunResult, Stage, StageError};
use serde::{Deserialize, Serialize};
use skytie_stages::params::Violation;
use skytie_stages::synth::generate::{RenderIdentity, RENDER_STAGE, STAGE};
use skytie_stages::synth::orthophoto::OrthophotoOptions;
use skytie_stages::synth::output::{aerial_format_from, parse_size_px};
use skytie_stages::synth::profile::{
    AerialEoParams, ComponentParams, EpochParams, InsParams, LensParams, OutageParams,
    ThesisParams, VerticalParams,
};
use skytie_stages::synth::{
    apply_profile, render_campaign, Preset, Profile, SynthError, SynthOptions, SynthSummary,
};
use std::path::{Path, PathBuf};

skytie_stages::params! {
    /// Parameters of the `[synth]` workflow table (preset and seed come from `campaign = "synth:<preset>"` and
    /// `seed`); the component tables `[synth.outage]`, `[synth.ins]`, … override a component's defaults.
    pub struct SynthParams {
        /// Preset: `tiny`, `demo`, `paper` or `realsize`.
        preset: String = "demo".into();
        /// Seed of the generator.
        seed: u64 = 1;
        /// Error profile: components joined by `+` (`thesis`, `outage`, `ins`, `vertical`, `aerial`, `lens`,
        /// `lens-unknown`, `epoch`), or `none`, or `all`; see docs/error-profiles.md.
        profile: String = "thesis".into();
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
        /// Also write an orthophoto of this GSD and a 1 m DTM (GeoTIFFs under `orthophoto/`, declared in
        /// `campaign.toml`), as `skytie synth --orthophoto-gsd`; 0 = no orthophoto.
        orthophoto_gsd_m: f64 = 0.0, unit "m", min 0.0, max 1.0;
        /// RMS planimetric error (2-D) of the orthophoto: a known smooth warp, as `--orthophoto-error`; needs
        /// `orthophoto_gsd_m`.
        orthophoto_error_m: f64 = 0.0, unit "m", min 0.0, max 5.0;
        /// Leave the nadir frames out (the orthophoto is the only nadir source), as `--without-nadir`; needs
        /// `orthophoto_gsd_m`.
        without_nadir: bool = false;
        /// `[synth.thesis]`: constant offset + noise (thesis 3.5.1.2).
        thesis: ThesisParams = ThesisParams::default(), section;
        /// `[synth.outage]`: GNSS outage drift.
        outage: OutageParams = OutageParams::default(), section;
        /// `[synth.ins]`: inertial heading, pitch and roll errors.
        ins: InsParams = InsParams::default(), section;
        /// `[synth.vertical]`: height and camera-height errors.
        vertical: VerticalParams = VerticalParams::default(), section;
        /// `[synth.aerial]`: aerial orientation errors.
        aerial: AerialEoParams = AerialEoParams::default(), section;
        /// `[synth.lens]`: nadir lens distortion.
        lens: LensParams = LensParams::default(), section;
        /// `[synth.epoch]`: aerial vs mobile-mapping epoch differences.
        epoch: EpochParams = EpochParams::default(), section;
    }
    check(p, v) {
        // The sections' own violations are already listed; the options add the preset's and the profile's.
        if v.is_empty() {
            if let Err(violation) = p.options() {
                v.push(violation);
            }
        }
    }
}

impl SynthParams {
    /// The generator options these parameters stand for; the error names the parameter at fault.
    pub fn options(&self) -> Result<SynthOptions, Violation> {
        let preset =
            Preset::from_name(&self.preset).map_err(|e| Violation::new("preset", e.to_string()))?;
        let mut o = SynthOptions::new(preset, self.seed);
        let mut profile =
            Profile::parse(&self.profile).map_err(|e| Violation::new("profile", e.to_string()))?;
        profile.params = ComponentParams {
            thesis: self.thesis.clone(),
            outage: self.outage.clone(),
            ins: self.ins.clone(),
            vertical: self.vertical.clone(),
            aerial: self.aerial.clone(),
            lens: self.lens.clone(),
            epoch: self.epoch.clone(),
        };
        o.profile = profile;
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
        o.orthophoto = self.orthophoto()?;
        o.params().map_err(|e| match e {
            SynthError::InvalidOption { option, message } => Violation::new(option, message),
            other => Violation::new("preset", other.to_string()),
        })?;
        Ok(o)
    }
}

impl SynthParams {
    /// The orthophoto options of `orthophoto_gsd_m`, `orthophoto_error_m` and `without_nadir`: none when the
    /// GSD is 0, an error naming the key when the other two are set without it.
    fn orthophoto(&self) -> Result<Option<OrthophotoOptions>, Violation> {
        if self.orthophoto_gsd_m == 0.0 {
            let needs_gsd = |key: &str| {
                Violation::new(
                    key,
                    "set without an orthophoto; give orthophoto_gsd_m (e.g. 0.1) or remove it"
                        .to_string(),
                )
            };
            if self.orthophoto_error_m != 0.0 {
                return Err(needs_gsd("orthophoto_error_m"));
            }
            if self.without_nadir {
                return Err(needs_gsd("without_nadir"));
            }
            return Ok(None);
        }
        Ok(Some(OrthophotoOptions {
            gsd_m: self.orthophoto_gsd_m,
            error_m: self.orthophoto_error_m,
            without_nadir: self.without_nadir,
        }))
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

    /// The campaign as written into `tmp` (the node's temporary folder) and recorded at `ctx`'s final folder.
    fn record(tmp: &Path, ctx: &NodeCtx, summary: SynthSummary) -> Result<Self, StageError> {
        Ok(GeneratedCampaign {
            dir: ctx
                .output_dir()
                .join("campaign")
                .to_string_lossy()
                .into_owned(),
            files: list_files(&tmp.join("campaign"))?,
            summary,
        })
    }

    /// Whether the folder still holds exactly the recorded files (by size).
    fn intact(&self) -> bool {
        list_files(&self.path()).is_ok_and(|files| files == self.files)
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

/// The render node: the error-free campaign of a render identity.
pub struct RenderCampaign;

impl Stage for RenderCampaign {
    crate::nodes::stage_types!(RENDER_STAGE, RenderIdentity => GeneratedCampaign, inputs: ());

    fn run(&self, identity: &RenderIdentity, _: InputsOf<Self>, ctx: &NodeCtx) -> RunResult<Self> {
        let options = SynthOptions::rendering(identity);
        let tmp = ctx.output_dir_tmp()?;
        let report = |done: u64, total: u64| ctx.report_steps(done, total);
        let (summary, reused) = render_campaign(&options, &tmp.join("campaign"), &ctx.partial_dir(), &report)
            .map_err(|e| {
                StageError::new(format!(
                    "synthetic campaign rendering failed: {e} (the images rendered so far are kept in {}; \
                     the next run resumes from them)",
                    ctx.partial_dir().display()
                ))
            })?;
        if reused > 0 {
            eprintln!(
                "render: resumed an interrupted rendering: {reused} images taken from {}",
                ctx.partial_dir().display()
            );
        }
        GeneratedCampaign::record(&tmp, ctx, summary)
    }

    fn cached_output_ok(&self, out: &GeneratedCampaign, _ctx: &NodeCtx) -> bool {
        out.intact()
    }
}

/// The generator node: the rendered campaign with the `[synth]` error profile applied.
pub struct SynthCampaign;

impl Stage for SynthCampaign {
    crate::nodes::stage_types!(STAGE, SynthParams => GeneratedCampaign, inputs: Handle<GeneratedCampaign>);

    fn run(&self, p: &SynthParams, rendered: InputsOf<Self>, ctx: &NodeCtx) -> RunResult<Self> {
        let options = p
            .options()
            .map_err(|v| StageError::new(format!("synth parameter {v}")))?;
        let tmp = ctx.output_dir_tmp()?;
        apply_profile(&rendered.path(), &options, &tmp.join("campaign")).map_err(|e| {
            StageError::new(format!(
                "applying the error profile '{}' failed: {e}",
                options.profile.name()
            ))
        })?;
        let summary = SynthSummary {
            name: options.campaign_name(),
            ..rendered.summary.clone()
        };
        GeneratedCampaign::record(&tmp, ctx, summary)
    }

    fn cached_output_ok(&self, out: &GeneratedCampaign, _ctx: &NodeCtx) -> bool {
        out.intact()
    }
}
