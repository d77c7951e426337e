//! Acceleration structure: a uniform 2-D grid over the objects' XY extent (street scenes are flat and
//! wide), each cell listing the objects whose bounds overlap it; rays are clipped to the objects' 3-D
//! bounds and walked cell by cell (2-D DDA, Amanatides–Woo) in front-to-back order.

use super::objects::Object;
use super::shapes::{Aabb, Ray};
use nalgebra::Vector3;

#[derive(Clone, Debug)]
pub struct Grid {
    bounds: Aabb,
    cell_m: f64,
    nx: usize,
    ny: usize,
    /// Offsets into `items` per cell (len nx·ny + 1).
    starts: Vec<u32>,
    items: Vec<u32>,
    /// Highest and lowest object z per cell (rays passing above/below a cell skip it).
    cell_z: Vec<(f64, f64)>,
}

impl Grid {
    /// Build over `objects` with cells of about `cell_m` (at most 512 per axis).
    pub fn build(objects: &[Object], cell_m: f64) -> Self {
        let top = objects.iter().filter(|o| !o.is_child).count();
        if top == 0 {
            return Self {
                bounds: Aabb::new(Vector3::zeros(), Vector3::zeros()),
                cell_m: 1.0,
                nx: 0,
                ny: 0,
                starts: vec![0],
                items: Vec::new(),
                cell_z: Vec::new(),
            };
        }
        let mut tops = objects.iter().filter(|o| !o.is_child);
        let mut bounds = tops
            .next()
            .map(|o| o.bounds)
            .unwrap_or(Aabb::new(Vector3::zeros(), Vector3::zeros()));
        for o in tops {
            bounds = bounds.union(&o.bounds);
        }
        // pad slightly so objects on the boundary are inside
        let pad = Vector3::repeat(1e-6);
        bounds = Aabb::new(bounds.min - pad, bounds.max + pad);
        let ext = bounds.max - bounds.min;
        let cell_m = cell_m.max(ext.x / 512.0).max(ext.y / 512.0).max(1e-3);
        let nx = ((ext.x / cell_m).ceil() as usize).max(1);
        let ny = ((ext.y / cell_m).ceil() as usize).max(1);
        let cell_range = |lo: f64, hi: f64, min: f64, n: usize| -> (usize, usize) {
            let a = (((lo - min) / cell_m).floor().max(0.0) as usize).min(n - 1);
            let b = (((hi - min) / cell_m).floor().max(0.0) as usize).min(n - 1);
            (a, b)
        };
        let mut counts = vec![0u32; nx * ny];
        let mut cell_z = vec![(f64::INFINITY, f64::NEG_INFINITY); nx * ny];
        for o in objects.iter().filter(|o| !o.is_child) {
            let (x0, x1) = cell_range(o.bounds.min.x, o.bounds.max.x, bounds.min.x, nx);
            let (y0, y1) = cell_range(o.bounds.min.y, o.bounds.max.y, bounds.min.y, ny);
            for iy in y0..=y1 {
                for ix in x0..=x1 {
                    counts[iy * nx + ix] += 1;
                    let z = &mut cell_z[iy * nx + ix];
                    z.0 = z.0.min(o.bounds.min.z);
                    z.1 = z.1.max(o.bounds.max.z);
                }
            }
        }
        let mut starts = vec![0u32; nx * ny + 1];
        for i in 0..nx * ny {
            starts[i + 1] = starts[i] + counts[i];
        }
        let mut fill = starts.clone();
        let mut items = vec![0u32; starts[nx * ny] as usize];
        for (k, o) in objects.iter().enumerate().filter(|(_, o)| !o.is_child) {
            let (x0, x1) = cell_range(o.bounds.min.x, o.bounds.max.x, bounds.min.x, nx);
            let (y0, y1) = cell_range(o.bounds.min.y, o.bounds.max.y, bounds.min.y, ny);
            for iy in y0..=y1 {
                for ix in x0..=x1 {
                    let c = iy * nx + ix;
                    items[fill[c] as usize] = k as u32;
                    fill[c] += 1;
                }
            }
        }
        Self {
            bounds,
            cell_m,
            nx,
            ny,
            starts,
            items,
            cell_z,
        }
    }

    /// Walk the cells pierced by the ray within (t_min, t_max), front to back. `visit(items, t_cell_exit)`
    /// returns `true` to stop.
    #[inline]
    pub fn walk(
        &self,
        ray: &Ray,
        t_min: f64,
        t_max: f64,
        mut visit: impl FnMut(&[u32], f64) -> bool,
    ) {
        let (o, d, inv_d) = (&ray.o, &ray.d, &ray.inv_d);
        if self.nx == 0 {
            return;
        }
        let Some((t0, t1)) = self.bounds.clip(o, inv_d, t_min, t_max) else {
            return;
        };
        let px = o.x + t0 * d.x;
        let py = o.y + t0 * d.y;
        let mut ix = (((px - self.bounds.min.x) / self.cell_m).max(0.0) as usize).min(self.nx - 1);
        let mut iy = (((py - self.bounds.min.y) / self.cell_m).max(0.0) as usize).min(self.ny - 1);
        let (step_x, mut t_next_x, dt_x) =
            dda_axis(self.bounds.min.x, self.cell_m, ix, o.x, d.x, inv_d.x);
        let (step_y, mut t_next_y, dt_y) =
            dda_axis(self.bounds.min.y, self.cell_m, iy, o.y, d.y, inv_d.y);
        let mut t_enter = t0;
        loop {
            let c = iy * self.nx + ix;
            let t_exit = t_next_x.min(t_next_y).min(t1);
            let (z_lo, z_hi) = self.cell_z[c];
            let za = o.z + t_enter * d.z;
            let zb = o.z + t_exit * d.z;
            if za.min(zb) <= z_hi && za.max(zb) >= z_lo {
                let cell = &self.items[self.starts[c] as usize..self.starts[c + 1] as usize];
                if !cell.is_empty() && visit(cell, t_exit) {
                    return;
                }
            }
            t_enter = t_exit;
            if t_exit >= t1 {
                return;
            }
            if t_next_x < t_next_y {
                let n = ix as isize + step_x;
                if n < 0 || n >= self.nx as isize {
                    return;
                }
                ix = n as usize;
                t_next_x += dt_x;
            } else {
                let n = iy as isize + step_y;
                if n < 0 || n >= self.ny as isize {
                    return;
                }
                iy = n as usize;
                t_next_y += dt_y;
            }
        }
    }
}

/// One axis of the grid walk (Amanatides & Woo): the cell step (±1, 0 along a parallel ray), the ray
/// parameter of the first cell boundary crossed from cell `i` (grid origin `min`, cells `cell_m` wide), and
/// the parameter increment per cell, for a ray with origin `o`, direction `d` and `inv_d = 1 / d` on this axis.
#[inline]
fn dda_axis(min: f64, cell_m: f64, i: usize, o: f64, d: f64, inv_d: f64) -> (isize, f64, f64) {
    if d > 0.0 {
        let b = min + (i + 1) as f64 * cell_m;
        (1, (b - o) * inv_d, cell_m * inv_d)
    } else if d < 0.0 {
        let b = min + i as f64 * cell_m;
        (-1, (b - o) * inv_d, -cell_m * inv_d)
    } else {
        (0, f64::INFINITY, f64::INFINITY)
    }
}
