//! Generation of a whole synthetic campaign folder in two steps: [`render_campaign`] renders the error-free
//! campaign (every image, the true tables, check points, `truth/`), then the error profile is applied to it
//! ([`super::profile::apply_profile_dir`]: new tables, the images hard-linked), so campaigns that differ only
//! in table-only profiles share one rendering. Both steps install their folder atomically (written to a
//! temporary sibling, then renamed).
//!
//! Deterministic: same options ⇒ byte-identical folder whatever the thread count (all randomness is hashed
//! from (seed, item); images are rendered row-parallel with ordered collects; files are written in a fixed
//! order). Timings are returned in [`SynthSummary`], never written into the folder.

pub use super::options::{RenderIdentity, SynthOptions};
use super::orthophoto::{self, OrthophotoOptions};
use super::output::{render_factor, write_aerial_image, write_jpeg};
pub use super::plan::{plan_campaign, AreaPlan, CampaignPlan};
use crate::crs::CoordinateFrame;

use super::postprocess::{apply_look, EpochLook};
use super::preset::{Preset, PresetParams};
use super::profile::readme::readme;
use super::profile::{apply_profile_dir, Profile};
use super::render::{primary_rays, render_frame, render_panorama_with_vehicle};
use super::render_store::RenderStore;
use super::rng::{hash_str, Stream};
use super::scene::{Epoch, Scene};
use super::scene_truth::SCENE_TRUTH_FILE;
use super::vehicle::VehicleBody;
use super::SynthError;
use crate::campaign::write as cw;
use crate::campaign::{AerialImage, Recording};
use crate::geometry::{FrameCamera, PanoramaCamera};
use crate::params::StageId;
use nalgebra::Vector3;
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};
use std::time::Instant;

/// The identity of the generator stage (the rendered campaign with an error profile applied) in cache keys;
/// bump the version whenever its output for the same inputs and parameters changes.
pub const STAGE: StageId = StageId::new("synth", "4");

/// The identity of the render stage (the error-free campaign of a [`RenderIdentity`]); bump the version
/// whenever the generator renders differently (scenes, presets, cameras, looks).
pub const RENDER_STAGE: StageId = StageId::new("render", "5");

/// What was generated and how long it took.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct SynthSummary {
    pub name: String,
    pub recordings: usize,
    pub nadir_images: usize,
    pub oblique_images: usize,
    pub checkpoints: usize,
    pub observations: usize,
    /// Primary (camera) rays traced for the images rendered by this generation (shadow rays of the shading are
    /// not counted; images taken from the render store of an interrupted generation are not either).
    pub primary_rays: u64,
    /// Wall time spent rendering (ray casting + post-processing), s.
    pub render_seconds: f64,
    /// Wall time of the whole generation, s.
    pub seconds: f64,
}

impl SynthSummary {
    /// Primary rays per second of rendering time.
    pub fn rays_per_second(&self) -> f64 {
        self.primary_rays as f64 / self.render_seconds.max(1e-9)
    }
}

/// The exposure gain of image `image_id`: exp(N(0, σ)) with σ = the preset's `exposure_log_sigma` (1 when 0).
fn exposure_gain(p: &PresetParams, seed: u64, image_id: &str) -> f32 {
    if p.exposure_log_sigma <= 0.0 {
        return 1.0;
    }
    let mut s = Stream::new(&[seed, hash_str("exposure"), hash_str(image_id)]);
    (p.exposure_log_sigma * s.normal()).exp() as f32
}

/// Render, post-process and save one panorama at its true pose; returns the primary rays traced.
fn write_panorama(
    scene: &Scene,
    rec: &Recording,
    p: &PresetParams,
    seed: u64,
    dir: &Path,
) -> Result<u64, SynthError> {
    // Rendered at the camera's size / k, upsampled by k when written.
    let k = render_factor(
        p.panorama_width_px,
        p.panorama_height_px(),
        p.render_max_width_px,
    );
    let camera = PanoramaCamera::new(
        p.panorama_width_px / k,
        p.panorama_height_px() / k,
        Vector3::new(rec.x, rec.y, rec.z),
        rec.yaw_deg,
        rec.pitch_deg,
        rec.roll_deg,
    );
    let vehicle = VehicleBody::standard(rec.heading_deg, rec.camera_height_m);
    let linear = render_panorama_with_vehicle(
        scene,
        &camera,
        Some(&vehicle),
        Epoch::MobileMapping,
        p.panorama_spp_axis,
    );
    let look = EpochLook::mobile_mapping().exposed(exposure_gain(p, seed, &rec.image_id));
    let img = apply_look(&linear, &look, seed, hash_str(&rec.image_id));
    let path = dir.join(&rec.file);
    write_jpeg(&img, k, &path, p.jpeg_quality)?;
    Ok(primary_rays(
        camera.width_px,
        camera.height_px,
        p.panorama_spp_axis,
    ))
}

/// Render, post-process and save one aerial frame; returns the primary rays traced.
fn write_aerial(
    scene: &Scene,
    a: &AerialImage,
    p: &PresetParams,
    seed: u64,
    dir: &Path,
) -> Result<u64, SynthError> {
    // Rendered at the camera's size / k (the same camera with its interior orientation divided by k),
    // upsampled by k when written.
    let k = render_factor(a.width_px, a.height_px, p.render_max_width_px);
    let mut camera = FrameCamera::from_aerial(a);
    let kf = f64::from(k);
    camera.focal_px /= kf;
    camera.cx_px /= kf;
    camera.cy_px /= kf;
    camera.width_px /= k;
    camera.height_px /= k;
    let linear = render_frame(scene, &camera, Epoch::Aerial, p.aerial_spp_axis);
    let look = EpochLook::aerial().exposed(exposure_gain(p, seed, &a.image_id));
    let img = apply_look(&linear, &look, seed, hash_str(&a.image_id));
    let path = dir.join(&a.file);
    write_aerial_image(&img, k, &path, p.aerial_format, p.jpeg_quality)?;
    Ok(primary_rays(
        camera.width_px,
        camera.height_px,
        p.aerial_spp_axis,
    ))
}

/// Write every file of the planned campaign without errors (the true tables as the recorded ones), named
/// `name`, into `root` (which must exist and be empty), taking the images an interrupted generation left in
/// `store` and keeping the new ones there; returns the primary rays traced and the number of images taken from
/// the store.
fn write_error_free(
    plan: &CampaignPlan,
    name: &str,
    root: &Path,
    store: &RenderStore,
    on_image: ImageProgress<'_>,
) -> Result<(u64, usize), SynthError> {
    let p = &plan.params;
    let io = |path: PathBuf| move |e: std::io::Error| SynthError::io(&path, e);
    let mut rays = 0u64;
    let (pano_dir, nadir_dir, oblique_dir) = (
        root.join("mm/panoramas"),
        root.join("aerial/nadir"),
        root.join("aerial/oblique"),
    );
    let mut reused = 0usize;
    let total = plan
        .areas
        .iter()
        .map(|a| a.truth.len() + a.nadir.len() + a.oblique.len())
        .sum::<usize>() as u64;
    let mut done = 0u64;
    on_image(done, total);
    // One image: taken from the store when an interrupted generation finished it, else rendered and kept.
    let mut image = |rel: String, render: &dyn Fn() -> Result<u64, SynthError>| {
        let path = root.join(&rel);
        if store.fetch(&rel, &path)? {
            reused += 1;
        } else {
            rays += render()?;
            store.keep(&rel, &path)?;
        }
        done += 1;
        on_image(done, total);
        Ok::<(), SynthError>(())
    };
    for area in &plan.areas {
        for rec in &area.truth {
            image(format!("mm/panoramas/{}", rec.file), &|| {
                write_panorama(&area.scene, rec, p, plan.seed, &pano_dir)
            })?;
        }
        for a in &area.nadir {
            image(format!("aerial/nadir/{}", a.file), &|| {
                write_aerial(&area.scene, a, p, plan.seed, &nadir_dir)
            })?;
        }
        for a in &area.oblique {
            image(format!("aerial/oblique/{}", a.file), &|| {
                write_aerial(&area.scene, a, p, plan.seed, &oblique_dir)
            })?;
        }
    }
    let truth = plan.true_tables();
    let path = root.join("campaign.toml");
    // The scene is built in a flat Cartesian world whose coordinates look like RD New: say so, or the
    // pipeline would treat them as map coordinates of a projection.
    cw::write_campaign_toml(&path, name, "EPSG:28992", CoordinateFrame::Cartesian)
        .map_err(io(path.clone()))?;
    if let Some(o) = &plan.orthophoto {
        write_orthophotos(plan, o, root, &path)?;
    }
    let write = |rel: &str, f: &dyn Fn(&Path) -> std::io::Result<()>| {
        let path = root.join(rel);
        f(&path).map_err(io(path))
    };
    for rel in ["mm/recordings.csv", "truth/recordings.csv"] {
        write(rel, &|p| cw::write_recordings_csv(p, &truth.recordings))?;
    }
    for (rel, frames) in [
        ("aerial/nadir/cameras.csv", &truth.nadir),
        ("aerial/oblique/cameras.csv", &truth.oblique),
    ] {
        write(rel, &|p| cw::write_aerial_cameras_csv(p, frames))?;
    }
    let control = plan.control();
    write("control/checkpoints.csv", &|p| {
        cw::write_checkpoints_csv(p, &control.checkpoints)
    })?;
    write("control/observations.csv", &|p| {
        cw::write_observations_csv(p, &control.observations)
    })?;
    let none = Profile::none();
    let readme = readme(name, plan.seed, &none, &none.apply(plan.seed, &truth));
    write("truth/README.md", &|p| {
        crate::fsutil::atomic_write(p, readme.as_bytes())
    })?;
    write(SCENE_TRUTH_FILE, &|p| {
        crate::fsutil::atomic_write(p, plan.scene_truth.to_toml().as_bytes())
    })?;
    Ok((rays, reused))
}

/// The orthophoto and DTM of every area, their tables in `campaign.toml` (at `toml`) and `truth/orthophoto.toml`.
fn write_orthophotos(
    plan: &CampaignPlan,
    o: &OrthophotoOptions,
    root: &Path,
    toml: &Path,
) -> Result<(), SynthError> {
    let io = |path: &Path| {
        let path = path.to_path_buf();
        move |e: std::io::Error| SynthError::io(&path, e)
    };
    let files = plan
        .areas
        .iter()
        .enumerate()
        .map(|(i, a)| orthophoto::write_area(&a.scene, &a.truth, o, plan.seed, i, root))
        .collect::<Result<Vec<_>, _>>()?;
    let text =
        std::fs::read_to_string(toml).map_err(io(toml))? + &orthophoto::campaign_tables(o, &files);
    crate::fsutil::atomic_write(toml, text.as_bytes()).map_err(io(toml))?;
    let path = root.join("truth/orthophoto.toml");
    let truth = orthophoto::truth_toml(o, plan.seed, plan.areas.len());
    crate::fsutil::atomic_write(&path, truth.as_bytes()).map_err(io(&path))
}

static TMP_COUNTER: AtomicU64 = AtomicU64::new(0);

/// A fresh sibling path of `out` with `tag` (e.g. `.name.tmp-<pid>-<n>`).
fn sibling(out: &Path, tag: &str) -> PathBuf {
    let name = out
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_else(|| "campaign".into());
    let n = TMP_COUNTER.fetch_add(1, Ordering::Relaxed);
    out.with_file_name(format!(".{name}.{tag}-{}-{n}", std::process::id()))
}

/// Whether an existing `out` may be replaced: an empty folder or a previous synthetic campaign.
fn replaceable(out: &Path) -> bool {
    if !out.is_dir() {
        return false;
    }
    let empty = std::fs::read_dir(out)
        .map(|mut d| d.next().is_none())
        .unwrap_or(false);
    empty || (out.join("campaign.toml").is_file() && out.join("truth/README.md").is_file())
}

/// Move the finished `tmp` folder to `out`, replacing a previous synthetic campaign there.
fn install(tmp: &Path, out: &Path) -> Result<(), SynthError> {
    if out.exists() {
        if !replaceable(out) {
            return Err(SynthError::OutputExists {
                path: out.display().to_string(),
            });
        }
        let old = sibling(out, "old");
        std::fs::rename(out, &old).map_err(|e| SynthError::io(out, e))?;
        if let Err(e) = std::fs::rename(tmp, out) {
            let _ = std::fs::rename(&old, out);
            return Err(SynthError::io(out, e));
        }
        std::fs::remove_dir_all(&old).map_err(|e| SynthError::io(&old, e))?;
    } else {
        std::fs::rename(tmp, out).map_err(|e| SynthError::io(out, e))?;
    }
    Ok(())
}

/// Generate the whole campaign described by `options` into the folder `out` (created, or replacing a previous
/// synthetic campaign; any other existing folder is refused): the error-free campaign is rendered into a
/// sibling folder, the profile applied from there into `out`, and the sibling removed. Every folder is written
/// into a temporary sibling first, then renamed, so `out` is never half-written. Finished images are kept in
/// the render store `.<out name>.render-store` beside `out` until the rendering is installed, so an interrupted
/// generation resumes ([`RenderStore`]).
pub fn generate(options: &SynthOptions, out: &Path) -> Result<SynthSummary, SynthError> {
    let name = out
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_else(|| "campaign".into());
    let store = out.with_file_name(format!(".{name}.render-store"));
    generate_resumable(options, out, &store).map(|(summary, _)| summary)
}

/// [`generate`] with the render store at `store_dir`; also returns how many images were taken from the store
/// (rendered by an interrupted generation with the same images) instead of being rendered.
pub fn generate_resumable(
    options: &SynthOptions,
    out: &Path,
    store_dir: &Path,
) -> Result<(SynthSummary, usize), SynthError> {
    let start = Instant::now();
    check_replaceable(out)?;
    let rendered = sibling(out, "rendered");
    let (mut summary, reused) = render_campaign(options, &rendered, store_dir, &|_, _| {})?;
    let applied = apply_profile(&rendered, options, out);
    let _ = std::fs::remove_dir_all(&rendered);
    applied?;
    summary.name = options.campaign_name();
    summary.seconds = start.elapsed().as_secs_f64();
    Ok((summary, reused))
}

/// Apply `options.profile` to the error-free campaign folder `rendered` (made by [`render_campaign`] with the
/// same options' render identity) and install the result as `out` (replacing a previous synthetic campaign).
pub fn apply_profile(
    rendered: &Path,
    options: &SynthOptions,
    out: &Path,
) -> Result<(), SynthError> {
    check_replaceable(out)?;
    let tmp = sibling(out, "tmp");
    let result = apply_profile_dir(
        rendered,
        &options.profile,
        options.seed,
        &options.campaign_name(),
        &tmp,
    )
    .and_then(|_| install(&tmp, out));
    if result.is_err() {
        let _ = std::fs::remove_dir_all(&tmp);
    }
    result
}

/// Refuse an existing `out` that is neither empty nor a synthetic campaign.
fn check_replaceable(out: &Path) -> Result<(), SynthError> {
    if out.exists() && !replaceable(out) {
        return Err(SynthError::OutputExists {
            path: out.display().to_string(),
        });
    }
    Ok(())
}

/// Called after each image of a rendering with (images done, images in all), and once with 0 before the first.
pub type ImageProgress<'a> = &'a dyn Fn(u64, u64);

/// Render the error-free campaign of `options` (its images depend only on [`SynthOptions::render_identity`];
/// the tables hold the true values, `truth/README.md` says so) into the folder `out`, created or replacing a
/// previous synthetic campaign. Finished images are kept in the render store at `store_dir` until the folder
/// is installed; `on_image` hears of each finished image. Returns the summary and how many images were taken
/// from the store.
pub fn render_campaign(
    options: &SynthOptions,
    out: &Path,
    store_dir: &Path,
    on_image: ImageProgress<'_>,
) -> Result<(SynthSummary, usize), SynthError> {
    let start = Instant::now();
    check_replaceable(out)?;
    let plan = plan_campaign(options)?;
    if let Some(parent) = out.parent().filter(|p| !p.as_os_str().is_empty()) {
        std::fs::create_dir_all(parent).map_err(|e| SynthError::io(parent, e))?;
    }
    let store = RenderStore::open(store_dir, &options.store_identity()?)?;
    let tmp = sibling(out, "tmp");
    std::fs::create_dir_all(&tmp).map_err(|e| SynthError::io(&tmp, e))?;
    let name = SynthOptions {
        profile: Profile::none(),
        ..options.clone()
    }
    .campaign_name();
    let render_start = Instant::now();
    let written = write_error_free(&plan, &name, &tmp, &store, on_image);
    let render_seconds = render_start.elapsed().as_secs_f64();
    let (rays, reused) = match written.and_then(|w| install(&tmp, out).map(|_| w)) {
        Ok(w) => w,
        Err(e) => {
            let _ = std::fs::remove_dir_all(&tmp);
            return Err(e);
        }
    };
    store.remove()?;
    let summary = SynthSummary {
        name,
        recordings: plan.recorded().len(),
        nadir_images: plan.areas.iter().map(|a| a.nadir.len()).sum(),
        oblique_images: plan.areas.iter().map(|a| a.oblique.len()).sum(),
        checkpoints: plan.areas.iter().map(|a| a.control.checkpoints.len()).sum(),
        observations: plan
            .areas
            .iter()
            .map(|a| a.control.observations.len())
            .sum(),
        primary_rays: rays,
        render_seconds,
        seconds: start.elapsed().as_secs_f64(),
    };
    Ok((summary, reused))
}

/// Generate preset `preset` (`tiny`, `demo`, `paper`) with seed `seed` and the thesis' error profile.
pub fn generate_preset(preset: &str, seed: u64, out: &Path) -> Result<SynthSummary, SynthError> {
    generate(&SynthOptions::new(Preset::from_name(preset)?, seed), out)
}
