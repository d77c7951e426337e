//! Seeded layout of everything above the ground: building blocks along the street sides (façade lines,
//! set-backs, gaps, storeys, windows grid, gable/flat roofs, balconies and oriels), street trees and parked
//! cars with their epochs. Pure function of (spec, seed, ground).

use super::ground::Ground;
use super::objects::{Material, Object, Shape, IN_AERIAL, IN_BOTH, IN_MM};
use super::shapes::{Aabb, ConvexPrism};
use super::spec::SceneSpec;
use crate::synth::noise::SplitMix64;
use nalgebra::Vector3;

/// A building's geometry and look (local frame). Public for tests and for synthcam's truth data.
#[derive(Clone, Debug, PartialEq)]
pub struct Building {
    pub id: u32,
    pub footprint_min_local: [f64; 2],
    pub footprint_max_local: [f64; 2],
    /// Outward unit normal (local XY) of the street façade.
    pub front_normal_local: [f64; 2],
    /// Ground height in front of the façade's centre (storey 0 floor), m.
    pub floor0_z_m: f64,
    pub base_z_m: f64,
    pub eave_z_m: f64,
    pub ridge_z_m: Option<f64>,
    pub storeys: u32,
    pub storey_height_m: f64,
    /// Horizontal pitch of the window grid along the façade, m.
    pub bay_m: f64,
    pub window_w_m: f64,
    pub window_h_m: f64,
    pub sill_m: f64,
    /// Bay index of the front door (ground floor).
    pub door_bay: u32,
    pub wall_rgb: [f32; 3],
    pub frame_rgb: [f32; 3],
    pub roof_rgb: [f32; 3],
    pub brick: bool,
    pub seed: u64,
}

/// A parked car (local frame).
#[derive(Clone, Debug, PartialEq)]
pub struct Car {
    pub centre_local: [f64; 2],
    pub ground_z_m: f64,
    pub length_m: f64,
    pub width_m: f64,
    pub height_m: f64,
    /// Long axis along local x (else y).
    pub along_x: bool,
    pub epochs: u8,
    pub rgb: [f32; 3],
}

/// Result of the layout.
pub struct Layout {
    pub buildings: Vec<Building>,
    pub cars: Vec<Car>,
    pub objects: Vec<Object>,
}

const WALL_COLOURS: [[f32; 3]; 8] = [
    [0.42, 0.20, 0.14], // red brick
    [0.50, 0.30, 0.20], // orange brick
    [0.30, 0.16, 0.12], // dark brick
    [0.62, 0.58, 0.50], // beige plaster
    [0.70, 0.68, 0.64], // white-ish plaster
    [0.45, 0.44, 0.42], // grey concrete
    [0.55, 0.40, 0.28], // yellow brick
    [0.36, 0.30, 0.28], // dark plaster
];
const CAR_COLOURS: [[f32; 3]; 8] = [
    [0.75, 0.75, 0.76],
    [0.05, 0.05, 0.06],
    [0.30, 0.31, 0.33],
    [0.55, 0.05, 0.04],
    [0.06, 0.12, 0.40],
    [0.80, 0.80, 0.78],
    [0.10, 0.25, 0.12],
    [0.60, 0.45, 0.10],
];

/// One side of one street where buildings stand.
struct Frontage {
    /// along-street range (s)
    s_range: (f64, f64),
    /// excluded s intervals (junctions)
    holes: Vec<(f64, f64)>,
    /// distance of the sidewalk's outer edge from the crown
    edge_q: f64,
    /// +1 left (q > 0), −1 right
    side: f64,
    along_x: bool,
    /// crown position for cross streets (x of crown)
    crown_x: f64,
}

impl Frontage {
    /// Local XY from street (s, q).
    fn xy(&self, s: f64, q: f64) -> [f64; 2] {
        if self.along_x {
            [s, q]
        } else {
            [self.crown_x - q, s]
        }
    }
}

fn pick(rng: &mut SplitMix64, r: [f64; 2]) -> f64 {
    rng.range(r[0], r[1])
}

pub fn generate(spec: &SceneSpec, seed: u64, ground: &Ground) -> Layout {
    let mut rng = SplitMix64::new(seed ^ 0xB1D1_u64);
    let hw = spec.road_half_width_m;
    let sw = spec.sidewalk_width_m;
    let len = spec.street_length_m;
    let mut frontages = Vec::new();
    let mut main_holes = Vec::new();
    let max_depth = spec.building_depth_m[1];
    if let Some(c) = spec.cross_street {
        let pad = c.half_width_m + sw + 1.0;
        if c.extent_left_m > 0.0 {
            main_holes.push((c.at_x_m - pad, c.at_x_m + pad, 1.0));
        }
        if c.extent_right_m > 0.0 {
            main_holes.push((c.at_x_m - pad, c.at_x_m + pad, -1.0));
        }
    }
    let canal_q = spec.canal.map(|c| hw + sw + c.quay_width_m);
    for (side, enabled) in [(1.0, spec.buildings_left), (-1.0, spec.buildings_right)] {
        if !enabled || (side < 0.0 && canal_q.is_some()) {
            continue;
        }
        let holes = main_holes
            .iter()
            .filter(|h| h.2 == side)
            .map(|h| (h.0, h.1))
            .collect();
        frontages.push(Frontage {
            s_range: (0.0, len),
            holes,
            edge_q: hw + sw,
            side,
            along_x: true,
            crown_x: 0.0,
        });
    }
    if let (Some(c), true) = (spec.cross_street, spec.buildings_on_cross_street) {
        let start = hw + sw + spec.setback_m[1] + max_depth + 2.0;
        for (lo, hi, on) in [
            (-c.extent_right_m, -start, c.extent_right_m > start),
            (start, c.extent_left_m, c.extent_left_m > start),
        ] {
            if !on {
                continue;
            }
            for side in [1.0, -1.0] {
                frontages.push(Frontage {
                    s_range: (lo, hi),
                    holes: Vec::new(),
                    edge_q: c.half_width_m + sw,
                    side,
                    along_x: false,
                    crown_x: c.at_x_m,
                });
            }
        }
    }
    let mut buildings = Vec::new();
    let mut objects = Vec::new();
    for f in &frontages {
        let mut s = f.s_range.0 + rng.range(0.0, 2.0);
        while s < f.s_range.1 - 4.0 {
            let width = pick(&mut rng, spec.building_width_m).min(f.s_range.1 - s);
            let gap = pick(&mut rng, spec.building_gap_m);
            let s_end = s + width;
            if let Some(h) = f.holes.iter().find(|h| s_end > h.0 && s < h.1) {
                s = h.1 + rng.range(0.0, 1.0);
                continue;
            }
            if width >= 4.0 {
                let id = buildings.len() as u32;
                let setback = pick(&mut rng, spec.setback_m);
                let depth = pick(&mut rng, spec.building_depth_m);
                add_building(
                    spec,
                    &mut rng,
                    ground,
                    f,
                    id,
                    s,
                    s_end,
                    f.edge_q + setback,
                    depth,
                    &mut buildings,
                    &mut objects,
                );
            }
            s = s_end + gap;
        }
    }
    add_trees(spec, &mut rng, ground, &mut objects);
    let cars = add_cars(spec, &mut rng, ground, &mut objects);
    Layout {
        buildings,
        cars,
        objects,
    }
}

#[allow(clippy::too_many_arguments)]
fn add_building(
    spec: &SceneSpec,
    rng: &mut SplitMix64,
    ground: &Ground,
    f: &Frontage,
    id: u32,
    s0: f64,
    s1: f64,
    facade_q: f64,
    depth: f64,
    buildings: &mut Vec<Building>,
    objects: &mut Vec<Object>,
) {
    let q_front = f.side * facade_q;
    let q_back = f.side * (facade_q + depth);
    let a = f.xy(s0, q_front);
    let b = f.xy(s1, q_back);
    let min = [a[0].min(b[0]), a[1].min(b[1])];
    let max = [a[0].max(b[0]), a[1].max(b[1])];
    let front_normal = if f.along_x {
        [0.0, -f.side]
    } else {
        [f.side, 0.0]
    };
    let mid = f.xy(0.5 * (s0 + s1), q_front - f.side * 0.05);
    let floor0 = ground.height(mid[0], mid[1]);
    let mut base = f64::INFINITY;
    for x in [min[0], max[0]] {
        for y in [min[1], max[1]] {
            base = base.min(ground.height(x, y));
        }
    }
    base -= 0.3;
    let storeys = spec.storeys[0]
        + rng.below((spec.storeys[1] - spec.storeys[0].min(spec.storeys[1]) + 1) as usize) as u32;
    let storey_h = pick(rng, spec.storey_height_m);
    let eave = floor0 + storeys as f64 * storey_h + rng.range(0.3, 0.9);
    let width = s1 - s0;
    let n_bays = ((width / rng.range(2.4, 3.2)).round() as u32).max(1);
    let bay = width / n_bays as f64;
    let window_w = bay * rng.range(0.42, 0.62);
    let window_h = (storey_h * rng.range(0.45, 0.55)).min(storey_h - 1.1);
    let wall = WALL_COLOURS[rng.below(WALL_COLOURS.len())];
    let brick = wall[0] > wall[2] * 1.6 && rng.chance(0.8);
    let frame = if rng.chance(0.6) {
        [0.85, 0.85, 0.82]
    } else {
        [0.12, 0.14, 0.13]
    };
    let gable = rng.chance(spec.gable_probability);
    let roof = if gable {
        if rng.chance(0.6) {
            [0.40, 0.16, 0.10]
        } else {
            [0.16, 0.16, 0.18]
        }
    } else {
        [0.30, 0.30, 0.29]
    };
    let ridge = gable.then(|| eave + depth * rng.range(0.35, 0.55));
    let body = Aabb::new(
        Vector3::new(min[0], min[1], base),
        Vector3::new(max[0], max[1], eave),
    );
    let parent = objects.len();
    objects.push(Object::new(
        Shape::Box(body),
        Material::Building { building: id },
        IN_BOTH,
    ));
    if let Some(rz) = ridge {
        let prism = ConvexPrism::gable(min, max, eave, rz, f.along_x);
        let bounds = Aabb::new(
            Vector3::new(min[0], min[1], eave),
            Vector3::new(max[0], max[1], rz),
        );
        objects.push(
            Object::with_bounds(
                Shape::Prism(prism),
                bounds,
                Material::GableRoof { building: id },
                IN_BOTH,
            )
            .as_child(),
        );
    }
    // balconies (one per bay on alternating or all floors) or oriels spanning the upper floors
    if storeys >= 2 && rng.chance(spec.balcony_probability) {
        let proj = rng.range(0.3, 0.5);
        let oriel = rng.chance(0.35);
        let every = if rng.chance(0.5) { 1 } else { 2 };
        for bay_i in (0..n_bays).filter(|i| i % every == 0) {
            let bs0 = s0 + bay_i as f64 * bay + 0.15 * bay;
            let bs1 = s0 + (bay_i + 1) as f64 * bay - 0.15 * bay;
            let floors: Vec<(f64, f64)> = if oriel {
                vec![(
                    floor0 + storey_h - 0.2,
                    floor0 + storeys as f64 * storey_h - 0.3,
                )]
            } else {
                (1..storeys)
                    .map(|k| {
                        (
                            floor0 + k as f64 * storey_h - 0.15,
                            floor0 + k as f64 * storey_h + 1.0,
                        )
                    })
                    .collect()
            };
            for (z0, z1) in floors {
                let pa = f.xy(bs0, q_front);
                let pb = f.xy(bs1, q_front - f.side * proj);
                let bmin = Vector3::new(pa[0].min(pb[0]), pa[1].min(pb[1]), z0);
                let bmax = Vector3::new(pa[0].max(pb[0]), pa[1].max(pb[1]), z1);
                objects.push(
                    Object::new(
                        Shape::Box(Aabb::new(bmin, bmax)),
                        Material::Balcony { building: id },
                        IN_BOTH,
                    )
                    .as_child(),
                );
            }
        }
    }
    // rooftop units on flat roofs
    if ridge.is_none() {
        for _ in 0..rng.below(3) {
            let (w, l, h) = (
                rng.range(0.8, 2.2),
                rng.range(0.8, 2.5),
                rng.range(0.5, 1.4),
            );
            let cx = rng.range(
                min[0] + 1.0 + 0.5 * w,
                (max[0] - 1.0 - 0.5 * w).max(min[0] + 1.0 + 0.5 * w),
            );
            let cy = rng.range(
                min[1] + 1.0 + 0.5 * l,
                (max[1] - 1.0 - 0.5 * l).max(min[1] + 1.0 + 0.5 * l),
            );
            let unit = Aabb::new(
                Vector3::new(cx - 0.5 * w, cy - 0.5 * l, eave - 0.05),
                Vector3::new(cx + 0.5 * w, cy + 0.5 * l, eave + h),
            );
            objects.push(
                Object::new(
                    Shape::Box(unit),
                    Material::RoofUnit { building: id },
                    IN_BOTH,
                )
                .as_child(),
            );
        }
    }
    // the body is a compound enclosing its roof and protrusions
    let mut env = objects[parent].bounds;
    for o in &objects[parent + 1..] {
        env = env.union(&o.bounds);
    }
    objects[parent].bounds = env;
    objects[parent].children_end = objects.len() as u32;
    buildings.push(Building {
        id,
        footprint_min_local: min,
        footprint_max_local: max,
        front_normal_local: front_normal,
        floor0_z_m: floor0,
        base_z_m: base,
        eave_z_m: eave,
        ridge_z_m: ridge,
        storeys,
        storey_height_m: storey_h,
        bay_m: bay,
        window_w_m: window_w,
        window_h_m: window_h,
        sill_m: rng.range(0.8, 1.0),
        door_bay: rng.below(n_bays as usize) as u32,
        wall_rgb: wall,
        frame_rgb: frame,
        roof_rgb: roof,
        brick,
        seed: rng.next_u64(),
    });
}

fn add_tree(
    rng: &mut SplitMix64,
    spec: &SceneSpec,
    ground: &Ground,
    xy: [f64; 2],
    objects: &mut Vec<Object>,
) {
    let gz = ground.height(xy[0], xy[1]);
    let r = pick(rng, spec.crown_radius_m);
    let rz = r * rng.range(0.9, 1.25);
    let ch = pick(rng, spec.crown_centre_height_m).max(rz + 1.8);
    let centre = Vector3::new(
        xy[0] + rng.range(-0.3, 0.3),
        xy[1] + rng.range(-0.3, 0.3),
        gz + ch,
    );
    let inv_r = Vector3::new(1.0 / r, 1.0 / (r * rng.range(0.85, 1.15)), 1.0 / rz);
    let trunk_r = rng.range(0.12, 0.22);
    objects.push(Object::new(
        Shape::Cylinder {
            cx: xy[0],
            cy: xy[1],
            r: trunk_r,
            z0: gz - 0.2,
            z1: gz + ch,
        },
        Material::Trunk,
        IN_BOTH,
    ));
    let (hole_seed, leaf_seed) = (rng.next_u64(), rng.next_u64());
    let growth_m = spec.changes.map_or(0.0, |c| c.crown_growth_m);
    let crown = |inv_r: Vector3<f64>, epochs| {
        Object::new(
            Shape::Crown {
                centre,
                inv_r,
                hole_seed,
            },
            Material::Leaves { seed: leaf_seed },
            epochs,
        )
    };
    if growth_m > 0.0 {
        // The aerial epoch's crown is larger (grown by the time of the flight).
        let grown = inv_r.map(|v| 1.0 / (1.0 / v + growth_m));
        objects.push(crown(inv_r, IN_MM));
        objects.push(crown(grown, IN_AERIAL));
    } else {
        objects.push(crown(inv_r, IN_BOTH));
    }
}

fn add_trees(spec: &SceneSpec, rng: &mut SplitMix64, ground: &Ground, objects: &mut Vec<Object>) {
    if spec.tree_spacing_m <= 0.0 {
        return;
    }
    let hw = spec.road_half_width_m;
    let sp = spec.tree_spacing_m;
    let q = hw + spec.tree_offset_m;
    for side in [1.0, -1.0] {
        let mut x = rng.range(0.2, 1.0) * sp;
        while x < spec.street_length_m {
            let near_junction = spec.cross_street.is_some_and(|c| {
                let on_side = if side > 0.0 {
                    c.extent_left_m > 0.0
                } else {
                    c.extent_right_m > 0.0
                };
                (x - c.at_x_m).abs() < c.half_width_m + spec.sidewalk_width_m + 2.5 && on_side
            }) || spec
                .cross_street
                .is_some_and(|c| (x - c.at_x_m).abs() < c.half_width_m + 13.0 && spec.markings);
            if !near_junction {
                let xt = x + rng.range(-0.15, 0.15) * sp;
                add_tree(rng, spec, ground, [xt, side * q], objects);
            }
            x += sp;
        }
    }
    if let Some(c) = spec.cross_street {
        let start = hw + spec.sidewalk_width_m + 4.0;
        let qc = c.half_width_m + spec.tree_offset_m;
        for (lo, hi) in [(-c.extent_right_m, -start), (start, c.extent_left_m)] {
            if hi - lo < sp {
                continue;
            }
            for side in [1.0, -1.0] {
                let mut y = lo + rng.range(0.3, 1.0) * sp;
                while y < hi {
                    add_tree(rng, spec, ground, [c.at_x_m - side * qc, y], objects);
                    y += sp;
                }
            }
        }
    }
}

fn add_cars(
    spec: &SceneSpec,
    rng: &mut SplitMix64,
    ground: &Ground,
    objects: &mut Vec<Object>,
) -> Vec<Car> {
    let mut cars = Vec::new();
    if spec.parking_width_m < 1.9 || spec.car_probability <= 0.0 {
        return cars;
    }
    let hw = spec.road_half_width_m;
    let q = hw - 0.5 * spec.parking_width_m;
    let slot = 5.6;
    for side in [1.0, -1.0] {
        let mut x = 3.0;
        while x + slot < spec.street_length_m - 2.0 {
            let cx = x + 0.5 * slot;
            x += slot;
            if spec
                .cross_street
                .is_some_and(|c| (cx - c.at_x_m).abs() < c.half_width_m + 16.0)
            {
                continue;
            }
            if !rng.chance(spec.car_probability) {
                continue;
            }
            let u = rng.next_f64();
            let epochs = if u < spec.car_mm_only_fraction {
                IN_MM
            } else if u < spec.car_mm_only_fraction + spec.car_aerial_only_fraction {
                IN_AERIAL
            } else {
                IN_BOTH
            };
            let length = rng.range(3.9, 4.8);
            let width = rng.range(1.70, 1.86);
            let height = rng.range(1.40, 1.58);
            let rgb = CAR_COLOURS[rng.below(CAR_COLOURS.len())];
            let c = [cx + rng.range(-0.3, 0.3), side * (q + rng.range(-0.1, 0.1))];
            let gz = ground.height(c[0], c[1]);
            let body = Aabb::new(
                Vector3::new(c[0] - 0.5 * length, c[1] - 0.5 * width, gz + 0.18),
                Vector3::new(c[0] + 0.5 * length, c[1] + 0.5 * width, gz + 0.95),
            );
            let cab_len = length * rng.range(0.48, 0.58);
            let cab_c = c[0] - side * 0.08 * length;
            let cabin = Aabb::new(
                Vector3::new(cab_c - 0.5 * cab_len, c[1] - 0.5 * width + 0.08, gz + 0.95),
                Vector3::new(
                    cab_c + 0.5 * cab_len,
                    c[1] + 0.5 * width - 0.08,
                    gz + height,
                ),
            );
            objects.push(Object::new(
                Shape::Box(body),
                Material::CarBody { rgb },
                epochs,
            ));
            objects.push(Object::new(
                Shape::Box(cabin),
                Material::CarCabin { rgb },
                epochs,
            ));
            cars.push(Car {
                centre_local: c,
                ground_z_m: gz,
                length_m: length,
                width_m: width,
                height_m: height,
                along_x: true,
                epochs,
                rgb,
            });
        }
    }
    cars
}
