//! A synthetic Tiny campaign generated once per test binary into a temporary folder, loaded into memory (recorded
//! and true poses, panoramas) with the scene it was rendered from; the folder is removed afterwards. Tests read
//! the true poses and the scene for grading only.

use skytie_stages::campaign::{read_recordings_csv, Recording};
use skytie_stages::correspondence::MmTiePoint;
use skytie_stages::geometry::{
    triangulate_rays, PanoramaCamera, Ray, Triangulation, TriangulationError,
};
use skytie_stages::imaging::io::load_gray;
use skytie_stages::imaging::GrayImage;
use skytie_stages::synth::generate::plan_campaign;
use skytie_stages::synth::scene::Scene;
use skytie_stages::synth::{generate, Preset, SynthOptions};
use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::sync::OnceLock;

/// The seed of the shared Tiny campaign.
pub const SEED: u64 = 7;

/// A campaign folder's recordings and panoramas in memory.
pub struct Campaign {
    /// Recorded poses, in driving order.
    pub recorded: Vec<Recording>,
    /// True poses by image id (grading only).
    pub truth: HashMap<String, Recording>,
    /// The recordings' panoramas, in the order of `recorded`.
    pub panoramas: Vec<GrayImage>,
}

impl Campaign {
    /// The true poses in the order of `recorded`.
    pub fn true_poses(&self) -> Vec<Recording> {
        self.recorded
            .iter()
            .map(|r| self.truth[&r.image_id].clone())
            .collect()
    }
}

/// The generated campaign and the scene it was rendered from.
pub struct Fixture {
    pub campaign: Campaign,
    pub scene: Scene,
}

/// The demo campaign `SKYTIE_DEMO` names (`demo_campaign_dir`), loaded, and its folder.
pub fn load_demo_campaign() -> Option<(PathBuf, Campaign)> {
    let root = super::demo_campaign_dir()?;
    let campaign = load_campaign(&root);
    Some((root, campaign))
}

/// Reads `mm/recordings.csv`, `truth/recordings.csv` and the panoramas of a campaign folder; panics on any
/// problem (the folders are test inputs).
pub fn load_campaign(root: &Path) -> Campaign {
    let (mut recorded, problems) = read_recordings_csv(&root.join("mm/recordings.csv"));
    assert!(problems.is_empty(), "{problems:?}");
    recorded.sort_by(|a, b| a.time_s.total_cmp(&b.time_s));
    let (truth, problems) = read_recordings_csv(&root.join("truth/recordings.csv"));
    assert!(problems.is_empty(), "{problems:?}");
    let panoramas = recorded
        .iter()
        .map(|r| load_gray(&root.join("mm/panoramas").join(&r.file)).unwrap())
        .collect();
    Campaign {
        recorded,
        truth: truth.into_iter().map(|r| (r.image_id.clone(), r)).collect(),
        panoramas,
    }
}

/// The Tiny campaign of `SEED`, generated on first use.
pub fn fixture() -> &'static Fixture {
    static F: OnceLock<Fixture> = OnceLock::new();
    F.get_or_init(|| {
        let dir = tempfile::tempdir().unwrap();
        let root = dir.path().join("tiny");
        let options = SynthOptions::new(Preset::Tiny, SEED);
        generate(&options, &root).unwrap();
        let campaign = load_campaign(&root);
        let mut plan = plan_campaign(&options).unwrap();
        Fixture {
            campaign,
            scene: plan.areas.remove(0).scene,
        }
    })
}

/// A tie point seen with the true poses: its panorama cameras and pixel rays (in observation order) and their
/// triangulation (σ 0.5 px per ray).
pub struct TrueRays {
    pub cams: Vec<PanoramaCamera>,
    pub rays: Vec<Ray>,
    pub triangulation: Result<Triangulation, TriangulationError>,
}

/// The rays of `tp`'s observations from the true poses `truth` (by image id) of panoramas of `pano` (width,
/// height) pixels.
pub fn true_rays(
    tp: &MmTiePoint,
    truth: &HashMap<String, Recording>,
    pano: (u32, u32),
) -> TrueRays {
    let cams: Vec<PanoramaCamera> = tp
        .observations
        .iter()
        .map(|o| PanoramaCamera::from_recording(&truth[&o.image_id], pano.0, pano.1))
        .collect();
    let rays: Vec<Ray> = tp
        .observations
        .iter()
        .zip(&cams)
        .map(|(o, c)| c.pixel_ray(o.u_px, o.v_px))
        .collect();
    let sigmas: Vec<f64> = cams.iter().map(|c| c.angular_sigma_rad(0.5)).collect();
    let triangulation = triangulate_rays(&rays, &sigmas);
    TrueRays {
        cams,
        rays,
        triangulation,
    }
}
