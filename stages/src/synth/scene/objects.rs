//! Scene objects above the ground (buildings, balconies, roofs, trees, cars, markers): shape, what they
//! are made of, in which epochs they exist, and the ray test that includes the see-through holes of
//! tree crowns.

use super::shapes::{
    cylinder_hit, ellipsoid_normal, ellipsoid_roots, sphere_hit, Aabb, ConvexPrism, Ray,
};
use crate::synth::noise::value3;
use nalgebra::Vector3;

/// Geometric shape (local frame).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Shape {
    Box(Aabb),
    Prism(ConvexPrism),
    /// Tree crown: axis-aligned ellipsoid with noise-driven holes.
    Crown {
        centre: Vector3<f64>,
        inv_r: Vector3<f64>,
        hole_seed: u64,
    },
    Cylinder {
        cx: f64,
        cy: f64,
        r: f64,
        z0: f64,
        z1: f64,
    },
    Sphere {
        centre: Vector3<f64>,
        r: f64,
    },
}

/// What an object is made of (drives SurfaceKind and texture).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Material {
    /// Building body: vertical faces are façade, the top (flat roof) is roof.
    Building {
        building: u32,
    },
    /// Protrusion (balcony/oriel) of a building's façade.
    /// Rooftop unit (air conditioner, lift housing) on a flat roof: counts as roof.
    RoofUnit {
        building: u32,
    },
    Balcony {
        building: u32,
    },
    /// Gable roof of a building.
    GableRoof {
        building: u32,
    },
    Leaves {
        seed: u64,
    },
    Trunk,
    CarBody {
        rgb: [f32; 3],
    },
    CarCabin {
        rgb: [f32; 3],
    },
    Marker {
        rgb: [f32; 3],
    },
}

/// Epoch presence bits.
pub const IN_MM: u8 = 1;
pub const IN_AERIAL: u8 = 2;
pub const IN_BOTH: u8 = IN_MM | IN_AERIAL;

/// One object.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Object {
    pub shape: Shape,
    pub bounds: Aabb,
    pub material: Material,
    pub epochs: u8,
    /// Parts of a compound (a building's roof, balconies) are the objects at indices
    /// `self_index + 1 .. children_end`; `bounds` then encloses them all. 0 = no parts.
    pub children_end: u32,
    /// This object is a part of a compound (not entered into the acceleration grid itself).
    pub is_child: bool,
}

/// Fraction of a crown's surface that is a see-through hole is set by this threshold on 3-D value noise.
const CROWN_HOLE_THRESHOLD: f32 = -0.38;
/// Spatial frequency of the crown hole pattern, 1/m.
const CROWN_HOLE_FREQ: f64 = 1.3;

impl Object {
    pub fn new(shape: Shape, material: Material, epochs: u8) -> Self {
        let bounds = match shape {
            Shape::Box(b) => b,
            Shape::Prism(p) => {
                // prisms are built from a footprint box: recover bounds from the planes is awkward, so
                // callers use `with_bounds`; this fallback is a degenerate box at the origin.
                let _ = p;
                Aabb::new(Vector3::zeros(), Vector3::zeros())
            }
            Shape::Crown { centre, inv_r, .. } => {
                let r = Vector3::new(1.0 / inv_r.x, 1.0 / inv_r.y, 1.0 / inv_r.z);
                Aabb::new(centre - r, centre + r)
            }
            Shape::Cylinder { cx, cy, r, z0, z1 } => Aabb::new(
                Vector3::new(cx - r, cy - r, z0),
                Vector3::new(cx + r, cy + r, z1),
            ),
            Shape::Sphere { centre, r } => {
                Aabb::new(centre - Vector3::repeat(r), centre + Vector3::repeat(r))
            }
        };
        Self::with_bounds(shape, bounds, material, epochs)
    }

    pub fn with_bounds(shape: Shape, bounds: Aabb, material: Material, epochs: u8) -> Self {
        Self {
            shape,
            bounds,
            material,
            epochs,
            children_end: 0,
            is_child: false,
        }
    }

    /// Mark as a part of a compound.
    pub fn as_child(mut self) -> Self {
        self.is_child = true;
        self
    }

    /// Is the crown surface at p a hole?
    #[inline]
    fn crown_hole(p: &Vector3<f64>, seed: u64) -> bool {
        value3(
            p.x * CROWN_HOLE_FREQ,
            p.y * CROWN_HOLE_FREQ,
            p.z * CROWN_HOLE_FREQ,
            seed,
        ) < CROWN_HOLE_THRESHOLD
    }

    /// Nearest hit (t, normal facing the ray's origin side) in (t_min, t_max).
    #[inline]
    pub fn hit(&self, ray: &Ray, t_min: f64, t_max: f64) -> Option<(f64, Vector3<f64>)> {
        let (o, d) = (&ray.o, &ray.d);
        match &self.shape {
            Shape::Box(b) => b.hit(ray, t_min, t_max),
            Shape::Prism(p) => p.hit(ray, t_min, t_max),
            Shape::Crown {
                centre,
                inv_r,
                hole_seed,
            } => {
                let (t0, t1) = ellipsoid_roots(centre, inv_r, o, d)?;
                for (t, front) in [(t0, true), (t1, false)] {
                    if t > t_min && t < t_max {
                        let p = o + d * t;
                        if !Self::crown_hole(&p, *hole_seed) {
                            let n = ellipsoid_normal(centre, inv_r, &p);
                            return Some((t, if front { n } else { -n }));
                        }
                    }
                }
                None
            }
            Shape::Cylinder { cx, cy, r, z0, z1 } => {
                cylinder_hit(*cx, *cy, *r, *z0, *z1, o, d, t_min, t_max)
            }
            Shape::Sphere { centre, r } => sphere_hit(centre, *r, o, d, t_min, t_max),
        }
    }
}
