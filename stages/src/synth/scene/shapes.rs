//! Analytic ray/shape intersections in the local frame: axis-aligned box, convex prism (gable roofs),
//! ellipsoid, vertical cylinder, sphere. Each returns the nearest t in (t_min, t_max) and the outward
//! normal of the surface hit (for closed shapes seen from outside).

use nalgebra::Vector3;

/// A ray in the local frame with its component-wise reciprocal direction (±inf allowed) for slab tests.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Ray {
    pub o: Vector3<f64>,
    pub d: Vector3<f64>,
    pub inv_d: Vector3<f64>,
}

impl Ray {
    pub fn new(o: Vector3<f64>, d: Vector3<f64>) -> Self {
        let inv_d = Vector3::new(1.0 / d.x, 1.0 / d.y, 1.0 / d.z);
        Self { o, d, inv_d }
    }
}

/// Axis-aligned box.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Aabb {
    pub min: Vector3<f64>,
    pub max: Vector3<f64>,
}

impl Aabb {
    pub fn new(min: Vector3<f64>, max: Vector3<f64>) -> Self {
        Self { min, max }
    }

    pub fn union(&self, o: &Aabb) -> Aabb {
        Aabb {
            min: self.min.inf(&o.min),
            max: self.max.sup(&o.max),
        }
    }

    /// Entry and exit t of the ray (slab method); `None` when it misses or the interval is outside
    /// (t_min, t_max). `inv_d` = component-wise 1/d (±inf allowed).
    #[inline]
    pub fn clip(
        &self,
        o: &Vector3<f64>,
        inv_d: &Vector3<f64>,
        t_min: f64,
        t_max: f64,
    ) -> Option<(f64, f64)> {
        let mut t0 = t_min;
        let mut t1 = t_max;
        for i in 0..3 {
            let mut ta = (self.min[i] - o[i]) * inv_d[i];
            let mut tb = (self.max[i] - o[i]) * inv_d[i];
            if ta.is_nan() || tb.is_nan() {
                // ray parallel to the slab and exactly on its boundary plane: treat as inside if within
                if o[i] < self.min[i] || o[i] > self.max[i] {
                    return None;
                }
                continue;
            }
            if ta > tb {
                std::mem::swap(&mut ta, &mut tb);
            }
            t0 = t0.max(ta);
            t1 = t1.min(tb);
            if t0 > t1 {
                return None;
            }
        }
        Some((t0, t1))
    }

    /// Nearest surface hit (t, outward normal) in (t_min, t_max), ray starting outside.
    #[inline]
    pub fn hit(&self, ray: &Ray, t_min: f64, t_max: f64) -> Option<(f64, Vector3<f64>)> {
        let (o, d, inv_d) = (&ray.o, &ray.d, &ray.inv_d);
        let mut t_enter = f64::NEG_INFINITY;
        let mut axis = 0;
        let mut t_exit = f64::INFINITY;
        for i in 0..3 {
            if d[i] == 0.0 {
                if o[i] < self.min[i] || o[i] > self.max[i] {
                    return None;
                }
                continue;
            }
            let ta = (self.min[i] - o[i]) * inv_d[i];
            let tb = (self.max[i] - o[i]) * inv_d[i];
            let (tn, tf) = if ta < tb { (ta, tb) } else { (tb, ta) };
            if tn > t_enter {
                t_enter = tn;
                axis = i;
            }
            t_exit = t_exit.min(tf);
        }
        if t_enter > t_exit || t_enter <= t_min || t_enter >= t_max {
            return None;
        }
        let mut n = Vector3::zeros();
        n[axis] = if d[axis] > 0.0 { -1.0 } else { 1.0 };
        Some((t_enter, n))
    }
}

/// Convex polytope given by up to 6 half-spaces `n·p ≤ c` (unit outward normals).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ConvexPrism {
    pub planes: [(Vector3<f64>, f64); 6],
    pub n_planes: usize,
}

impl ConvexPrism {
    /// A gable roof over the box footprint [min, max] (XY), eaves at `eave_z`, ridge at `ridge_z`,
    /// ridge along x when `ridge_along_x`.
    pub fn gable(
        min: [f64; 2],
        max: [f64; 2],
        eave_z: f64,
        ridge_z: f64,
        ridge_along_x: bool,
    ) -> Self {
        let z = Vector3::z();
        let mut planes = [(z, 0.0); 6];
        let rise = ridge_z - eave_z;
        let (a, b, i, j) = if ridge_along_x {
            (min[1], max[1], 1, 0)
        } else {
            (min[0], max[0], 0, 1)
        };
        let half = 0.5 * (b - a);
        let mid = 0.5 * (a + b);
        // sloped planes: z − eave ≤ rise·(1 − |u − mid|/half)  ⇔  (±rise/half)·u + z ≤ …
        for (k, s) in [1.0f64, -1.0].into_iter().enumerate() {
            let mut n = Vector3::zeros();
            n[i] = s * rise / half;
            n[2] = 1.0;
            let c = eave_z + rise + s * rise / half * mid;
            let len = n.norm();
            planes[k] = (n / len, c / len);
        }
        planes[2] = (-z, -eave_z);
        let mut e = Vector3::zeros();
        e[j] = 1.0;
        planes[3] = (e, if ridge_along_x { max[0] } else { max[1] });
        planes[4] = (-e, -(if ridge_along_x { min[0] } else { min[1] }));
        Self {
            planes,
            n_planes: 5,
        }
    }

    /// Nearest hit from outside (Kay–Kajiya).
    #[inline]
    pub fn hit(&self, ray: &Ray, t_min: f64, t_max: f64) -> Option<(f64, Vector3<f64>)> {
        let (o, d) = (&ray.o, &ray.d);
        let mut t_enter = f64::NEG_INFINITY;
        let mut n_enter = Vector3::zeros();
        let mut t_exit = f64::INFINITY;
        for &(n, c) in &self.planes[..self.n_planes] {
            let dn = n.dot(d);
            let dist = c - n.dot(o); // > 0 inside
            if dn.abs() < 1e-15 {
                if dist < 0.0 {
                    return None;
                }
                continue;
            }
            let t = dist / dn;
            if dn < 0.0 {
                if t > t_enter {
                    t_enter = t;
                    n_enter = n;
                }
            } else {
                t_exit = t_exit.min(t);
            }
        }
        if t_enter > t_exit || t_enter <= t_min || t_enter >= t_max {
            return None;
        }
        Some((t_enter, n_enter))
    }
}

/// Ray/ellipsoid (axis-aligned radii): both roots (t_near, t_far) if the ray meets the surface.
#[inline]
pub fn ellipsoid_roots(
    c: &Vector3<f64>,
    inv_r: &Vector3<f64>,
    o: &Vector3<f64>,
    d: &Vector3<f64>,
) -> Option<(f64, f64)> {
    let oc = (o - c).component_mul(inv_r);
    let dd = d.component_mul(inv_r);
    let a = dd.dot(&dd);
    let b = oc.dot(&dd);
    let cc = oc.dot(&oc) - 1.0;
    let disc = b * b - a * cc;
    if disc < 0.0 {
        return None;
    }
    let sq = disc.sqrt();
    // numerically stable roots
    let q = if b > 0.0 { -(b + sq) } else { -b + sq };
    let (t1, t2) = if q == 0.0 {
        (0.0, 0.0)
    } else {
        (q / a, cc / q)
    };
    Some(if t1 < t2 { (t1, t2) } else { (t2, t1) })
}

/// Outward normal of an axis-aligned ellipsoid at surface point p.
#[inline]
pub fn ellipsoid_normal(c: &Vector3<f64>, inv_r: &Vector3<f64>, p: &Vector3<f64>) -> Vector3<f64> {
    (p - c)
        .component_mul(inv_r)
        .component_mul(inv_r)
        .normalize()
}

/// Ray/sphere nearest hit from outside.
#[inline]
pub fn sphere_hit(
    c: &Vector3<f64>,
    r: f64,
    o: &Vector3<f64>,
    d: &Vector3<f64>,
    t_min: f64,
    t_max: f64,
) -> Option<(f64, Vector3<f64>)> {
    let inv = Vector3::repeat(1.0 / r);
    let (t0, t1) = ellipsoid_roots(c, &inv, o, d)?;
    let t = if t0 > t_min { t0 } else { t1 };
    if t <= t_min || t >= t_max {
        return None;
    }
    let p = o + d * t;
    Some((t, (p - c) / r))
}

/// Vertical cylinder (axis through (cx, cy), radius r, from z0 to z1): nearest hit on the side or caps.
/// The shape's five numbers and the ray's four are passed flat, like the other `*_hit` primitives, because
/// this runs per ray and per object in the renderer's inner loop.
#[inline]
#[allow(clippy::too_many_arguments)]
pub fn cylinder_hit(
    cx: f64,
    cy: f64,
    r: f64,
    z0: f64,
    z1: f64,
    o: &Vector3<f64>,
    d: &Vector3<f64>,
    t_min: f64,
    t_max: f64,
) -> Option<(f64, Vector3<f64>)> {
    let (ox, oy) = (o.x - cx, o.y - cy);
    let a = d.x * d.x + d.y * d.y;
    let mut best: Option<(f64, Vector3<f64>)> = None;
    if a > 1e-18 {
        let b = ox * d.x + oy * d.y;
        let c = ox * ox + oy * oy - r * r;
        let disc = b * b - a * c;
        if disc >= 0.0 {
            let t = (-b - disc.sqrt()) / a;
            if t > t_min && t < t_max {
                let z = o.z + t * d.z;
                if z >= z0 && z <= z1 {
                    let n = Vector3::new((ox + t * d.x) / r, (oy + t * d.y) / r, 0.0);
                    best = Some((t, n));
                }
            }
        }
    }
    if d.z != 0.0 {
        for (zc, nz) in [(z0, -1.0), (z1, 1.0)] {
            let t = (zc - o.z) / d.z;
            if t > t_min && t < t_max && best.is_none_or(|b| t < b.0) && (d.z * nz) < 0.0 {
                let (x, y) = (ox + t * d.x, oy + t * d.y);
                if x * x + y * y <= r * r {
                    best = Some((t, Vector3::new(0.0, 0.0, nz)));
                }
            }
        }
    }
    best
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn box_hit_distance_and_normal() {
        let b = Aabb::new(Vector3::new(1.0, -1.0, 0.0), Vector3::new(3.0, 1.0, 2.0));
        let o = Vector3::new(0.0, 0.0, 1.0);
        let d = Vector3::new(1.0, 0.0, 0.0);
        let (t, n) = b.hit(&Ray::new(o, d), 0.0, f64::INFINITY).unwrap();
        assert!((t - 1.0).abs() < 1e-12);
        assert_eq!(n, Vector3::new(-1.0, 0.0, 0.0));
        let d = Vector3::new(0.0, 1.0, 0.0);
        assert!(b.hit(&Ray::new(o, d), 0.0, f64::INFINITY).is_none());
    }

    #[test]
    fn gable_roof_ridge_height_and_slope_normal() {
        let g = ConvexPrism::gable([0.0, 0.0], [10.0, 8.0], 10.0, 13.0, true);
        // Straight down from z = 50 at (x, y): the height hit and the normal there.
        let down = |x: f64, y: f64| {
            let ray = Ray::new(Vector3::new(x, y, 50.0), Vector3::new(0.0, 0.0, -1.0));
            g.hit(&ray, 0.0, f64::INFINITY).map(|(t, n)| (50.0 - t, n))
        };
        // over the ridge line (y = 4) the roof is at z = 13
        let (z, _) = down(5.0, 4.0).unwrap();
        assert!((z - 13.0).abs() < 1e-9);
        // at y = 2 (half-way down the slope) z = 11.5, normal tilted towards −y
        let (z, n) = down(5.0, 2.0).unwrap();
        assert!((z - 11.5).abs() < 1e-9);
        assert!(n.y < -0.5 && n.z > 0.5);
        // outside the footprint: miss
        assert!(down(11.0, 2.0).is_none());
    }

    #[test]
    fn ellipsoid_sphere_cylinder() {
        let c = Vector3::new(0.0, 0.0, 5.0);
        let (t0, t1) = ellipsoid_roots(
            &c,
            &Vector3::new(0.5, 0.5, 1.0 / 3.0),
            &Vector3::new(-10.0, 0.0, 5.0),
            &Vector3::x(),
        )
        .unwrap();
        assert!((t0 - 8.0).abs() < 1e-12 && (t1 - 12.0).abs() < 1e-12);
        let (t, n) = sphere_hit(
            &c,
            1.0,
            &Vector3::new(0.0, 0.0, 0.0),
            &Vector3::z(),
            0.0,
            f64::INFINITY,
        )
        .unwrap();
        assert!((t - 4.0).abs() < 1e-12 && (n.z + 1.0).abs() < 1e-12);
        // Along +x at height z into the upright cylinder of radius 0.5 at (2, 0) from z = 0 to 3.
        let along_x_at = |z: f64| {
            cylinder_hit(
                2.0,
                0.0,
                0.5,
                0.0,
                3.0,
                &Vector3::new(0.0, 0.0, z),
                &Vector3::x(),
                0.0,
                f64::INFINITY,
            )
        };
        let (t, n) = along_x_at(1.0).unwrap();
        assert!((t - 1.5).abs() < 1e-12 && (n.x + 1.0).abs() < 1e-12);
        assert!(along_x_at(3.5).is_none());
    }
}
