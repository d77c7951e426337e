//! Generation of a whole synthetic campaign folder: plan (scenes, true trajectory, deterioration, aerial
//! flight plans, check points), render every image, write the campaign format plus `truth/`, and install the
//! folder atomically (written to a temporary sibling, then renamed).
//!
//! Deterministic: same options ⇒ byte-identical folder whatever the thread count (all randomness is hashed
//! from (seed, item); images are rendered row-parallel with ordered collects; files are written in a fixed
//! order). Timings are returned in [`SynthSummary`], never written into the folder.

use super::aerial_plan::{plan_nadir, plan_oblique};
use super::control::{plan_control, ControlParams, ControlSet};
use super::deteriorate::{Deterioration, DeteriorationModel};
use super::output::{render_factor, write_aerial_image, write_jpeg, AerialFormat};
use super::postprocess::{apply_look, EpochLook};
use super::preset::{Preset, PresetParams};
use super::render::{primary_rays, render_frame, render_panorama_with_vehicle};
use super::render_store::RenderStore;
use super::rng::hash_str;
use super::scene::{Epoch, Scene};
use super::scene_truth::{build_scenes, SceneTruth, SCENE_TRUTH_FILE};
use super::trajectory::{sample_route, true_recordings};
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

/// The stage's identity in cache keys; bump the version whenever its output for the same inputs and parameters
/// changes.
pub const STAGE: StageId = StageId {
    name: "synth",
    version: "1",
};

/// What to generate.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct SynthOptions {
    pub preset: Preset,
    pub seed: u64,
    pub deterioration: Deterioration,
    /// Override the nadir flying height above ground, m (the GSD is kept, so the focal length follows).
    pub nadir_altitude_m: Option<f64>,
    /// Override the oblique flying height above ground, m (GSD kept).
    pub oblique_altitude_m: Option<f64>,
    /// Override the panorama width (even; height = width / 2).
    pub panorama_width_px: Option<u32>,
    /// Override the maximum number of panoramas per route.
    pub max_recordings_per_route: Option<usize>,
    /// Sensor sizes and image files.
    #[serde(default)]
    pub sizes: SizeOptions,
}

/// Overrides of the preset's sensor sizes and image files.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct SizeOptions {
    /// Nadir camera width × height, px; the footprint is kept (the GSD scales with the width).
    pub nadir_px: Option<(u32, u32)>,
    /// Oblique camera width × height, px; the footprint and the distortion coefficients are kept.
    pub oblique_px: Option<(u32, u32)>,
    /// File format of the aerial frames.
    pub aerial_format: Option<AerialFormat>,
    /// Render at most this wide and upsample (`Some(0)`: render at the camera's size).
    pub render_max_width_px: Option<u32>,
    /// Write the campaign at the size it is rendered at (cameras divided by the render factors): the
    /// demo-size twin of a real-size preset, with the same scene, trajectory, flight plans and content.
    pub at_render_size: bool,
}

impl SizeOptions {
    /// `p` with these overrides applied.
    fn apply(&self, p: &mut PresetParams) -> Result<(), SynthError> {
        let bad = |option: &str, message: String| SynthError::InvalidOption {
            option: option.into(),
            message,
        };
        let size_ok = |(w, h): (u32, u32)| w >= 16 && h >= 16 && w <= 1 << 20 && h <= 1 << 20;
        if let Some((w, h)) = self.nadir_px {
            if !size_ok((w, h)) {
                return Err(bad(
                    "nadir_px",
                    format!("{w} × {h}; give sides in [16, 1048576]"),
                ));
            }
            p.nadir.gsd_m *= f64::from(p.nadir.width_px) / f64::from(w);
            (p.nadir.width_px, p.nadir.height_px) = (w, h);
        }
        if let Some((w, h)) = self.oblique_px {
            if !size_ok((w, h)) {
                return Err(bad(
                    "oblique_px",
                    format!("{w} × {h}; give sides in [16, 1048576]"),
                ));
            }
            let f = f64::from(w) / f64::from(p.oblique.width_px);
            p.oblique.gsd_center_m /= f;
            p.oblique.corner_distortion_px *= f;
            (p.oblique.width_px, p.oblique.height_px) = (w, h);
        }
        if let Some(format) = self.aerial_format {
            format.check().map_err(|m| bad("aerial_format", m))?;
            p.aerial_format = format;
        }
        if let Some(cap) = self.render_max_width_px {
            p.render_max_width_px = (cap > 0).then_some(cap);
        }
        if self.at_render_size {
            at_render_size(p);
        }
        Ok(())
    }
}

/// The preset at the size its images are rendered at: every camera divided by its render factor, GSDs and
/// pixel-sized noise and distortion scaled to match, nothing upsampled.
fn at_render_size(p: &mut PresetParams) {
    let cap = p.render_max_width_px;
    let k = f64::from(render_factor(p.nadir.width_px, p.nadir.height_px, cap));
    p.nadir.width_px = (f64::from(p.nadir.width_px) / k) as u32;
    p.nadir.height_px = (f64::from(p.nadir.height_px) / k) as u32;
    p.nadir.gsd_m *= k;
    let k = f64::from(render_factor(p.oblique.width_px, p.oblique.height_px, cap));
    p.oblique.width_px = (f64::from(p.oblique.width_px) / k) as u32;
    p.oblique.height_px = (f64::from(p.oblique.height_px) / k) as u32;
    p.oblique.gsd_center_m *= k;
    p.oblique.corner_distortion_px /= k;
    let k = render_factor(p.panorama_width_px, p.panorama_height_px(), cap);
    p.panorama_width_px /= k;
    p.observation_sigma_px /= f64::from(k);
    p.render_max_width_px = None;
}

impl SynthOptions {
    /// Preset defaults with the thesis deterioration (3.5.1.2).
    pub fn new(preset: Preset, seed: u64) -> Self {
        Self {
            preset,
            seed,
            deterioration: Deterioration::Thesis,
            nadir_altitude_m: None,
            oblique_altitude_m: None,
            panorama_width_px: None,
            max_recordings_per_route: None,
            sizes: SizeOptions::default(),
        }
    }

    /// What identifies the images of a generation with these options in a [`RenderStore`] (the options as
    /// JSON).
    pub fn store_identity(&self) -> Result<String, SynthError> {
        serde_json::to_string(self).map_err(|e| SynthError::InvalidOption {
            option: "options".into(),
            message: format!("cannot serialise the options ({e})"),
        })
    }

    /// The preset's parameters with this option set's overrides applied and checked.
    pub fn params(&self) -> Result<PresetParams, SynthError> {
        let mut p = self.preset.params();
        let bad = |option: &str, message: String| SynthError::InvalidOption {
            option: option.into(),
            message,
        };
        if let Some(a) = self.nadir_altitude_m {
            if !(a.is_finite() && a > 10.0) {
                return Err(bad(
                    "nadir_altitude_m",
                    format!("{a} m; give a height above ground > 10 m"),
                ));
            }
            p.nadir.altitude_m = a;
        }
        if let Some(a) = self.oblique_altitude_m {
            if !(a.is_finite() && a > 10.0) {
                return Err(bad(
                    "oblique_altitude_m",
                    format!("{a} m; give a height above ground > 10 m"),
                ));
            }
            p.oblique.altitude_m = a;
        }
        if let Some(w) = self.panorama_width_px {
            if w < 16 || w % 2 != 0 {
                return Err(bad(
                    "panorama_width_px",
                    format!("{w}; give an even width ≥ 16"),
                ));
            }
            p.panorama_width_px = w;
        }
        if let Some(n) = self.max_recordings_per_route {
            if n == 0 {
                return Err(bad("max_recordings_per_route", "0; give at least 1".into()));
            }
            p.max_recordings_per_route = n;
        }
        self.sizes.apply(&mut p)?;
        Ok(p)
    }

    /// `synth-<preset>-seed<N>`.
    pub fn campaign_name(&self) -> String {
        format!("synth-{}-seed{}", self.preset.name(), self.seed)
    }
}

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

/// One scene area with its route's plan.
pub struct AreaPlan {
    pub scene: Scene,
    /// True poses in driving order.
    pub truth: Vec<Recording>,
    /// Distance of each recording along the route, m.
    pub along_m: Vec<f64>,
    pub nadir: Vec<AerialImage>,
    pub oblique: Vec<AerialImage>,
    pub control: ControlSet,
}

/// Everything about a campaign except its pixels.
pub struct CampaignPlan {
    pub name: String,
    pub seed: u64,
    pub params: PresetParams,
    pub deterioration: DeteriorationModel,
    pub areas: Vec<AreaPlan>,
    /// Recorded (deteriorated) poses of all areas, in the order of the truth.
    pub recorded: Vec<Recording>,
    /// What `truth/scene.toml` records (how to rebuild the scenes for evaluation).
    pub scene_truth: SceneTruth,
}

impl CampaignPlan {
    /// True poses of all areas.
    pub fn truth(&self) -> Vec<Recording> {
        self.areas
            .iter()
            .flat_map(|a| a.truth.iter().cloned())
            .collect()
    }
}

/// Whether any of `recordings`' projection centres projects into the aerial frame `img`.
fn sees_any(img: &AerialImage, recordings: &[Recording]) -> bool {
    let cam = crate::geometry::FrameCamera::from_aerial(img);
    recordings.iter().any(|r| {
        cam.project_world(&nalgebra::Vector3::new(r.x, r.y, r.z))
            .is_some_and(|(u, v)| cam.contains(u, v))
    })
}

/// Plan a campaign without rendering: scenes, true and recorded trajectory, aerial flight plans, check points.
pub fn plan_campaign(options: &SynthOptions) -> Result<CampaignPlan, SynthError> {
    let params = options.params()?;
    let seed = options.seed;
    let mut areas = Vec::new();
    let scenes = build_scenes(options.preset, seed);
    let scene_truth = SceneTruth::of(options.preset, seed, &scenes);
    for (area, scene) in scenes.into_iter().enumerate() {
        let samples = sample_route(
            scene.route_world(),
            params.recording_spacing_m,
            params.max_recordings_per_route,
        );
        if samples.len() < 2 {
            return Err(SynthError::EmptyRoute {
                preset: options.preset.name().into(),
                area,
            });
        }
        let truth = true_recordings(&samples, area, &params, seed, |x, y| {
            scene.ground_height_m(x, y)
        });
        let along_m: Vec<f64> = samples.iter().map(|s| s.along_m).collect();
        let route_xy: Vec<[f64; 2]> = truth.iter().map(|r| [r.x, r.y]).collect();
        let mid = route_xy[route_xy.len() / 2];
        let ground_z_m = scene.ground_height_m(mid[0], mid[1]);
        let nadir = plan_nadir(
            &route_xy,
            ground_z_m,
            &params.nadir,
            seed,
            &format!("nadir_{area}"),
        );
        let oblique = plan_oblique(
            &route_xy,
            ground_z_m,
            &params.oblique,
            &format!("oblique_{area}"),
        );
        let control_params = ControlParams {
            spacing_m: params.checkpoint_spacing_m,
            max_route_distance_m: params.checkpoint_max_route_distance_m,
            max_observation_distance_m: params.observation_max_distance_m,
            sigma_px: params.observation_sigma_px,
            panorama_width_px: params.panorama_width_px,
            id_prefix: format!("cp_{area}"),
        };
        let control = plan_control(&scene, &truth, &along_m, &control_params, seed);
        areas.push(AreaPlan {
            scene,
            truth,
            along_m,
            nadir,
            oblique,
            control,
        });
    }
    let extension = params.aerial_format.extension();
    for a in &mut areas {
        for img in a.nadir.iter_mut().chain(a.oblique.iter_mut()) {
            img.file = format!("{}.{extension}", img.image_id);
        }
    }
    let deterioration = options.deterioration.resolve(seed);
    let mut recorded = Vec::new();
    for a in &mut areas {
        let area_recorded = deterioration.apply(&a.truth, &a.along_m, seed);
        // An aerial frame that sees none of the recorded positions is of no use to the pipeline (and
        // `skytie check` warns about it): the flight plan covers more than the route, so leave those out.
        a.nadir.retain(|img| sees_any(img, &area_recorded));
        a.oblique.retain(|img| sees_any(img, &area_recorded));
        recorded.extend(area_recorded);
    }
    Ok(CampaignPlan {
        name: options.campaign_name(),
        seed,
        params,
        deterioration,
        areas,
        recorded,
        scene_truth,
    })
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
    let img = apply_look(
        &linear,
        &EpochLook::mobile_mapping(),
        seed,
        hash_str(&rec.image_id),
    );
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
    let img = apply_look(&linear, &EpochLook::aerial(), seed, hash_str(&a.image_id));
    let path = dir.join(&a.file);
    write_aerial_image(&img, k, &path, p.aerial_format, p.jpeg_quality)?;
    Ok(primary_rays(
        camera.width_px,
        camera.height_px,
        p.aerial_spp_axis,
    ))
}

/// Write every file of the planned campaign into `root` (which must exist and be empty), taking the images an
/// interrupted generation left in `store` and keeping the new ones there; returns the primary rays traced and
/// the number of images taken from the store.
fn write_campaign(
    plan: &CampaignPlan,
    root: &Path,
    store: &RenderStore,
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
    // One image: taken from the store when an interrupted generation finished it, else rendered and kept.
    let mut image = |rel: String, render: &dyn Fn() -> Result<u64, SynthError>| {
        let path = root.join(&rel);
        if store.fetch(&rel, &path)? {
            reused += 1;
            return Ok::<(), SynthError>(());
        }
        rays += render()?;
        store.keep(&rel, &path)
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
    let path = root.join("campaign.toml");
    cw::write_campaign_toml(&path, &plan.name, "EPSG:28992").map_err(io(path))?;
    let path = root.join("mm/recordings.csv");
    cw::write_recordings_csv(&path, &plan.recorded).map_err(io(path))?;
    let path = root.join("truth/recordings.csv");
    cw::write_recordings_csv(&path, &plan.truth()).map_err(io(path))?;
    let nadir: Vec<AerialImage> = plan
        .areas
        .iter()
        .flat_map(|a| a.nadir.iter().cloned())
        .collect();
    let path = root.join("aerial/nadir/cameras.csv");
    cw::write_aerial_cameras_csv(&path, &nadir).map_err(io(path))?;
    let oblique: Vec<AerialImage> = plan
        .areas
        .iter()
        .flat_map(|a| a.oblique.iter().cloned())
        .collect();
    let path = root.join("aerial/oblique/cameras.csv");
    cw::write_aerial_cameras_csv(&path, &oblique).map_err(io(path))?;
    let checkpoints: Vec<_> = plan
        .areas
        .iter()
        .flat_map(|a| a.control.checkpoints.iter().cloned())
        .collect();
    let path = root.join("control/checkpoints.csv");
    cw::write_checkpoints_csv(&path, &checkpoints).map_err(io(path))?;
    let observations: Vec<_> = plan
        .areas
        .iter()
        .flat_map(|a| a.control.observations.iter().cloned())
        .collect();
    let path = root.join("control/observations.csv");
    cw::write_observations_csv(&path, &observations).map_err(io(path))?;
    let readme = plan
        .deterioration
        .readme(&plan.name, plan.seed, plan.recorded.len());
    let path = root.join("truth/README.md");
    crate::fsutil::atomic_write(&path, readme.as_bytes()).map_err(io(path))?;
    let path = root.join(SCENE_TRUTH_FILE);
    crate::fsutil::atomic_write(&path, plan.scene_truth.to_toml().as_bytes()).map_err(io(path))?;
    Ok((rays, reused))
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
/// synthetic campaign; any other existing folder is refused). Written into a temporary sibling first, then
/// renamed, so `out` is never half-written. Finished images are kept in the render store
/// `.<out name>.render-store` beside `out` until the campaign is installed, so an interrupted generation
/// resumes ([`RenderStore`]).
pub fn generate(options: &SynthOptions, out: &Path) -> Result<SynthSummary, SynthError> {
    let name = out
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_else(|| "campaign".into());
    let store = out.with_file_name(format!(".{name}.render-store"));
    generate_resumable(options, out, &store).map(|(summary, _)| summary)
}

/// [`generate`] with the render store at `store_dir`; also returns how many images were taken from the store
/// (rendered by an interrupted generation with the same options) instead of being rendered.
pub fn generate_resumable(
    options: &SynthOptions,
    out: &Path,
    store_dir: &Path,
) -> Result<(SynthSummary, usize), SynthError> {
    let start = Instant::now();
    if out.exists() && !replaceable(out) {
        return Err(SynthError::OutputExists {
            path: out.display().to_string(),
        });
    }
    let plan = plan_campaign(options)?;
    if let Some(parent) = out.parent().filter(|p| !p.as_os_str().is_empty()) {
        std::fs::create_dir_all(parent).map_err(|e| SynthError::io(parent, e))?;
    }
    let store = RenderStore::open(store_dir, &options.store_identity()?)?;
    let tmp = sibling(out, "tmp");
    std::fs::create_dir_all(&tmp).map_err(|e| SynthError::io(&tmp, e))?;
    let render_start = Instant::now();
    let written = write_campaign(&plan, &tmp, &store);
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
        name: plan.name.clone(),
        recordings: plan.recorded.len(),
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

/// Generate preset `preset` (`tiny`, `demo`, `paper`) with seed `seed` and the thesis deterioration.
pub fn generate_preset(preset: &str, seed: u64, out: &Path) -> Result<SynthSummary, SynthError> {
    generate(&SynthOptions::new(Preset::from_name(preset)?, seed), out)
}
