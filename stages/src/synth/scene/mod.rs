//! The procedural 3-D street scene of the synthetic campaign and its ray caster.
//!
//! A street (optionally a junction, a canal) with a sloped, cambered ground, kerbs, sidewalks, road
//! markings and manholes, buildings with window grids, balconies/oriels and flat or gable roofs, street
//! trees with see-through crowns, and parked cars that differ between the mobile-mapping and the aerial
//! epoch; lit by an epoch-specific sun with cast shadows plus sky ambient. Used by `synth` (cameras,
//! render loop) as the known truth every stage is judged against.
//!
//! Frames: world = `origin_world` + rotation by the street heading (see [`spec`]); all maths is done in the
//! street-local frame in f64.

pub mod accel;
pub mod epoch_changes;
pub mod epoch_draw;
pub mod frame;
pub mod ground;
pub mod layout;
pub mod markings;
pub mod objects;
mod shading;
pub mod shapes;
pub mod spec;

use accel::Grid;
use frame::LocalFrame;
use ground::{Ground, GroundClass, StreetShape};
use markings::{StreetAxis, StreetMarkingInput, StreetMarkings};
use nalgebra::Vector3;
use objects::{Material, Object, Shape, IN_AERIAL, IN_BOTH, IN_MM};
use shapes::Ray;

pub use epoch_changes::{EpochChangeSpec, Roadworks};
pub use layout::{Building, Car};
pub use spec::{CanalSpec, CrossStreetSpec, RouteSpec, SceneSpec, SunSpec};

/// Acquisition epoch: the mobile-mapping run and the aerial flight see a different sun (so different
/// shadows) and different parked cars.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Epoch {
    MobileMapping,
    Aerial,
}

impl Epoch {
    #[inline]
    fn bit(self) -> u8 {
        match self {
            Epoch::MobileMapping => IN_MM,
            Epoch::Aerial => IN_AERIAL,
        }
    }
    #[inline]
    fn index(self) -> usize {
        match self {
            Epoch::MobileMapping => 0,
            Epoch::Aerial => 1,
        }
    }
}

/// An unshaded emissive sphere (camera known-answer tests). It casts no shadow and receives none.
#[derive(Clone, Debug, PartialEq)]
pub struct Marker {
    pub center_world: Vector3<f64>,
    pub radius_m: f64,
    pub rgb: [f32; 3],
}

/// What a ray hit.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SurfaceKind {
    Road,
    Marking,
    Sidewalk,
    Kerb,
    Grass,
    Water,
    Facade { building: u32 },
    Roof { building: u32 },
    Tree,
    Car,
    Marker,
}

/// A ray hit in world coordinates; `distance_m` along the (normalised) ray direction; the normal faces
/// the ray's origin side.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Hit {
    pub distance_m: f64,
    pub point_world: Vector3<f64>,
    pub normal_world: Vector3<f64>,
    pub surface: SurfaceKind,
}

/// Internal hit in the local frame.
#[derive(Clone, Copy, Debug)]
pub(crate) enum HitWhat {
    Ground { class: GroundClass, face: bool },
    Object(u32),
}

#[derive(Clone, Copy, Debug)]
pub(crate) struct LocalHit {
    pub t: f64,
    pub p: Vector3<f64>,
    pub n: Vector3<f64>,
    pub what: HitWhat,
}

/// The generated scene. `Send + Sync`; all queries are read-only.
pub struct Scene {
    frame: LocalFrame,
    ground: Ground,
    /// Flat grey ground without texture (markers-only scenes).
    plain_ground: bool,
    streets: Vec<StreetMarkings>,
    /// Roadworks patches (epoch changes), in their street's coordinates.
    roadworks: Vec<Roadworks>,
    sidewalk_width_m: f64,
    kerb_band_m: f64,
    objects: Vec<Object>,
    grid: Grid,
    buildings: Vec<Building>,
    cars: Vec<Car>,
    route_world: Vec<[f64; 2]>,
    bounds_local: ([f64; 2], [f64; 2]),
    /// Unit vectors towards the sun, local frame, per epoch.
    sun_local: [Vector3<f64>; 2],
    texture_seed: u64,
}

/// Grid cell size, m.
const GRID_CELL_M: f64 = 4.0;
/// Offset of shadow-ray origins along the surface normal, m.
const SHADOW_EPS_M: f64 = 1e-4;

fn sun_vector_world(s: &SunSpec) -> Vector3<f64> {
    let (a, e) = (s.azimuth_deg.to_radians(), s.elevation_deg.to_radians());
    Vector3::new(a.sin() * e.cos(), a.cos() * e.cos(), e.sin())
}

impl Scene {
    /// Generate the scene for `spec`; deterministic per (spec, seed).
    pub fn generate(spec: &SceneSpec, seed: u64) -> Scene {
        let frame = LocalFrame::new(spec.origin_world, spec.street_heading_deg);
        let hw = spec.road_half_width_m;
        let sw = spec.sidewalk_width_m;
        let cross = spec.cross_street.map(|c| {
            let y0 = if c.extent_right_m > 0.0 {
                f64::NEG_INFINITY
            } else {
                0.0
            };
            let y1 = if c.extent_left_m > 0.0 {
                f64::INFINITY
            } else {
                0.0
            };
            (c.at_x_m, c.half_width_m, y0, y1)
        });
        let canal = spec.canal.map(|c| {
            let q = hw + sw + c.quay_width_m;
            (-(q + c.width_m), -q, c.drop_m)
        });
        let ground = Ground::street(StreetShape {
            z0: spec.base_height_m,
            gx: spec.slope_x,
            gy: spec.slope_y,
            crossfall: spec.crossfall,
            kerb_m: spec.kerb_height_m,
            half_width_m: hw,
            cross,
            canal,
        });
        let phase = |k: u64| crate::synth::noise::unit_f64(crate::synth::noise::mix64(seed ^ k));
        let mut streets = vec![StreetMarkings::layout(&StreetMarkingInput {
            axis: StreetAxis::AlongX,
            s_range: (0.0, spec.street_length_m),
            half_width_m: hw,
            parking_width_m: spec.parking_width_m,
            junctions: spec
                .cross_street
                .iter()
                .map(|c| (c.at_x_m, c.half_width_m))
                .collect(),
            paint: spec.markings,
            manhole_spacing_m: spec.manhole_spacing_m,
            manhole_phase: phase(0x3A11),
        })];
        if let Some(c) = spec.cross_street {
            streets.push(StreetMarkings::layout(&StreetMarkingInput {
                axis: StreetAxis::AlongY { crown_x: c.at_x_m },
                s_range: (-c.extent_right_m, c.extent_left_m),
                half_width_m: c.half_width_m,
                parking_width_m: 0.0,
                junctions: vec![(0.0, hw)],
                paint: spec.markings,
                manhole_spacing_m: spec.manhole_spacing_m,
                manhole_phase: phase(0x3A12),
            }));
        }
        let mut lay = layout::generate(spec, seed, &ground);
        let mut roadworks = Vec::new();
        if let Some(ch) = &spec.changes {
            let mut ranges = vec![((0.0, spec.street_length_m), hw)];
            if let Some(c) = spec.cross_street {
                ranges.push(((-c.extent_right_m, c.extent_left_m), c.half_width_m));
            }
            for (k, (st, (s_range, half))) in streets.iter_mut().zip(ranges).enumerate() {
                st.vary_epochs(seed, k, ch.changed_marking_fraction);
                for r in epoch_changes::place_roadworks(ch, seed, k, s_range, half) {
                    lay.objects
                        .extend(epoch_changes::cones(&r, st.axis, |x, y| {
                            ground.height(x, y)
                        }));
                    roadworks.push(r);
                }
            }
        }
        let grid = Grid::build(&lay.objects, GRID_CELL_M);
        let route_local = route_polyline(spec);
        let route_world = route_local.iter().map(|p| frame.to_world_xy(*p)).collect();
        let mut ymax = hw + sw + spec.setback_m[1] + spec.building_depth_m[1] + 5.0;
        let mut ymin = -ymax;
        if let Some(c) = spec.cross_street {
            ymax = ymax.max(c.extent_left_m);
            ymin = ymin.min(-c.extent_right_m);
        }
        if let Some(c) = canal {
            ymin = ymin.min(c.0 - 5.0);
        }
        let bounds_local = ([-10.0, ymin], [spec.street_length_m + 10.0, ymax]);
        let sun_local = [
            frame.dir_to_local(&sun_vector_world(&spec.sun_mobile_mapping)),
            frame.dir_to_local(&sun_vector_world(&spec.sun_aerial)),
        ];
        Scene {
            frame,
            ground,
            plain_ground: false,
            streets,
            roadworks,
            sidewalk_width_m: sw,
            kerb_band_m: spec.kerb_band_m,
            objects: lay.objects,
            grid,
            buildings: lay.buildings,
            cars: lay.cars,
            route_world,
            bounds_local,
            sun_local,
            texture_seed: crate::synth::noise::mix64(seed ^ 0x7E47),
        }
    }

    /// Flat grey ground at height `ground_z_m` (no texture, no objects) plus markers: for camera
    /// known-answer tests. The local frame equals the world frame shifted by `origin_world`.
    pub fn markers_only(origin_world: [f64; 2], ground_z_m: f64, markers: Vec<Marker>) -> Scene {
        let frame = LocalFrame::new(origin_world, 0.0);
        let spec = SceneSpec::demo();
        let mut s = Scene {
            frame,
            ground: Ground::flat(ground_z_m),
            plain_ground: true,
            streets: Vec::new(),
            roadworks: Vec::new(),
            sidewalk_width_m: 0.0,
            kerb_band_m: 0.0,
            objects: Vec::new(),
            grid: Grid::build(&[], GRID_CELL_M),
            buildings: Vec::new(),
            cars: Vec::new(),
            route_world: Vec::new(),
            bounds_local: ([-50.0, -50.0], [50.0, 50.0]),
            sun_local: [
                sun_vector_world(&spec.sun_mobile_mapping),
                sun_vector_world(&spec.sun_aerial),
            ],
            texture_seed: 0,
        };
        s.add_markers(&markers);
        s
    }

    /// Add emissive marker spheres (rebuilds the acceleration grid).
    pub fn add_markers(&mut self, markers: &[Marker]) {
        for m in markers {
            let c = self.frame.point_to_local(&m.center_world);
            self.objects.push(Object::new(
                Shape::Sphere {
                    centre: c,
                    r: m.radius_m.abs(),
                },
                Material::Marker { rgb: m.rgb },
                IN_BOTH,
            ));
        }
        self.grid = Grid::build(&self.objects, GRID_CELL_M);
    }

    /// World XY of the local origin.
    pub fn origin_world(&self) -> [f64; 2] {
        self.frame.origin_world
    }

    /// XY min and max (world) of the modelled area.
    pub fn bounds_world(&self) -> ([f64; 2], [f64; 2]) {
        let (lo, hi) = self.bounds_local;
        let mut min = [f64::INFINITY; 2];
        let mut max = [f64::NEG_INFINITY; 2];
        for x in [lo[0], hi[0]] {
            for y in [lo[1], hi[1]] {
                let w = self.frame.to_world_xy([x, y]);
                for i in 0..2 {
                    min[i] = min[i].min(w[i]);
                    max[i] = max[i].max(w[i]);
                }
            }
        }
        (min, max)
    }

    /// The driving polyline (world XY) in the right-hand lane.
    pub fn route_world(&self) -> &[[f64; 2]] {
        &self.route_world
    }

    /// Height of the road/sidewalk surface (world Z) at world (x, y).
    pub fn ground_height_m(&self, x_world: f64, y_world: f64) -> f64 {
        let l = self.frame.to_local_xy([x_world, y_world]);
        self.ground.height(l[0], l[1])
    }

    /// The buildings (local frame; see [`Scene::local_to_world_xy`]).
    pub fn buildings(&self) -> &[Building] {
        &self.buildings
    }

    /// The parked cars (local frame) with their epochs.
    pub fn cars(&self) -> &[Car] {
        &self.cars
    }

    /// Is this car present in `epoch`?
    pub fn car_in_epoch(car: &Car, epoch: Epoch) -> bool {
        car.epochs & epoch.bit() != 0
    }

    /// Street-local XY → world XY.
    pub fn local_to_world_xy(&self, local: [f64; 2]) -> [f64; 2] {
        self.frame.to_world_xy(local)
    }

    /// World XY → street-local XY.
    pub fn world_to_local_xy(&self, world: [f64; 2]) -> [f64; 2] {
        self.frame.to_local_xy(world)
    }

    /// Street-local direction → world direction.
    pub fn local_dir_to_world(&self, d_local: &Vector3<f64>) -> Vector3<f64> {
        self.frame.dir_to_world(d_local)
    }

    /// Nearest hit in the local frame (`d` unit length).
    pub(crate) fn trace_local(
        &self,
        o: &Vector3<f64>,
        d: &Vector3<f64>,
        epoch: Epoch,
    ) -> Option<LocalHit> {
        let mut best_t = f64::INFINITY;
        let mut best: Option<LocalHit> = None;
        if let Some(g) = self.ground.intersect(o, d, 0.0, f64::INFINITY) {
            best_t = g.t;
            best = Some(LocalHit {
                t: g.t,
                p: o + d * g.t,
                n: g.normal_local,
                what: HitWhat::Ground {
                    class: g.class,
                    face: g.vertical_face,
                },
            });
        }
        let ray = Ray::new(*o, *d);
        let bit = epoch.bit();
        let mut best_obj: Option<(u32, f64, Vector3<f64>)> = None;
        self.grid.walk(&ray, 0.0, best_t, |cell, t_exit| {
            for &k in cell {
                let obj = &self.objects[k as usize];
                if obj.epochs & bit == 0 {
                    continue;
                }
                let end = obj.children_end.max(k + 1);
                if end > k + 1 && obj.bounds.clip(o, &ray.inv_d, 0.0, best_t).is_none() {
                    continue; // misses the compound's envelope
                }
                for j in k..end {
                    let part = &self.objects[j as usize];
                    if let Some((t, n)) = part.hit(&ray, 0.0, best_t) {
                        best_t = t;
                        best_obj = Some((j, t, n));
                    }
                }
            }
            best_t <= t_exit
        });
        if let Some((k, t, n)) = best_obj {
            best = Some(LocalHit {
                t,
                p: o + d * t,
                n,
                what: HitWhat::Object(k),
            });
        }
        best
    }

    /// Is the segment from `o` along `d` (unit, local) blocked before `t_max`? Markers are ignored.
    pub(crate) fn occluded_local(&self, o: &Vector3<f64>, d: &Vector3<f64>, epoch: Epoch) -> bool {
        // the ground can only block a rising shadow ray within a short range (kerb steps)
        if let Some(_g) = self.ground.intersect(o, d, 0.0, 30.0) {
            return true;
        }
        let ray = Ray::new(*o, *d);
        let bit = epoch.bit();
        let mut blocked = false;
        self.grid.walk(&ray, 0.0, f64::INFINITY, |cell, _| {
            for &k in cell {
                let obj = &self.objects[k as usize];
                if obj.epochs & bit == 0 || matches!(obj.material, Material::Marker { .. }) {
                    continue;
                }
                let end = obj.children_end.max(k + 1);
                if end > k + 1 && obj.bounds.clip(o, &ray.inv_d, 0.0, f64::INFINITY).is_none() {
                    continue;
                }
                for j in k..end {
                    if self.objects[j as usize]
                        .hit(&ray, 0.0, f64::INFINITY)
                        .is_some()
                    {
                        blocked = true;
                        return true;
                    }
                }
            }
            false
        });
        blocked
    }

    /// The nearest surface along the ray (direction need not be normalised), in `epoch`.
    pub fn first_hit(
        &self,
        origin_world: &Vector3<f64>,
        dir_world: &Vector3<f64>,
        epoch: Epoch,
    ) -> Option<Hit> {
        let n = dir_world.norm();
        if !(n > 0.0) || !n.is_finite() || !origin_world.iter().all(|v| v.is_finite()) {
            return None;
        }
        let o = self.frame.point_to_local(origin_world);
        let d = self.frame.dir_to_local(&(dir_world / n));
        let h = self.trace_local(&o, &d, epoch)?;
        Some(Hit {
            distance_m: h.t,
            point_world: origin_world + dir_world / n * h.t,
            normal_world: self.frame.dir_to_world(&h.n),
            surface: self.surface_kind(&h, epoch),
        })
    }

    /// Linear RGB (nominally 0..1) seen along the ray: sun (per epoch) + sky ambient shading, cast shadows,
    /// sky colour when nothing is hit. Markers return their rgb unshaded.
    pub fn radiance(
        &self,
        origin_world: &Vector3<f64>,
        dir_world: &Vector3<f64>,
        epoch: Epoch,
    ) -> [f32; 3] {
        let n = dir_world.norm();
        if !(n > 0.0) || !n.is_finite() || !origin_world.iter().all(|v| v.is_finite()) {
            return [0.0; 3];
        }
        let d_world = dir_world / n;
        let o = self.frame.point_to_local(origin_world);
        let d = self.frame.dir_to_local(&d_world);
        match self.trace_local(&o, &d, epoch) {
            None => crate::synth::texture::sky(d_world.z),
            Some(h) => self.shade(&h, &d, epoch),
        }
    }

    /// Distinct ground features with exact world coordinates, for check points: zebra stripe corners,
    /// stop-line corners, manhole centres, arrow tips, dashed-line ends. Only features on the carriageway
    /// that are visible from 2 m straight above in both epochs are returned.
    pub fn checkpoint_candidates(&self) -> Vec<(String, Vector3<f64>)> {
        let mut out = Vec::new();
        for st in &self.streets {
            for (kind, xy) in st.features_local() {
                let under_roadworks = self.roadworks.iter().any(|r| {
                    let (s, q) = self.streets[r.street].axis.to_sq(xy[0], xy[1]);
                    r.contains(s, q)
                });
                if !self.ground.on_road(xy[0], xy[1]) || under_roadworks {
                    continue;
                }
                let z = self.ground.height(xy[0], xy[1]);
                let o = Vector3::new(xy[0], xy[1], z + 2.0);
                let down = Vector3::new(0.0, 0.0, -1.0);
                let visible = [Epoch::MobileMapping, Epoch::Aerial].iter().all(|&e| {
                    matches!(self.trace_local(&o, &down, e), Some(h) if matches!(h.what, HitWhat::Ground { face: false, .. }) && (h.t - 2.0).abs() < 1e-6)
                });
                if visible {
                    let w = self.frame.to_world_xy(xy);
                    out.push((kind.to_string(), Vector3::new(w[0], w[1], z)));
                }
            }
        }
        out
    }
}

/// The route in local XY: right-hand lane of the main street, optionally a right turn into the cross street.
fn route_polyline(spec: &SceneSpec) -> Vec<[f64; 2]> {
    let r = &spec.route;
    let lo = r.lane_offset_m;
    match spec.cross_street {
        Some(c) if r.turn_right && c.extent_right_m > 0.0 => {
            let rad = r.turn_radius_m.max(1.0);
            let xa = c.at_x_m - lo - rad; // arc start x
            let mut pts = vec![[r.start_x_m, -lo]];
            let centre = [xa, -lo - rad];
            let n = 12;
            for k in 0..=n {
                let a = std::f64::consts::FRAC_PI_2 * (1.0 - k as f64 / n as f64);
                pts.push([centre[0] + rad * a.cos(), centre[1] + rad * a.sin()]);
            }
            let y_end = (-lo - rad - r.length_after_junction_m).max(-c.extent_right_m + 2.0);
            pts.push([c.at_x_m - lo, y_end]);
            pts
        }
        _ => vec![[r.start_x_m, -lo], [r.end_x_m, -lo]],
    }
}
