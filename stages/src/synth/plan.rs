//! The plan of a synthetic campaign, everything but its pixels: scenes, true trajectory, aerial flight plans,
//! check points, and the recorded tables that the error profile makes from the true ones.

use super::aerial_plan::{plan_nadir, plan_oblique};
use super::control::{plan_control, ControlParams, ControlSet};
use super::options::SynthOptions;
use super::preset::PresetParams;
use super::profile::{Applied, Tables};
use super::scene::Scene;
use super::scene_truth::{build_scenes, SceneTruth};
use super::trajectory::{sample_route, true_recordings};
use super::SynthError;
use crate::campaign::{AerialImage, Recording};

/// One scene area with its route's plan.
pub struct AreaPlan {
    pub scene: Scene,
    /// True poses in driving order.
    pub truth: Vec<Recording>,
    /// Distance of each recording along the route, m.
    pub along_m: Vec<f64>,
    /// True poses (and lens parameters) of the aerial frames.
    pub nadir: Vec<AerialImage>,
    pub oblique: Vec<AerialImage>,
    pub control: ControlSet,
}

/// Everything about a campaign except its pixels.
pub struct CampaignPlan {
    pub name: String,
    pub seed: u64,
    pub params: PresetParams,
    pub areas: Vec<AreaPlan>,
    /// The recorded tables (all areas, in the order of the truth) and how the profile made them.
    pub applied: Applied,
    /// What `truth/scene.toml` records (how to rebuild the scenes for evaluation).
    pub scene_truth: SceneTruth,
    /// The orthophoto and DTM to write, if any.
    pub orthophoto: Option<super::orthophoto::OrthophotoOptions>,
}

impl CampaignPlan {
    /// True poses of all areas.
    pub fn truth(&self) -> Vec<Recording> {
        self.areas
            .iter()
            .flat_map(|a| a.truth.iter().cloned())
            .collect()
    }

    /// The true tables of all areas (recordings, nadir and oblique frames).
    pub fn true_tables(&self) -> Tables {
        Tables {
            recordings: self.truth(),
            nadir: self.areas.iter().flat_map(|a| a.nadir.clone()).collect(),
            oblique: self.areas.iter().flat_map(|a| a.oblique.clone()).collect(),
        }
    }

    /// The check points and observations of all areas, in area order.
    pub fn control(&self) -> ControlSet {
        ControlSet {
            checkpoints: self
                .areas
                .iter()
                .flat_map(|a| a.control.checkpoints.iter().cloned())
                .collect(),
            observations: self
                .areas
                .iter()
                .flat_map(|a| a.control.observations.iter().cloned())
                .collect(),
        }
    }

    /// Recorded (erroneous) poses of all areas, in the order of the truth.
    pub fn recorded(&self) -> &[Recording] {
        &self.applied.tables.recordings
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

/// The plan of one area: true trajectory along its route, aerial flight plans, check points.
fn plan_area(
    scene: Scene,
    area: usize,
    params: &PresetParams,
    options: &SynthOptions,
) -> Result<AreaPlan, SynthError> {
    let seed = options.seed;
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
    let truth = true_recordings(&samples, area, params, seed, |x, y| {
        scene.ground_height_m(x, y)
    });
    let along_m: Vec<f64> = samples.iter().map(|s| s.along_m).collect();
    let route_xy: Vec<[f64; 2]> = truth.iter().map(|r| [r.x, r.y]).collect();
    let mid = route_xy[route_xy.len() / 2];
    let ground_z_m = scene.ground_height_m(mid[0], mid[1]);
    let mut nadir = plan_nadir(
        &route_xy,
        ground_z_m,
        &params.nadir,
        seed,
        &format!("nadir_{area}"),
    );
    let mut oblique = plan_oblique(
        &route_xy,
        ground_z_m,
        &params.oblique,
        &format!("oblique_{area}"),
    );
    // An aerial frame that sees none of the panoramas is of no use to the pipeline (and `skytie check` warns
    // about it): the flight plan covers more than the route, so leave those out.
    nadir.retain(|img| sees_any(img, &truth));
    if options.orthophoto.as_ref().is_some_and(|o| o.without_nadir) {
        nadir.clear();
    }
    oblique.retain(|img| sees_any(img, &truth));
    let extension = params.aerial_format.extension();
    for img in nadir.iter_mut().chain(oblique.iter_mut()) {
        img.file = format!("{}.{extension}", img.image_id);
    }
    let control_params = ControlParams {
        spacing_m: params.checkpoint_spacing_m,
        max_route_distance_m: params.checkpoint_max_route_distance_m,
        max_observation_distance_m: params.observation_max_distance_m,
        sigma_px: params.observation_sigma_px,
        panorama_width_px: params.panorama_width_px,
        id_prefix: format!("cp_{area}"),
    };
    let control = plan_control(&scene, &truth, &along_m, &control_params, seed);
    Ok(AreaPlan {
        scene,
        truth,
        along_m,
        nadir,
        oblique,
        control,
    })
}

/// Plan a campaign without rendering: scenes, true and recorded tables, aerial flight plans, check points.
pub fn plan_campaign(options: &SynthOptions) -> Result<CampaignPlan, SynthError> {
    let params = options.params()?;
    let seed = options.seed;
    let render = options.profile.render_options();
    let scenes = build_scenes(options.preset, seed, render.epoch.as_ref());
    let scene_truth = SceneTruth::of(options.preset, seed, render.epoch.as_ref(), &scenes);
    let areas = scenes
        .into_iter()
        .enumerate()
        .map(|(area, scene)| plan_area(scene, area, &params, options))
        .collect::<Result<Vec<_>, _>>()?;
    let mut plan = CampaignPlan {
        name: options.campaign_name(),
        seed,
        params,
        areas,
        applied: Applied {
            tables: Tables {
                recordings: Vec::new(),
                nadir: Vec::new(),
                oblique: Vec::new(),
            },
            notes: Vec::new(),
            aerial_changed: false,
        },
        scene_truth,
        orthophoto: options.orthophoto.clone(),
    };
    plan.applied = options.profile.apply(seed, &plan.true_tables());
    Ok(plan)
}
