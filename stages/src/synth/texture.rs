//! Procedural materials (linear RGB albedo, nominally 0..1) for the synthetic scene: asphalt, road paint,
//! paving tiles, kerb concrete, grass, water, manhole covers, façades (brick/plaster with a window grid),
//! roofs, leaves, bark and car paint.
//!
//! All functions are pure in (position, parameters, seed). Detail is band-limited: the finest structure is
//! ~1 cm (asphalt grain), well above the ~2 mm limit, so supersampled renders do not alias badly.

use crate::synth::noise::{fbm2, floor_f64, gradient2, hash2, unit_f32, value2, value3};

#[inline]
fn scale(c: [f32; 3], k: f32) -> [f32; 3] {
    [c[0] * k, c[1] * k, c[2] * k]
}

#[inline]
fn mix(a: [f32; 3], b: [f32; 3], t: f32) -> [f32; 3] {
    [
        a[0] + (b[0] - a[0]) * t,
        a[1] + (b[1] - a[1]) * t,
        a[2] + (b[2] - a[2]) * t,
    ]
}

#[inline]
fn smoothstep(e0: f32, e1: f32, x: f32) -> f32 {
    let t = ((x - e0) / (e1 - e0)).clamp(0.0, 1.0);
    t * t * (3.0 - 2.0 * t)
}

/// Asphalt at local (x, y): cm-scale grain with bright aggregate, m-scale blotches, rectangular repair
/// patches on a 7 m lattice, and thin dark cracks.
pub fn asphalt(x: f64, y: f64, seed: u64) -> [f32; 3] {
    let grain = value2(x * 90.0, y * 90.0, seed) * 0.035;
    let stone = unit_f32(hash2(
        floor_f64(x * 70.0) as i64,
        floor_f64(y * 70.0) as i64,
        seed ^ 0xA66,
    ));
    let stone = if stone > 0.93 { 0.06 } else { 0.0 };
    let blotch = fbm2(x, y, seed ^ 0xB10, 0.35, 2, 0.55) * 0.045;
    let mut v = 0.17 + grain + stone + blotch;
    // repair patches
    let (cx, cy) = (floor_f64(x / 7.0) as i64, floor_f64(y / 7.0) as i64);
    let h = hash2(cx, cy, seed ^ 0x9A7C);
    if unit_f32(h) < 0.22 {
        let fx = x - cx as f64 * 7.0;
        let fy = y - cy as f64 * 7.0;
        let (x0, w) = (
            1.0 + 2.0 * unit_f32(h >> 8) as f64,
            1.5 + 2.5 * unit_f32(h >> 16) as f64,
        );
        let (y0, hgt) = (
            1.0 + 2.0 * unit_f32(h >> 24) as f64,
            1.0 + 2.0 * unit_f32(h >> 32) as f64,
        );
        if fx > x0 && fx < x0 + w && fy > y0 && fy < y0 + hgt {
            v = 0.12 + grain * 0.5 + blotch * 0.3;
        }
    }
    // cracks: thin zero-crossings of a low-frequency gradient noise, wiggled
    let c = gradient2(
        x * 0.45 + 0.3 * value2(x * 3.0, y * 3.0, seed ^ 7) as f64,
        y * 0.45,
        seed ^ 0xC4AC,
    )
    .abs();
    if c < 0.010 {
        v *= 0.45 + 40.0 * c;
    }
    [v * 0.98, v, v * 1.03]
}

/// White road paint, slightly worn.
pub fn paint(x: f64, y: f64, seed: u64) -> [f32; 3] {
    let wear = fbm2(x, y, seed ^ 0x9A1, 2.0, 3, 0.5);
    let grain = value2(x * 80.0, y * 80.0, seed ^ 0x9A2) * 0.04;
    let v = 0.78 - 0.12 * wear.max(0.0) + grain;
    [v, v, v * 0.97]
}

/// Cast-iron manhole cover; (ds, dq) is the offset from its centre (m), radius `r`.
pub fn manhole(ds: f64, dq: f64, r: f64, seed: u64) -> [f32; 3] {
    let rho = (ds * ds + dq * dq).sqrt();
    let mut v = 0.10 + value2(ds * 40.0, dq * 40.0, seed) * 0.02;
    if rho > r - 0.04 {
        v = 0.22; // steel rim
    } else if (floor_f64(rho / 0.05) as i64) % 2 == 0 && rho > 0.06 {
        v += 0.06; // concentric ribs
    }
    [v, v * 0.98, v * 0.95]
}

/// Concrete paving tiles (0.30 m) with dark joints and per-tile brightness; (s, q) street coordinates.
pub fn paving(s: f64, q: f64, seed: u64) -> [f32; 3] {
    const TILE: f64 = 0.30;
    let (is, iq) = (floor_f64(s / TILE), floor_f64(q / TILE));
    let (fs, fq) = (s - is * TILE, q - iq * TILE);
    let joint = fs.min(TILE - fs).min(fq).min(TILE - fq);
    let h = hash2(is as i64, iq as i64, seed ^ 0x7A1E);
    let tile = 0.36 + 0.10 * unit_f32(h) + value2(s * 50.0, q * 50.0, seed) * 0.03;
    let v = if joint < 0.004 { 0.16 } else { tile };
    let tint = if unit_f32(h >> 20) < 0.12 {
        [1.08, 0.92, 0.85]
    } else {
        [1.0, 0.99, 0.97]
    };
    [v * tint[0], v * tint[1], v * tint[2]]
}

/// Concrete kerb stone.
pub fn kerb(x: f64, y: f64, z: f64, seed: u64) -> [f32; 3] {
    let v = 0.52
        + value3(x * 30.0, y * 30.0, z * 30.0, seed) * 0.04
        + fbm2(x, y, seed, 1.0, 2, 0.5) * 0.04;
    [v, v, v * 0.98]
}

/// Lawn / verge grass.
pub fn grass(x: f64, y: f64, seed: u64) -> [f32; 3] {
    let big = fbm2(x, y, seed ^ 0x6A55, 0.3, 3, 0.5);
    let fine = value2(x * 35.0, y * 35.0, seed ^ 0x6A56);
    let base = mix([0.07, 0.16, 0.04], [0.16, 0.22, 0.07], 0.5 + 0.5 * big);
    scale(base, 1.0 + 0.25 * fine)
}

/// Canal water (dark, with ripples).
pub fn water(x: f64, y: f64, seed: u64) -> [f32; 3] {
    let r = fbm2(x, y * 3.0, seed ^ 0x3A7E, 0.8, 3, 0.5);
    let v = 0.06 + 0.03 * r;
    [v * 0.8, v * 1.1, v * 1.15]
}

/// Leaves on a crown surface point.
pub fn leaves(x: f64, y: f64, z: f64, seed: u64) -> [f32; 3] {
    let n1 = value3(x * 6.0, y * 6.0, z * 6.0, seed);
    let n2 = value3(x * 25.0, y * 25.0, z * 25.0, seed ^ 0x1EAF);
    let k = 0.8 + 0.35 * n1 + 0.2 * n2;
    scale([0.07, 0.15, 0.04], k.max(0.2))
}

/// Tree bark.
pub fn bark(x: f64, y: f64, z: f64, seed: u64) -> [f32; 3] {
    let v = value3(x * 20.0, y * 20.0, z * 4.0, seed) * 0.03;
    [0.16 + v, 0.12 + v, 0.09 + v]
}

/// Car paint (with a hint of dirt variation).
pub fn car_paint(rgb: [f32; 3], x: f64, y: f64, z: f64, seed: u64) -> [f32; 3] {
    scale(rgb, 1.0 + 0.05 * value3(x * 3.0, y * 3.0, z * 3.0, seed))
}

/// The look parameters of a façade (see `scene::layout::Building`).
#[derive(Clone, Copy, Debug)]
pub struct FacadeLook {
    pub wall_rgb: [f32; 3],
    pub frame_rgb: [f32; 3],
    pub brick: bool,
    pub storey_height_m: f64,
    pub storeys: u32,
    pub bay_m: f64,
    pub window_w_m: f64,
    pub window_h_m: f64,
    pub sill_m: f64,
    pub door_bay: u32,
    pub seed: u64,
}

/// A façade point: `u` metres along the façade from its left end, `v` metres above storey 0's floor.
/// Windows on a grid (frames, sills, glass brightness varying per window: curtains/shutters), a door in
/// one ground-floor bay, brick bond or plaster between.
pub fn facade(u: f64, v: f64, look: &FacadeLook) -> [f32; 3] {
    let seed = look.seed;
    let wall = if look.brick {
        const BRICK_W: f64 = 0.22;
        const BRICK_H: f64 = 0.0625;
        let row = floor_f64(v / BRICK_H);
        let off = if (row as i64) % 2 == 0 {
            0.0
        } else {
            0.5 * BRICK_W
        };
        let col = floor_f64((u + off) / BRICK_W);
        let fu = u + off - col * BRICK_W;
        let fv = v - row * BRICK_H;
        let mortar = fu < 0.010 || fv < 0.010;
        if mortar {
            [0.50, 0.48, 0.44]
        } else {
            let k = 0.85 + 0.3 * unit_f32(hash2(col as i64, row as i64, seed));
            scale(look.wall_rgb, k)
        }
    } else {
        scale(
            look.wall_rgb,
            1.0 + 0.08 * fbm2(u, v, seed, 0.8, 3, 0.5) + 0.03 * value2(u * 40.0, v * 40.0, seed),
        )
    };
    if v < 0.0 {
        return scale(wall, 0.7); // plinth
    }
    let storey = floor_f64(v / look.storey_height_m);
    if storey as u32 >= look.storeys {
        return wall; // parapet / attic wall
    }
    let bay = floor_f64(u / look.bay_m);
    let bu = u - bay * look.bay_m - 0.5 * look.bay_m; // relative to bay centre
    let sv = v - storey * look.storey_height_m; // height within storey
    let frame_w = 0.07;
    if storey == 0.0 && bay as u32 == look.door_bay {
        // door: 1.1 × 2.3 m
        let (hw, h) = (0.55, 2.3);
        if bu.abs() < hw && sv < h {
            if bu.abs() > hw - frame_w || sv > h - frame_w {
                return look.frame_rgb;
            }
            let door = scale(
                [0.22, 0.12, 0.07],
                1.0 + 0.1 * value2(u * 5.0, v * 40.0, seed),
            );
            return door;
        }
        return wall;
    }
    let hw = 0.5 * look.window_w_m;
    let (w0, w1) = (look.sill_m, look.sill_m + look.window_h_m);
    if bu.abs() < hw && sv > w0 && sv < w1 {
        if bu.abs() > hw - frame_w || sv < w0 + frame_w || sv > w1 - frame_w || bu.abs() < 0.025 {
            return look.frame_rgb;
        }
        // glass: brightness per window (curtains, shutters, reflections)
        let h = hash2(bay as i64, storey as i64, seed ^ 0x61A55);
        let kind = unit_f32(h);
        return if kind < 0.15 {
            [0.55, 0.52, 0.45] // light curtains
        } else if kind < 0.22 {
            scale(look.frame_rgb, 0.8) // closed shutters
        } else {
            let g = 0.05 + 0.08 * unit_f32(h >> 24) + 0.05 * ((sv - w0) / look.window_h_m) as f32;
            [g * 0.9, g, g * 1.15]
        };
    }
    // sill: a light band just under the window
    if bu.abs() < hw + 0.05 && sv <= w0 && sv > w0 - 0.06 {
        return [0.6, 0.6, 0.58];
    }
    wall
}

/// Roof albedo: `tiles` for gable roofs (rows along the slope), else gravel/bitumen for flat roofs.
pub fn roof(rgb: [f32; 3], along: f64, across: f64, tiles: bool, seed: u64) -> [f32; 3] {
    if tiles {
        let row = floor_f64(across / 0.33);
        let f = (across - row * 0.33) as f32 / 0.33;
        let col = ((along + if (row as i64) % 2 == 0 { 0.0 } else { 0.1 }) / 0.2).floor();
        let k = 0.85 + 0.2 * unit_f32(hash2(col as i64, row as i64, seed))
            - 0.25 * smoothstep(0.75, 1.0, f);
        scale(rgb, k)
    } else {
        // bitumen sheets 1 m wide with dark seams, weathered patches on a 3 m lattice, fine grit
        let g = value2(along * 60.0, across * 60.0, seed) * 0.05
            + fbm2(along, across, seed, 0.2, 3, 0.5) * 0.08;
        let sheet = across - floor_f64(across);
        let seam = if sheet < 0.02 { 0.6 } else { 1.0 };
        let h = hash2(
            floor_f64(along / 3.0) as i64,
            floor_f64(across / 3.0) as i64,
            seed ^ 0x400F,
        );
        let patch = if unit_f32(h) < 0.2 { 0.75 } else { 1.0 };
        scale(rgb, (1.0 + g) * seam * patch)
    }
}

/// Coping (light edge band) of a flat roof.
pub fn roof_coping(x: f64, y: f64, seed: u64) -> [f32; 3] {
    let v = 0.55 + 0.04 * value2(x * 20.0, y * 20.0, seed);
    [v, v, v * 0.98]
}

/// Rooftop unit (air conditioner, skylight frame): light metal.
pub fn metal(x: f64, y: f64, z: f64, seed: u64) -> [f32; 3] {
    let v = 0.62 + 0.05 * value3(x * 8.0, y * 8.0, z * 8.0, seed);
    [v * 0.98, v, v * 1.02]
}

/// Sky radiance for a world direction with elevation sin `dz` (zenith blue to hazy horizon).
pub fn sky(dz: f64) -> [f32; 3] {
    let e = dz.clamp(-1.0, 1.0) as f32;
    if e <= 0.0 {
        return [0.55, 0.58, 0.60];
    }
    let t = e.sqrt();
    mix([0.78, 0.82, 0.86], [0.30, 0.45, 0.78], t)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn look() -> FacadeLook {
        FacadeLook {
            wall_rgb: [0.4, 0.2, 0.15],
            frame_rgb: [0.85, 0.85, 0.82],
            brick: true,
            storey_height_m: 3.0,
            storeys: 3,
            bay_m: 3.0,
            window_w_m: 1.5,
            window_h_m: 1.5,
            sill_m: 0.9,
            door_bay: 0,
            seed: 5,
        }
    }

    #[test]
    fn facade_has_window_frames_where_laid_out() {
        let l = look();
        // window of bay 1, storey 1: centre at u = 4.5, v = 3 + 0.9 + 0.75; frame at its left edge
        assert_eq!(facade(4.5 - 0.72, 3.0 + 1.65, &l), l.frame_rgb);
        // the central mullion
        assert_eq!(facade(4.5, 3.0 + 1.65, &l), l.frame_rgb);
        // door in bay 0 at ground level
        let d = facade(1.5 + 0.3, 1.0, &l);
        assert!(d[0] < 0.3 && d[0] > d[2]);
    }

    #[test]
    fn textures_are_bounded_and_vary() {
        let mut lo = f32::MAX;
        let mut hi = f32::MIN;
        for i in 0..2000 {
            let x = i as f64 * 0.0137;
            let a = asphalt(x, x * 0.3, 1);
            for c in a {
                assert!((0.0..=1.0).contains(&c));
            }
            lo = lo.min(a[1]);
            hi = hi.max(a[1]);
            let p = paving(x, 0.1, 1);
            assert!(p.iter().all(|c| (0.0..=1.0).contains(c)));
        }
        assert!(hi - lo > 0.08, "asphalt has contrast: {lo}..{hi}");
    }
}
