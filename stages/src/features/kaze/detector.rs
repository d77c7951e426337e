//! KAZE keypoint detector (Alcantarilla, Bartoli & Davison 2012 "Detector"; KAZE paper §4.2): 3×3×3 maxima of the
//! scale-normalised det(Hessian) above a threshold, duplicate suppression across neighbouring levels, and
//! sub-pixel / sub-scale refinement by a quadratic fit.
//!
//! Pixel convention: a candidate at array index (col, row) sits at the pixel centre
//! (u, v) = (col + 0.5, row + 0.5) (campaign-format.md); the refined offset δ is added to that.

use rayon::prelude::*;

use super::params::KazeParams;
use super::scale_space::Level;
use crate::imaging::GrayImage;

/// A refined detection, before orientation.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Detection {
    pub u_px: f32,
    pub v_px: f32,
    /// Refined σ (px).
    pub sigma_px: f32,
    pub response: f32,
    /// Evolution level index i the maximum was found on.
    pub level: usize,
}

#[derive(Clone, Copy, Debug)]
struct Candidate {
    col: usize,
    row: usize,
    level: usize,
    response: f32,
}

/// Is `value` ≥ all of the 3×3 pixels of `img` around (col, row) (the centre included)?
#[inline]
fn dominates_3x3(img: &GrayImage, col: usize, row: usize, value: f32) -> bool {
    let w = img.width;
    for r in row - 1..=row + 1 {
        let line = &img.data[r * w + col - 1..r * w + col + 2];
        if line.iter().any(|&v| v > value) {
            return false;
        }
    }
    true
}

/// Candidates of level `i` (1 ≤ i ≤ N − 2) in raster order.
fn level_candidates(levels: &[Level], i: usize, threshold: f32) -> Vec<Candidate> {
    let det = &levels[i].det;
    let (w, h) = (det.width, det.height);
    if w < 3 || h < 3 {
        return Vec::new();
    }
    let rows: Vec<Vec<Candidate>> = (1..h - 1)
        .into_par_iter()
        .map(|row| {
            let mut found = Vec::new();
            for col in 1..w - 1 {
                let value = det.data[row * w + col];
                if value > threshold
                    && dominates_3x3(det, col, row, value)
                    && dominates_3x3(&levels[i - 1].det, col, row, value)
                    && dominates_3x3(&levels[i + 1].det, col, row, value)
                {
                    found.push(Candidate {
                        col,
                        row,
                        level: i,
                        response: value,
                    });
                }
            }
            found
        })
        .collect();
    rows.into_iter().flatten().collect()
}

/// Accepted candidates after duplicate suppression: a candidate within squared distance < s_i² of an
/// already accepted point on level i−1, i or i+1 replaces the earliest such point if its response is
/// larger, else it is dropped. Candidates are visited level by level in raster order (deterministic).
fn suppress_duplicates(candidates: &[Candidate], levels: &[Level], width: usize) -> Vec<Candidate> {
    let cell = levels.iter().map(|l| l.step_px).max().unwrap_or(1).max(1);
    let cells_x = width / cell + 1;
    let cells_y = levels[0].det.height / cell + 1;
    let mut grid: Vec<Vec<usize>> = vec![Vec::new(); cells_x * cells_y];
    let mut accepted: Vec<Candidate> = Vec::new();
    for c in candidates {
        let s = levels[c.level].step_px as f32;
        let (cx, cy) = (c.col / cell, c.row / cell);
        let mut earliest: Option<usize> = None;
        for gy in cy.saturating_sub(1)..=(cy + 1).min(cells_y - 1) {
            for gx in cx.saturating_sub(1)..=(cx + 1).min(cells_x - 1) {
                for &k in &grid[gy * cells_x + gx] {
                    let a = &accepted[k];
                    if a.level.abs_diff(c.level) > 1 {
                        continue;
                    }
                    let dx = a.col as f32 - c.col as f32;
                    let dy = a.row as f32 - c.row as f32;
                    if dx * dx + dy * dy < s * s && earliest.is_none_or(|e| k < e) {
                        earliest = Some(k);
                    }
                }
            }
        }
        match earliest {
            Some(k) => {
                if c.response > accepted[k].response {
                    let old = accepted[k];
                    let old_cell = (old.row / cell) * cells_x + old.col / cell;
                    grid[old_cell].retain(|&x| x != k);
                    accepted[k] = *c;
                    grid[cy * cells_x + cx].push(k);
                }
            }
            None => {
                grid[cy * cells_x + cx].push(accepted.len());
                accepted.push(*c);
            }
        }
    }
    accepted
}

/// Quadratic fit of det(Hessian) in (x, y, level) around a candidate; `None` if the offset leaves the
/// ±1 box in any coordinate or the 3×3 system is singular.
fn refine(c: &Candidate, levels: &[Level], p: &KazeParams) -> Option<Detection> {
    let (below, here, above) = (
        &levels[c.level - 1].det,
        &levels[c.level].det,
        &levels[c.level + 1].det,
    );
    let (x, y) = (c.col, c.row);
    let at = |img: &GrayImage, dx: isize, dy: isize| -> f64 {
        img.get((x as isize + dx) as usize, (y as isize + dy) as usize) as f64
    };
    let centre = at(here, 0, 0);
    let gx = 0.5 * (at(here, 1, 0) - at(here, -1, 0));
    let gy = 0.5 * (at(here, 0, 1) - at(here, 0, -1));
    let gs = 0.5 * (at(above, 0, 0) - at(below, 0, 0));
    let hxx = at(here, 1, 0) + at(here, -1, 0) - 2.0 * centre;
    let hyy = at(here, 0, 1) + at(here, 0, -1) - 2.0 * centre;
    let hss = at(above, 0, 0) + at(below, 0, 0) - 2.0 * centre;
    let hxy = 0.25 * (at(here, 1, 1) + at(here, -1, -1) - at(here, -1, 1) - at(here, 1, -1));
    let hxs = 0.25 * (at(above, 1, 0) + at(below, -1, 0) - at(above, -1, 0) - at(below, 1, 0));
    let hys = 0.25 * (at(above, 0, 1) + at(below, 0, -1) - at(above, 0, -1) - at(below, 0, 1));
    let h = nalgebra::Matrix3::new(hxx, hxy, hxs, hxy, hyy, hys, hxs, hys, hss);
    let g = nalgebra::Vector3::new(-gx, -gy, -gs);
    let delta = h.lu().solve(&g)?;
    if !delta.iter().all(|d| d.is_finite() && d.abs() <= 1.0) {
        return None;
    }
    let level = &levels[c.level];
    let sigma_px = p.sigma_of(level.octave, level.sublevel as f32 + delta[2] as f32);
    Some(Detection {
        u_px: (x as f64 + 0.5 + delta[0]) as f32,
        v_px: (y as f64 + 0.5 + delta[1]) as f32,
        sigma_px,
        response: c.response,
        level: c.level,
    })
}

/// All refined detections, in deterministic order (level, then raster order of the first acceptance).
pub fn detect(levels: &[Level], p: &KazeParams) -> Vec<Detection> {
    if levels.len() < 3 {
        return Vec::new();
    }
    let width = levels[0].det.width;
    let candidates: Vec<Candidate> = (1..levels.len() - 1)
        .flat_map(|i| level_candidates(levels, i, p.threshold))
        .collect();
    let accepted = suppress_duplicates(&candidates, levels, width);
    let refined: Vec<Option<Detection>> =
        accepted.par_iter().map(|c| refine(c, levels, p)).collect();
    refined.into_iter().flatten().collect()
}
