//! Surface classification and shading of scene hits: which `SurfaceKind` a hit is, its procedural
//! albedo, and the lighting `albedo · (E_sun · max(0, n·s) · visible + E_sky · (0.6 + 0.4·n_z))`.

use super::ground::GroundClass;
use super::markings::{GroundMark, StreetAxis, MANHOLE_RADIUS_M};
use super::objects::Material;
use super::{Epoch, HitWhat, LocalHit, Scene, SurfaceKind, SHADOW_EPS_M};
use crate::synth::texture::{self, FacadeLook};
use nalgebra::Vector3;

/// Sun irradiance (linear RGB) on a surface facing the sun.
const SUN_RGB: [f32; 3] = [0.80, 0.77, 0.71];
/// Sky (ambient) irradiance on an upward-facing surface.
const SKY_RGB: [f32; 3] = [0.26, 0.29, 0.35];
/// Fresh asphalt of roadworks is this much darker than the worn road.
const FRESH_ASPHALT: f32 = 0.55;
/// Albedo of the plain grey ground of markers-only scenes.
const PLAIN_GREY: f32 = 0.5;

impl Scene {
    /// The mark (paint, manhole, roadworks) on the carriageway at local (x, y) in `epoch`, with the street
    /// coordinates used.
    fn mark_at(&self, x: f64, y: f64, epoch: Epoch) -> (GroundMark, f64, f64) {
        for r in &self.roadworks {
            let (s, q) = self.streets[r.street].axis.to_sq(x, y);
            if r.epochs & epoch.bit() != 0 && r.contains(s, q) {
                return (GroundMark::Roadworks, s, q);
            }
        }
        for st in &self.streets {
            let (s, q) = st.axis.to_sq(x, y);
            let m = st.mark_at(s, q, epoch.bit());
            if m != GroundMark::None {
                return (m, s, q);
            }
        }
        (GroundMark::None, x, y)
    }

    /// Street coordinates of the nearest street for paving orientation.
    fn paving_coords(&self, x: f64, y: f64) -> (f64, f64) {
        if let Some(st) = self.streets.get(1) {
            if let StreetAxis::AlongY { crown_x } = st.axis {
                if (x - crown_x).abs() < y.abs() {
                    return st.axis.to_sq(x, y);
                }
            }
        }
        (x, y)
    }

    pub(crate) fn surface_kind(&self, h: &LocalHit, epoch: Epoch) -> SurfaceKind {
        match h.what {
            HitWhat::Ground { face: true, .. } => SurfaceKind::Kerb,
            HitWhat::Ground { class, .. } => {
                if self.plain_ground {
                    return SurfaceKind::Road;
                }
                match class {
                    GroundClass::Road => match self.mark_at(h.p.x, h.p.y, epoch).0 {
                        GroundMark::Paint => SurfaceKind::Marking,
                        _ => SurfaceKind::Road,
                    },
                    GroundClass::Water => SurfaceKind::Water,
                    GroundClass::Raised => {
                        let d = self.ground.distance_behind_kerb(h.p.x, h.p.y);
                        if d < self.kerb_band_m {
                            SurfaceKind::Kerb
                        } else if d < self.sidewalk_width_m {
                            SurfaceKind::Sidewalk
                        } else {
                            SurfaceKind::Grass
                        }
                    }
                }
            }
            HitWhat::Object(k) => match self.objects[k as usize].material {
                Material::Building { building } => {
                    if h.n.z > 0.5 {
                        SurfaceKind::Roof { building }
                    } else {
                        SurfaceKind::Facade { building }
                    }
                }
                Material::Balcony { building } => SurfaceKind::Facade { building },
                Material::RoofUnit { building } => SurfaceKind::Roof { building },
                Material::GableRoof { building } => {
                    if h.n.z.abs() < 1e-6 {
                        SurfaceKind::Facade { building }
                    } else {
                        SurfaceKind::Roof { building }
                    }
                }
                Material::Leaves { .. } | Material::Trunk => SurfaceKind::Tree,
                Material::CarBody { .. } | Material::CarCabin { .. } => SurfaceKind::Car,
                Material::Marker { .. } => SurfaceKind::Marker,
            },
        }
    }

    fn facade_albedo(&self, building: u32, p: &Vector3<f64>, n: &Vector3<f64>) -> [f32; 3] {
        let b = &self.buildings[building as usize];
        let look = FacadeLook {
            wall_rgb: b.wall_rgb,
            frame_rgb: b.frame_rgb,
            brick: b.brick,
            storey_height_m: b.storey_height_m,
            storeys: b.storeys,
            bay_m: b.bay_m,
            window_w_m: b.window_w_m,
            window_h_m: b.window_h_m,
            sill_m: b.sill_m,
            door_bay: b.door_bay,
            seed: b.seed,
        };
        let front = b.front_normal_local;
        let v = p.z - b.floor0_z_m;
        let is_front = n.x * front[0] + n.y * front[1] > 0.9;
        let u = if front[1].abs() > 0.5 {
            p.x - b.footprint_min_local[0]
        } else {
            p.y - b.footprint_min_local[1]
        };
        if is_front {
            texture::facade(u, v, &look)
        } else {
            // side and back walls: wall material, fewer windows (use a sparser look)
            let u_side = if n.x.abs() > 0.5 { p.y } else { p.x };
            let sparse = FacadeLook {
                bay_m: look.bay_m * 2.0,
                door_bay: u32::MAX,
                ..look
            };
            texture::facade(
                u_side - b.footprint_min_local[0].min(b.footprint_min_local[1]),
                v,
                &sparse,
            )
        }
    }

    fn albedo(&self, h: &LocalHit, epoch: Epoch) -> [f32; 3] {
        let seed = self.texture_seed;
        let p = &h.p;
        match h.what {
            HitWhat::Ground { face: true, class } => {
                if class == GroundClass::Water {
                    texture::water(p.x, p.y, seed)
                } else {
                    texture::kerb(p.x, p.y, p.z, seed)
                }
            }
            HitWhat::Ground { class, .. } => {
                if self.plain_ground {
                    return [PLAIN_GREY; 3];
                }
                match class {
                    GroundClass::Road => match self.mark_at(p.x, p.y, epoch) {
                        (GroundMark::Paint, _, _) => texture::paint(p.x, p.y, seed),
                        (GroundMark::Manhole { ds, dq }, _, _) => {
                            texture::manhole(ds, dq, MANHOLE_RADIUS_M, seed)
                        }
                        (GroundMark::Roadworks, _, _) => {
                            texture::asphalt(p.x, p.y, seed ^ 0x4E57).map(|v| v * FRESH_ASPHALT)
                        }
                        _ => texture::asphalt(p.x, p.y, seed),
                    },
                    GroundClass::Water => texture::water(p.x, p.y, seed),
                    GroundClass::Raised => {
                        let d = self.ground.distance_behind_kerb(p.x, p.y);
                        if d < self.kerb_band_m {
                            texture::kerb(p.x, p.y, p.z, seed)
                        } else if d < self.sidewalk_width_m {
                            let (s, q) = self.paving_coords(p.x, p.y);
                            texture::paving(s, q, seed)
                        } else {
                            texture::grass(p.x, p.y, seed)
                        }
                    }
                }
            }
            HitWhat::Object(k) => match self.objects[k as usize].material {
                Material::Building { building } => {
                    if h.n.z > 0.5 {
                        let b = &self.buildings[building as usize];
                        let (lo, hi) = (b.footprint_min_local, b.footprint_max_local);
                        let edge = (p.x - lo[0])
                            .min(hi[0] - p.x)
                            .min(p.y - lo[1])
                            .min(hi[1] - p.y);
                        if edge < 0.3 {
                            texture::roof_coping(p.x, p.y, b.seed)
                        } else {
                            texture::roof(b.roof_rgb, p.x, p.y, false, b.seed)
                        }
                    } else {
                        self.facade_albedo(building, p, &h.n)
                    }
                }
                Material::RoofUnit { building } => {
                    let b = &self.buildings[building as usize];
                    texture::metal(p.x, p.y, p.z, b.seed)
                }
                Material::Balcony { building } => {
                    let b = &self.buildings[building as usize];
                    let k = 0.9
                        + 0.1
                            * crate::synth::noise::value3(p.x * 4.0, p.y * 4.0, p.z * 4.0, b.seed);
                    [
                        b.frame_rgb[0] * 0.8 * k,
                        b.frame_rgb[1] * 0.8 * k,
                        b.frame_rgb[2] * 0.8 * k,
                    ]
                }
                Material::GableRoof { building } => {
                    let b = &self.buildings[building as usize];
                    if h.n.z.abs() < 1e-6 {
                        self.facade_albedo(building, p, &h.n)
                    } else {
                        let along_x = (b.footprint_max_local[0] - b.footprint_min_local[0]).abs()
                            > 0.0
                            && h.n.x.abs() < h.n.y.abs();
                        let (along, across) = if along_x { (p.x, p.z) } else { (p.y, p.z) };
                        texture::roof(b.roof_rgb, along, across * 1.4, true, b.seed)
                    }
                }
                Material::Leaves { seed } => texture::leaves(p.x, p.y, p.z, seed),
                Material::Trunk => texture::bark(p.x, p.y, p.z, seed),
                Material::CarBody { rgb } => texture::car_paint(rgb, p.x, p.y, p.z, seed),
                Material::CarCabin { rgb } => {
                    // windows all round except a thin roof rim
                    if h.n.z > 0.5 {
                        texture::car_paint(rgb, p.x, p.y, p.z, seed)
                    } else {
                        [0.04, 0.05, 0.06]
                    }
                }
                Material::Marker { rgb } => rgb,
            },
        }
    }

    /// Shade a hit seen along local direction `d` in `epoch`.
    pub(crate) fn shade(&self, h: &LocalHit, d: &Vector3<f64>, epoch: Epoch) -> [f32; 3] {
        if let HitWhat::Object(k) = h.what {
            if let Material::Marker { rgb } = self.objects[k as usize].material {
                return rgb;
            }
        }
        // normal facing the viewer
        let n = if h.n.dot(d) > 0.0 { -h.n } else { h.n };
        let albedo = self.albedo(h, epoch);
        let sun = &self.sun_local[epoch.index()];
        let cos_s = n.dot(sun);
        let mut direct = 0.0f32;
        if cos_s > 0.0 {
            let o = h.p + n * SHADOW_EPS_M;
            if !self.occluded_local(&o, sun, epoch) {
                direct = cos_s as f32;
            }
        }
        let sky = 0.6 + 0.4 * n.z as f32;
        let mut out = [0.0f32; 3];
        for c in 0..3 {
            out[c] = albedo[c] * (SUN_RGB[c] * direct + SKY_RGB[c] * sky);
        }
        out
    }
}
