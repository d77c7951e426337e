//! The ground: a piecewise-planar height field in the street-local frame with vertical steps (kerbs,
//! quay walls), and its exact ray intersection.
//!
//! Height model (local metres): `base(x, y) = z0 + gx·x + gy·y` (longitudinal slopes). Carriageways fall
//! from their crown line with the cross-fall `cf`: `h = base − cf·d`, `d` = distance to the nearest active
//! crown line (`|y|` for the main street, `|x − xj|` for the cross street, the minimum inside the junction —
//! continuous, piecewise planar). Everything outside the carriageways is raised by the kerb height:
//! `h = base − cf·hw + kerb`; a canal lies `drop` below that.
//!
//! Intersection: the ray's XY projection is cut at every line where the planar piece may change (crowns,
//! kerb lines, junction diagonals, canal edges); inside each interval the height is one plane, solved
//! exactly; at each cut a jump up in height that the ray passes under is a vertical face (kerb/quay wall).

use nalgebra::Vector3;

/// What kind of ground a point belongs to (before markings/kerb bands are looked up).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum GroundClass {
    Road,
    Raised,
    Water,
}

/// `h = a + b·x + c·y` (local frame).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Plane {
    pub a: f64,
    pub b: f64,
    pub c: f64,
}

impl Plane {
    #[inline]
    pub fn height(&self, x: f64, y: f64) -> f64 {
        self.a + self.b * x + self.c * y
    }
    #[inline]
    pub fn normal(&self) -> Vector3<f64> {
        Vector3::new(-self.b, -self.c, 1.0).normalize()
    }
}

/// A line `nx·x + ny·y = c` in the local XY plane (unit normal).
#[derive(Clone, Copy, Debug)]
struct Line {
    nx: f64,
    ny: f64,
    c: f64,
}

/// A ground intersection in the local frame.
#[derive(Clone, Copy, Debug)]
pub struct GroundHit {
    pub t: f64,
    pub normal_local: Vector3<f64>,
    pub class: GroundClass,
    /// The hit is on a vertical step face (kerb or quay wall).
    pub vertical_face: bool,
}

const MAX_LINES: usize = 12;

/// The shape of a street's ground: the sloped base plane, the carriageway's crown and kerbs, an optional cross
/// street and canal.
#[derive(Clone, Copy, Debug)]
pub struct StreetShape {
    /// Height of the base plane at the local origin, m.
    pub z0: f64,
    /// Slope of the base plane along local x and y.
    pub gx: f64,
    pub gy: f64,
    /// Fall of the carriageway from its crown towards the kerbs (height per metre).
    pub crossfall: f64,
    /// Kerb height, m.
    pub kerb_m: f64,
    /// Half width of the main carriageway, m.
    pub half_width_m: f64,
    /// (x of crown, half width, y_min, y_max) of the cross street.
    pub cross: Option<(f64, f64, f64, f64)>,
    /// (y_lo, y_hi, drop) of the canal.
    pub canal: Option<(f64, f64, f64)>,
}

/// The ground height field (local frame).
#[derive(Clone, Debug)]
pub struct Ground {
    shape: StreetShape,
    /// Flat ground: no carriageway at all (everything "Raised" at z0 + slopes).
    flat: bool,
    lines: [Line; MAX_LINES],
    n_lines: usize,
    /// Bounds of `h − base` over the whole plane (relief above/below the sloped base plane), m.
    relief_max_m: f64,
    /// |∇base|, the base plane's slope.
    base_slope: f64,
}

impl Ground {
    /// The ground of a street of `shape`.
    pub fn street(shape: StreetShape) -> Self {
        let StreetShape {
            gx,
            gy,
            crossfall,
            kerb_m,
            half_width_m,
            cross,
            canal,
            ..
        } = shape;
        let mut g = Self {
            shape,
            flat: false,
            lines: [Line {
                nx: 0.0,
                ny: 1.0,
                c: 0.0,
            }; MAX_LINES],
            n_lines: 0,
            relief_max_m: (kerb_m - crossfall * half_width_m).max(0.0),
            base_slope: (gx * gx + gy * gy).sqrt(),
        };
        let mut push = |nx: f64, ny: f64, c: f64| {
            let n = (nx * nx + ny * ny).sqrt();
            g.lines[g.n_lines] = Line {
                nx: nx / n,
                ny: ny / n,
                c: c / n,
            };
            g.n_lines += 1;
        };
        push(0.0, 1.0, 0.0);
        push(0.0, 1.0, half_width_m);
        push(0.0, 1.0, -half_width_m);
        if let Some((xj, hwc, y0, y1)) = cross {
            push(1.0, 0.0, xj);
            push(1.0, 0.0, xj - hwc);
            push(1.0, 0.0, xj + hwc);
            push(-1.0, 1.0, -xj); // y = x − xj
            push(1.0, 1.0, xj); // y = −(x − xj)
            if y0.is_finite() && y0 != 0.0 {
                push(0.0, 1.0, y0);
            }
            if y1.is_finite() && y1 != 0.0 {
                push(0.0, 1.0, y1);
            }
        }
        if let Some((lo, hi, _)) = canal {
            push(0.0, 1.0, lo);
            push(0.0, 1.0, hi);
        }
        g
    }

    /// A flat, sloped-free plane at height `z` (no carriageway, no kerbs).
    pub fn flat(z: f64) -> Self {
        let mut g = Self::street(StreetShape {
            z0: z,
            gx: 0.0,
            gy: 0.0,
            crossfall: 0.0,
            kerb_m: 0.0,
            half_width_m: 0.0,
            cross: None,
            canal: None,
        });
        g.flat = true;
        g.n_lines = 0;
        g
    }

    #[inline]
    fn cross_active(&self, x: f64, y: f64) -> Option<f64> {
        match self.shape.cross {
            Some((xj, _, y0, y1)) if y > y0 && y < y1 => Some(x - xj),
            _ => None,
        }
    }

    /// Is (x, y) on a carriageway?
    #[inline]
    pub fn on_road(&self, x: f64, y: f64) -> bool {
        if self.flat {
            return false;
        }
        if y.abs() < self.shape.half_width_m {
            return true;
        }
        match self.shape.cross {
            Some((xj, hwc, y0, y1)) => (x - xj).abs() < hwc && y > y0 && y < y1,
            None => false,
        }
    }

    /// Distance from (x, y) to the nearest kerb line, for points off the carriageway (0 on it).
    pub fn distance_behind_kerb(&self, x: f64, y: f64) -> f64 {
        if self.flat {
            return f64::INFINITY;
        }
        if self.on_road(x, y) {
            return 0.0;
        }
        let mut d = y.abs() - self.shape.half_width_m;
        if let Some((xj, hwc, y0, y1)) = self.shape.cross {
            if y > y0 && y < y1 {
                d = d.min((x - xj).abs() - hwc);
            }
        }
        d.max(0.0)
    }

    /// The planar piece and its class at (x, y).
    #[inline]
    pub fn piece(&self, x: f64, y: f64) -> (Plane, GroundClass) {
        let raised = Plane {
            a: self.shape.z0 - self.shape.crossfall * self.shape.half_width_m + self.shape.kerb_m,
            b: self.shape.gx,
            c: self.shape.gy,
        };
        if self.flat {
            return (
                Plane {
                    a: self.shape.z0,
                    b: self.shape.gx,
                    c: self.shape.gy,
                },
                GroundClass::Raised,
            );
        }
        if self.on_road(x, y) {
            let ay = y.abs();
            if let Some(dx) = self.cross_active(x, y) {
                if dx.abs() < ay {
                    let s = if dx >= 0.0 { 1.0 } else { -1.0 };
                    let xj = x - dx;
                    return (
                        Plane {
                            a: self.shape.z0 + self.shape.crossfall * s * xj,
                            b: self.shape.gx - self.shape.crossfall * s,
                            c: self.shape.gy,
                        },
                        GroundClass::Road,
                    );
                }
            }
            let s = if y >= 0.0 { 1.0 } else { -1.0 };
            return (
                Plane {
                    a: self.shape.z0,
                    b: self.shape.gx,
                    c: self.shape.gy - self.shape.crossfall * s,
                },
                GroundClass::Road,
            );
        }
        if let Some((lo, hi, drop)) = self.shape.canal {
            if y > lo && y < hi {
                return (
                    Plane {
                        a: raised.a - drop,
                        ..raised
                    },
                    GroundClass::Water,
                );
            }
        }
        (raised, GroundClass::Raised)
    }

    /// Ground height at local (x, y).
    #[inline]
    pub fn height(&self, x: f64, y: f64) -> f64 {
        self.piece(x, y).0.height(x, y)
    }

    /// Lowest and highest ground height over a local XY box (exact for planar pieces: evaluated at the
    /// corners of every piece boundary is overkill; a bound from the slopes is enough for culling).
    pub fn height_bounds(&self, min: [f64; 2], max: [f64; 2]) -> (f64, f64) {
        let mut lo = f64::INFINITY;
        let mut hi = f64::NEG_INFINITY;
        for x in [min[0], max[0]] {
            for y in [min[1], max[1]] {
                let b = self.shape.z0 + self.shape.gx * x + self.shape.gy * y;
                lo = lo.min(b);
                hi = hi.max(b);
            }
        }
        let w = self.shape.crossfall
            * self
                .shape
                .half_width_m
                .max(self.shape.cross.map_or(0.0, |c| c.1));
        let drop = self.shape.canal.map_or(0.0, |c| c.2);
        (lo - w - drop, hi + self.shape.kerb_m.max(0.0))
    }

    /// First intersection of the ray `o + t·d` (local frame) with the ground for t in (t_min, t_max).
    /// Rays that start below the ground never hit it.
    pub fn intersect(
        &self,
        o: &Vector3<f64>,
        d: &Vector3<f64>,
        t_min: f64,
        t_max: f64,
    ) -> Option<GroundHit> {
        // Cull with the bound h(p) ≤ base(o) + relief_max + |∇base|·|p − o|_xy: a hit needs
        // t·(d_z − |∇base|·|d_xy|) ≤ base(o) + relief_max − o_z.
        let (mut t_min, mut t_max) = (t_min, t_max);
        let num =
            self.shape.z0 + self.shape.gx * o.x + self.shape.gy * o.y + self.relief_max_m - o.z;
        let denom = d.z - self.base_slope * (d.x * d.x + d.y * d.y).sqrt();
        if denom >= 0.0 {
            if num < 0.0 {
                return None;
            }
            if denom > 0.0 {
                t_max = t_max.min(num / denom + 1e-9);
            }
        } else {
            t_min = t_min.max(num / denom - 1e-9);
        }
        if t_min >= t_max {
            return None;
        }
        let mut ts = [0.0f64; MAX_LINES];
        let mut idx = [0usize; MAX_LINES];
        let mut n = 0;
        for (i, l) in self.lines[..self.n_lines].iter().enumerate() {
            let denom = l.nx * d.x + l.ny * d.y;
            if denom.abs() < 1e-15 {
                continue;
            }
            let t = (l.c - (l.nx * o.x + l.ny * o.y)) / denom;
            if t > t_min && t < t_max {
                // insertion sort
                let mut k = n;
                while k > 0 && ts[k - 1] > t {
                    ts[k] = ts[k - 1];
                    idx[k] = idx[k - 1];
                    k -= 1;
                }
                ts[k] = t;
                idx[k] = i;
                n += 1;
            }
        }
        let mut ta = t_min;
        let mut prev: Option<Plane> = None;
        for k in 0..=n {
            let tb = if k < n { ts[k] } else { t_max };
            let tm = if tb.is_finite() {
                0.5 * (ta + tb)
            } else {
                ta + 1.0
            };
            let (plane, class) = self.piece(o.x + tm * d.x, o.y + tm * d.y);
            if let Some(p) = prev {
                // step face at the boundary t = ta?
                let (x, y, z) = (o.x + ta * d.x, o.y + ta * d.y, o.z + ta * d.z);
                let h_prev = p.height(x, y);
                let h_new = plane.height(x, y);
                if z >= h_prev - 1e-9 && z < h_new - 1e-9 {
                    let l = self.lines[idx[k - 1]];
                    let s = if l.nx * d.x + l.ny * d.y > 0.0 {
                        -1.0
                    } else {
                        1.0
                    };
                    return Some(GroundHit {
                        t: ta,
                        normal_local: Vector3::new(s * l.nx, s * l.ny, 0.0),
                        class: GroundClass::Raised,
                        vertical_face: true,
                    });
                }
            }
            let f0 = o.z - plane.height(o.x, o.y);
            let f1 = d.z - (plane.b * d.x + plane.c * d.y);
            if f1 < 0.0 {
                let t = -f0 / f1;
                if t >= ta && t <= tb && t > t_min && t < t_max {
                    return Some(GroundHit {
                        t,
                        normal_local: plane.normal(),
                        class,
                        vertical_face: false,
                    });
                }
            }
            prev = Some(plane);
            ta = tb;
        }
        None
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn ground() -> Ground {
        Ground::street(StreetShape {
            z0: 1.0,
            gx: 0.01,
            gy: 0.0,
            crossfall: 0.02,
            kerb_m: 0.12,
            half_width_m: 4.0,
            cross: Some((50.0, 3.0, -40.0, 40.0)),
            canal: None,
        })
    }

    #[test]
    fn heights_follow_crown_crossfall_and_kerb() {
        let g = ground();
        assert!((g.height(10.0, 0.0) - 1.1).abs() < 1e-12);
        assert!((g.height(10.0, 3.0) - (1.1 - 0.06)).abs() < 1e-12);
        assert!((g.height(10.0, -3.0) - (1.1 - 0.06)).abs() < 1e-12);
        // sidewalk: kerb 0.12 above the road edge (edge at 1.1 − 0.08)
        assert!((g.height(10.0, 5.0) - (1.1 - 0.08 + 0.12)).abs() < 1e-12);
        // junction: crown of the cross street
        assert!((g.height(50.0, 2.0) - 1.5).abs() < 1e-12);
        // continuity across the junction diagonal
        let a = g.height(51.0, 2.0 - 1e-9);
        let b = g.height(51.0, 2.0 + 1e-9);
        assert!((a - b).abs() < 1e-9);
    }

    #[test]
    fn vertical_ray_hits_at_height_and_horizontal_ray_hits_kerb_face() {
        let g = ground();
        for &(x, y) in &[(10.0, 1.3), (49.0, 2.5), (60.0, -6.0), (50.5, -20.0)] {
            let o = Vector3::new(x, y, 50.0);
            let h = g
                .intersect(&o, &Vector3::new(0.0, 0.0, -1.0), 0.0, f64::INFINITY)
                .unwrap();
            assert!((50.0 - h.t - g.height(x, y)).abs() < 1e-9);
            assert!(!h.vertical_face);
        }
        // horizontal ray 5 cm above the road edge towards +y hits the kerb face at y = 4
        let z = g.height(10.0, 3.999) + 0.05;
        let h = g
            .intersect(
                &Vector3::new(10.0, 0.0, z),
                &Vector3::new(0.0, 1.0, 0.0),
                0.0,
                f64::INFINITY,
            )
            .unwrap();
        assert!(h.vertical_face);
        assert!((h.t - 4.0).abs() < 1e-9);
        assert!((h.normal_local - Vector3::new(0.0, -1.0, 0.0)).norm() < 1e-12);
    }

    #[test]
    fn oblique_rays_hit_on_the_surface() {
        let g = ground();
        for i in 0..200 {
            let a = i as f64 * 0.1;
            let o = Vector3::new(20.0 + 10.0 * a.cos(), 3.0 * a.sin(), 2.5);
            let d = Vector3::new(a.cos(), (a * 1.7).sin(), -0.05 - 0.3 * (i % 7) as f64 / 7.0)
                .normalize();
            if let Some(h) = g.intersect(&o, &d, 0.0, f64::INFINITY) {
                let p = o + d * h.t;
                if !h.vertical_face {
                    assert!((p.z - g.height(p.x, p.y)).abs() < 1e-9, "ray {i}");
                }
            }
        }
    }
}
