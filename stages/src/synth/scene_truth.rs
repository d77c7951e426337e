//! `truth/scene.toml`: how an evaluator rebuilds the scene of a synthetic campaign, and the visibility questions
//! it can then answer (evaluation only; the pipeline never reads `truth/`).
//!
//! The generator is deterministic per (preset, seed), so the file names the two plus a *fingerprint*: a hash of
//! the hit distances of a fixed fan of probe rays cast from the driving route. Rebuilding the scene with another
//! version of the generator (or for a folder whose file was edited) gives another fingerprint, and the rebuild
//! is refused rather than grading against a different world. Campaigns rendered by other software have no such
//! file; graders then report what needs visibility (e.g. `oblique.non_matchable`) as null.

use nalgebra::Vector3;
use serde::{Deserialize, Serialize};

use super::preset::Preset;
use super::profile::EpochParams;
use super::scene::{Epoch, EpochChangeSpec, Scene, SceneSpec};
use crate::geometry::ray::Ray;

/// The file, relative to the campaign root.
pub const SCENE_TRUTH_FILE: &str = "truth/scene.toml";

/// Value of the `generator` key written by skytie's generator.
pub const GENERATOR: &str = "skytie-synth";

/// A hit counts as the point itself when it lies within this of the expected distance along the ray, m.
pub const VISIBILITY_TOLERANCE_M: f64 = 0.05;

/// Seed of the scene of area `area` (area 0 uses the campaign seed itself; areas of one campaign differ).
pub fn scene_seed(seed: u64, area: usize) -> u64 {
    seed ^ ((area as u64) << 48)
}

/// The scene spec of an area with the epoch differences of profile `epoch` (when given): more parked cars in
/// one epoch only, the mobile-mapping sun lower, changed markings, roadworks and grown crowns.
pub fn with_epoch_changes(mut spec: SceneSpec, epoch: Option<&EpochParams>) -> SceneSpec {
    if let Some(e) = epoch {
        spec.car_mm_only_fraction = e.moved_car_fraction / 2.0;
        spec.car_aerial_only_fraction = e.moved_car_fraction / 2.0;
        spec.sun_mobile_mapping.elevation_deg = e.mm_sun_elevation_deg;
        spec.changes = Some(EpochChangeSpec {
            changed_marking_fraction: e.changed_marking_fraction,
            roadworks_per_street: e.roadworks_per_street,
            crown_growth_m: e.crown_growth_m,
        });
    }
    spec
}

/// The scenes of `preset` with campaign seed `seed` (and the epoch differences of the `epoch` profile), one
/// per area, as the generator builds them.
pub fn build_scenes(preset: Preset, seed: u64, epoch: Option<&EpochParams>) -> Vec<Scene> {
    preset
        .scene_specs()
        .into_iter()
        .enumerate()
        .map(|(area, spec)| {
            Scene::generate(&with_epoch_changes(spec, epoch), scene_seed(seed, area))
        })
        .collect()
}

/// Points every `step_m` along a polyline (world XY), starting at its first vertex.
pub fn along_polyline(route: &[[f64; 2]], step_m: f64) -> Vec<[f64; 2]> {
    let mut out = Vec::new();
    let mut next_m = 0.0;
    let mut done_m = 0.0;
    for seg in route.windows(2) {
        let (a, b) = (seg[0], seg[1]);
        let len = (b[0] - a[0]).hypot(b[1] - a[1]);
        while len > 0.0 && next_m <= done_m + len {
            let t = (next_m - done_m) / len;
            out.push([a[0] + t * (b[0] - a[0]), a[1] + t * (b[1] - a[1])]);
            next_m += step_m;
        }
        done_m += len;
    }
    out
}

/// Hash (hex) of the hit distances (mm) of probe rays cast in the mobile-mapping epoch from points every 10 m
/// along the driving route, 2 m above the ground: 16 azimuths × 3 elevations (−15°, 0°, +15°).
pub fn fingerprint(scenes: &[Scene]) -> String {
    let mut h: u64 = 0xcbf2_9ce4_8422_2325;
    let mut eat = |x: i64| {
        for b in x.to_le_bytes() {
            h ^= u64::from(b);
            h = h.wrapping_mul(0x0100_0000_01b3);
        }
    };
    for scene in scenes {
        for p in along_polyline(scene.route_world(), 10.0) {
            let origin = Vector3::new(p[0], p[1], scene.ground_height_m(p[0], p[1]) + 2.0);
            for az in 0..16 {
                let a = (f64::from(az) * 22.5).to_radians();
                for el_deg in [-15.0f64, 0.0, 15.0] {
                    let e = el_deg.to_radians();
                    let dir = Vector3::new(a.sin() * e.cos(), a.cos() * e.cos(), e.sin());
                    let mm = scene
                        .first_hit(&origin, &dir, Epoch::MobileMapping)
                        .map_or(-1, |hit| (hit.distance_m * 1000.0).round() as i64);
                    eat(mm);
                }
            }
        }
    }
    format!("{h:016x}")
}

/// Contents of `truth/scene.toml`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SceneTruth {
    /// Which generator wrote the campaign (`skytie-synth`).
    pub generator: String,
    /// Preset name (`tiny`, `demo`, `paper`).
    pub preset: String,
    /// Campaign seed.
    pub seed: u64,
    /// [`fingerprint`] of the scenes.
    pub fingerprint: String,
    /// The epoch differences of the `epoch` error profile, if the campaign has them.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub epoch: Option<EpochParams>,
}

impl SceneTruth {
    /// The record of `scenes`, built for (`preset`, `seed`, `epoch`).
    pub fn of(preset: Preset, seed: u64, epoch: Option<&EpochParams>, scenes: &[Scene]) -> Self {
        Self {
            generator: GENERATOR.into(),
            preset: preset.name().into(),
            seed,
            fingerprint: fingerprint(scenes),
            epoch: epoch.cloned(),
        }
    }

    /// The file's text (a comment saying what it is for, then the keys).
    pub fn to_toml(&self) -> String {
        let mut t = format!(
            "# Rebuilds this synthetic campaign's scene for evaluation (visibility, true surface points).\n\
             # Never read by the pipeline. Written by skytie's generator; other software leaves it out.\n\
             generator = {:?}\npreset = {:?}\nseed = {}\nfingerprint = {:?}\n",
            self.generator, self.preset, self.seed, self.fingerprint
        );
        if let Some(e) = &self.epoch {
            let table = toml::to_string(e).unwrap_or_default();
            t.push_str(&format!("\n[epoch]\n{table}"));
        }
        t
    }

    /// Parse the file's text; the error says what is wrong.
    pub fn parse(text: &str) -> Result<Self, String> {
        let t: SceneTruth = toml::from_str(text).map_err(|e| e.to_string())?;
        if t.generator != GENERATOR {
            return Err(format!(
                "generator = {:?}: only scenes of {GENERATOR:?} can be rebuilt",
                t.generator
            ));
        }
        Ok(t)
    }

    /// Rebuild the scenes and check the fingerprint.
    pub fn rebuild(&self) -> Result<SceneOracle, String> {
        let preset = Preset::from_name(&self.preset).map_err(|e| e.to_string())?;
        let scenes = build_scenes(preset, self.seed, self.epoch.as_ref());
        let got = fingerprint(&scenes);
        if got != self.fingerprint {
            return Err(format!(
                "the rebuilt scene of preset {} seed {} has fingerprint {got}, the file says {}: the campaign \
                 was written by another version of the generator; regenerate it with `skytie synth` to grade \
                 visibility",
                self.preset, self.seed, self.fingerprint
            ));
        }
        Ok(SceneOracle { scenes })
    }
}

/// Visibility questions about a rebuilt scene (world coordinates, metres).
pub struct SceneOracle {
    scenes: Vec<Scene>,
}

impl SceneOracle {
    /// An oracle over already built scenes.
    pub fn new(scenes: Vec<Scene>) -> Self {
        Self { scenes }
    }

    /// The area whose bounds contain `xy_world`.
    fn scene_at(&self, x_world: f64, y_world: f64) -> Option<&Scene> {
        self.scenes.iter().find(|s| {
            let (lo, hi) = s.bounds_world();
            (lo[0]..=hi[0]).contains(&x_world) && (lo[1]..=hi[1]).contains(&y_world)
        })
    }

    /// The surface point a mobile-mapping camera sees along `ray` (the first hit in the mobile-mapping epoch),
    /// or `None` for sky or a ray starting outside every area.
    pub fn mm_surface_point(&self, ray: &Ray) -> Option<Vector3<f64>> {
        let o = &ray.origin_world;
        self.scene_at(o.x, o.y)?
            .first_hit(o, &ray.dir_world, Epoch::MobileMapping)
            .map(|h| h.point_world)
    }

    /// Whether `point_world` is the first surface an aerial camera at `centre_world` sees towards it, in the
    /// aerial epoch (other parked cars; a point on a car that has left is not visible).
    pub fn visible_from_aerial(
        &self,
        centre_world: &Vector3<f64>,
        point_world: &Vector3<f64>,
    ) -> bool {
        let Some(scene) = self.scene_at(point_world.x, point_world.y) else {
            return false;
        };
        let d = point_world - centre_world;
        scene
            .first_hit(centre_world, &d, Epoch::Aerial)
            .is_some_and(|h| (h.distance_m - d.norm()).abs() <= VISIBILITY_TOLERANCE_M)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_record_round_trips_and_rebuilds_the_same_scene() {
        let scenes = build_scenes(Preset::Tiny, 7, None);
        let t = SceneTruth::of(Preset::Tiny, 7, None, &scenes);
        let back = SceneTruth::parse(&t.to_toml()).expect("parses");
        assert_eq!(back, t);
        assert!(back.rebuild().is_ok());
        assert_ne!(
            fingerprint(&build_scenes(Preset::Tiny, 8, None)),
            t.fingerprint,
            "another seed builds another scene"
        );
    }

    #[test]
    fn points_along_a_polyline_are_evenly_spaced_across_vertices() {
        let pts = along_polyline(&[[0.0, 0.0], [3.0, 0.0], [3.0, 4.0]], 2.0);
        let want = [[0.0, 0.0], [2.0, 0.0], [3.0, 1.0], [3.0, 3.0]];
        assert_eq!(pts.len(), want.len());
        for (p, w) in pts.iter().zip(want) {
            assert!(
                (p[0] - w[0]).abs() < 1e-12 && (p[1] - w[1]).abs() < 1e-12,
                "{p:?} vs {w:?}"
            );
        }
    }

    #[test]
    fn a_wrong_fingerprint_or_generator_is_refused_with_the_reason() {
        let mut t = SceneTruth::of(Preset::Tiny, 7, None, &build_scenes(Preset::Tiny, 7, None));
        t.fingerprint = "0000000000000000".into();
        let e = SceneTruth::parse(&t.to_toml())
            .unwrap()
            .rebuild()
            .err()
            .unwrap();
        assert!(e.contains("another version of the generator"), "{e}");
        let e = SceneTruth::parse(
            "generator = \"blender\"\npreset = \"tiny\"\nseed = 1\nfingerprint = \"x\"\n",
        )
        .unwrap_err();
        assert!(e.contains("blender"), "{e}");
        assert!(SceneTruth::parse("preset = \"tiny\"").is_err());
    }

    #[test]
    fn a_facade_point_seen_from_the_street_is_visible_from_above_and_a_point_behind_it_is_not() {
        let scenes = build_scenes(Preset::Tiny, 3, None);
        let route = along_polyline(scenes[0].route_world(), 5.0);
        assert!(route.len() > 3, "the tiny route is longer than 15 m");
        let oracle = SceneOracle::new(scenes);
        let p = route[route.len() / 2];
        let ground = oracle.scenes[0].ground_height_m(p[0], p[1]);
        // Look sideways (perpendicular to the route) from 2 m above the road (over parked cars, which differ
        // between the epochs) until something is hit.
        let q = route[route.len() / 2 + 1];
        let along = Vector3::new(q[0] - p[0], q[1] - p[1], 0.0).normalize();
        let mut checked = 0;
        for side in [1.0, -1.0] {
            let dir = Vector3::new(-along.y, along.x, 0.0) * side;
            let ray = Ray {
                origin_world: Vector3::new(p[0], p[1], ground + 2.0),
                dir_world: dir,
            };
            let Some(x) = oracle.mm_surface_point(&ray) else {
                continue;
            };
            // A point 1 m behind the surface is hidden by it.
            let behind = x + dir * 1.0;
            assert!(!oracle.visible_from_aerial(&ray.origin_world, &behind));
            // The point itself is visible from where it was seen.
            assert!(oracle.visible_from_aerial(&ray.origin_world, &x));
            checked += 1;
        }
        assert!(checked > 0, "no surface beside the tiny route");
    }
}
