//! Profile `outage`: a GNSS outage per route, as in a street canyon. While satellites are blocked the
//! navigation solution coasts on the inertial unit and its error grows; post-processing (forward-backward
//! smoothing) pulls it back where the fix returns. So the horizontal error rises smoothly from centimetres at
//! the outage's start to `peak` in its middle and falls back to centimetres at its end. The error *grows* in a
//! direction fixed in the vehicle frame (an along- and cross-track velocity error), so the direction in which
//! it grows turns with the vehicle through a bend while the error already accumulated stays where it is in the
//! world: the error is the integral of that rate, run forward from the outage's start and backward from its
//! end and blended as a two-filter smoother does, which keeps it continuous through a bend. A random walk is
//! added on top. Outside the outages positions keep centimetre noise.

use super::{Draw, Tables};
use crate::synth::rng::{hash_str, Stream};
use std::f64::consts::PI;

crate::params! {
    /// Parameters of the `outage` component (`[synth.outage]`).
    pub struct OutageParams {
        /// Length of the outage along the route: drawn uniformly from this range [low, high] (and cut to
        /// `max_route_fraction` of a shorter route).
        length_m: [f64; 2] = [80.0, 150.0], unit "m", min 0.0;
        /// Largest error (middle of the outage): drawn uniformly from this range [low, high].
        peak_m: [f64; 2] = [1.5, 2.0], unit "m", min 0.0;
        /// Longest outage as a fraction of its route's length.
        max_route_fraction: f64 = 0.8, above 0.0, max 1.0;
        /// SD of one step of the random walk (per recording inside the outage, per horizontal axis).
        random_walk_step_m: f64 = 0.04, unit "m", min 0.0;
        /// SD of the white noise of every recording (a healthy fix), per horizontal axis.
        fix_sigma_m: f64 = 0.02, unit "m", min 0.0;
    }
    check(p, v) {
        super::check_ordered("length_m", p.length_m, v);
        super::check_ordered("peak_m", p.peak_m, v);
    }
}

/// The drawn outage of one route.
#[derive(Clone, Debug, PartialEq)]
pub struct Outage {
    /// Start along the route, m.
    pub start_m: f64,
    pub length_m: f64,
    pub peak_m: f64,
    /// Direction in which the drift grows, relative to the driving direction, degrees clockwise (0 = ahead,
    /// 90 = right).
    pub relative_azimuth_deg: f64,
}

impl Outage {
    /// Position in the outage (0 at its start, 1 at its end), or `None` outside it.
    pub fn phase(&self, along_m: f64) -> Option<f64> {
        let t = (along_m - self.start_m) / self.length_m.max(1e-9);
        (0.0..=1.0).contains(&t).then_some(t)
    }

    /// Size of the smooth drift (without the random walk) at `along_m` on a straight route, m:
    /// `peak · sin²(π t)`. Through a bend the size differs (see [`Outage::drift_world_m`]).
    pub fn drift_m(&self, along_m: f64) -> f64 {
        self.phase(along_m).map_or(0.0, |t| self.peak_m * shape(t))
    }

    /// The smooth drift (without the random walk) of the recordings inside the outage, world x (east) and y
    /// (north), m. `along_m` and `heading_deg` (true heading, degrees clockwise from grid north) are those
    /// recordings in driving order; every `along_m` must lie inside the outage.
    ///
    /// The size `peak · sin²(π t)` is the integral of its rate along the route; the rate points
    /// `relative_azimuth_deg` from the driving direction. Integrated forward from the outage's start (error
    /// 0 there) and backward from its end (error 0 there, too), the two solutions agree on a straight route and
    /// differ past a bend; they are blended with weights inversely proportional to each one's error variance
    /// (the backward one weighs `t² / (t² + (1 − t)²)`), as a two-filter smoother does. The result is scaled
    /// so that its largest size equals the largest `peak · sin²(π t)` at these recordings: on a straight route
    /// it is exactly `peak · sin²(π t)` pointing `relative_azimuth_deg` from the driving direction.
    pub fn drift_world_m(&self, along_m: &[f64], heading_deg: &[f64]) -> Vec<[f64; 2]> {
        let n = along_m.len().min(heading_deg.len());
        if n == 0 {
            return Vec::new();
        }
        let t: Vec<f64> = along_m[..n]
            .iter()
            .map(|&a| ((a - self.start_m) / self.length_m.max(1e-9)).clamp(0.0, 1.0))
            .collect();
        let g: Vec<f64> = t.iter().map(|&t| shape(t)).collect();
        let rate_dir: Vec<[f64; 2]> = heading_deg[..n]
            .iter()
            .map(|&h| {
                let (s, c) = (h + self.relative_azimuth_deg).to_radians().sin_cos();
                [s, c]
            })
            .collect();
        // Trapezoidal integration of d(size) · direction between consecutive recordings, starting where the
        // size is 0 with the direction of the nearest recording.
        let integrate = |order: &mut dyn Iterator<Item = usize>| {
            let mut out = vec![[0.0f64; 2]; n];
            let (mut acc, mut prev): ([f64; 2], Option<usize>) = ([0.0; 2], None);
            for i in order {
                let (g0, d0) = prev.map_or((0.0, rate_dir[i]), |p| (g[p], rate_dir[p]));
                let dg = g[i] - g0;
                acc[0] += dg * 0.5 * (d0[0] + rate_dir[i][0]);
                acc[1] += dg * 0.5 * (d0[1] + rate_dir[i][1]);
                out[i] = acc;
                prev = Some(i);
            }
            out
        };
        let forward = integrate(&mut (0..n));
        let backward = integrate(&mut (0..n).rev());
        let mut drift: Vec<[f64; 2]> = (0..n)
            .map(|i| {
                let w = backward_weight(t[i]);
                [
                    (1.0 - w) * forward[i][0] + w * backward[i][0],
                    (1.0 - w) * forward[i][1] + w * backward[i][1],
                ]
            })
            .collect();
        let want = g.iter().copied().fold(0.0, f64::max);
        let got = drift.iter().map(|d| d[0].hypot(d[1])).fold(0.0, f64::max);
        let scale = if got > 1e-12 {
            self.peak_m * want / got
        } else {
            0.0
        };
        for d in &mut drift {
            d[0] *= scale;
            d[1] *= scale;
        }
        drift
    }
}

/// Weight of the backward solution at phase `t` of the outage in the two-filter blend: each solution weighted by
/// the inverse of its error variance, which grows with the square of the distance from its own fix (a velocity
/// error makes the position error grow in proportion to the distance).
fn backward_weight(t: f64) -> f64 {
    let (f, b) = (t * t, (1.0 - t) * (1.0 - t));
    if f + b > 0.0 {
        f / (f + b)
    } else {
        0.5
    }
}

/// The drift's shape over the outage: `sin²(π t)`, 0 at both ends and 1 in the middle.
fn shape(t: f64) -> f64 {
    (PI * t).sin().powi(2)
}

impl OutageParams {
    /// The outage of route `route` (of length `route_length_m`) for `seed`.
    pub fn draw(&self, seed: u64, route: usize, route_length_m: f64) -> Outage {
        let mut s = Stream::new(&[seed, hash_str("outage"), route as u64]);
        let length_m = s
            .range(self.length_m[0], self.length_m[1])
            .min(self.max_route_fraction * route_length_m);
        let start_m = s.uniform() * (route_length_m - length_m).max(0.0);
        Outage {
            start_m,
            length_m,
            peak_m: s.range(self.peak_m[0], self.peak_m[1]),
            relative_azimuth_deg: s.range(0.0, 360.0),
        }
    }

    /// Add the outage errors to the recorded positions; returns the README lines.
    pub fn apply(&self, on: &Draw<'_>, out: &mut Tables) -> Vec<String> {
        let routes = on.routes;
        let mut notes = Vec::new();
        for (route, members) in routes.members.iter().enumerate() {
            let o = self.draw(on.seed, route, routes.length_m[route]);
            let inside_idx: Vec<usize> = members
                .iter()
                .copied()
                .filter(|&i| o.phase(routes.along_m[i]).is_some())
                .collect();
            let along: Vec<f64> = inside_idx.iter().map(|&i| routes.along_m[i]).collect();
            let heading: Vec<f64> = inside_idx
                .iter()
                .map(|&i| on.truth.recordings[i].heading_deg)
                .collect();
            let drift = o.drift_world_m(&along, &heading);
            let mut walk = on.route_stream("outage-walk", route);
            let (mut wx, mut wy) = (0.0, 0.0);
            let mut next_inside = 0;
            for &i in members {
                let t = &on.truth.recordings[i];
                let mut fix = on.recording_stream("outage-fix", &t.image_id);
                let (mut dx, mut dy) = (
                    self.fix_sigma_m * fix.normal(),
                    self.fix_sigma_m * fix.normal(),
                );
                if let Some(phase) = o.phase(routes.along_m[i]) {
                    wx += self.random_walk_step_m * walk.normal();
                    wy += self.random_walk_step_m * walk.normal();
                    let taper = (PI * phase).sin();
                    let d = drift[next_inside];
                    next_inside += 1;
                    dx += d[0] + taper * wx;
                    dy += d[1] + taper * wy;
                }
                let r = &mut out.recordings[i];
                r.x += dx;
                r.y += dy;
            }
            let inside: Vec<&str> = inside_idx
                .iter()
                .map(|&i| on.truth.recordings[i].image_id.as_str())
                .collect();
            let span = match (inside.first(), inside.last()) {
                (Some(a), Some(b)) => format!("recordings {a} … {b}"),
                _ => "no recording".into(),
            };
            notes.push(format!(
                "`outage` route {route}: a GNSS outage from {:.1} m to {:.1} m along the route ({span}): a \
                 horizontal error of size peak · sin²(π t) with peak {:.3} m at {:.1} m (t = 0 at the outage's \
                 start, 1 at its end) on a straight route, growing in a direction {:.1}° clockwise from the \
                 driving direction (so the direction of growth turns with the vehicle; the error is that \
                 rate integrated forward from the start and backward from the end, blended with weights \
                 t² / (t² + (1 − t)²) for the backward one and scaled to the peak), plus a random walk \
                 with N(0, {:.3} m) steps per recording and axis, tapered by sin(π t);",
                o.start_m,
                o.start_m + o.length_m,
                o.peak_m,
                o.start_m + o.length_m / 2.0,
                o.relative_azimuth_deg,
                self.random_walk_step_m
            ));
        }
        notes.push(format!(
            "`outage`: plus N(0, {:.3} m) per horizontal axis on every panorama (the fix outside outages);",
            self.fix_sigma_m
        ));
        notes
    }
}
