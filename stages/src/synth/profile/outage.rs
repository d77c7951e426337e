//! Profile `outage`: a GNSS outage per route, as in a street canyon. While satellites are blocked the
//! navigation solution coasts on the inertial unit and its error grows; post-processing (forward-backward
//! smoothing) pulls it back where the fix returns. So the horizontal error rises smoothly from centimetres at
//! the outage's start to `peak` in its middle and falls back to centimetres at its end. The error is fixed in
//! the vehicle frame (an along- and cross-track drift), so its direction in the world turns with the vehicle
//! through a bend, and a random walk is added on top. Outside the outages positions keep centimetre noise.

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
    /// Direction of the drift relative to the driving direction, degrees clockwise (0 = ahead, 90 = right).
    pub relative_azimuth_deg: f64,
}

impl Outage {
    /// Position in the outage (0 at its start, 1 at its end), or `None` outside it.
    pub fn phase(&self, along_m: f64) -> Option<f64> {
        let t = (along_m - self.start_m) / self.length_m.max(1e-9);
        (0.0..=1.0).contains(&t).then_some(t)
    }

    /// Size of the smooth drift (without the random walk) at `along_m`, m: `peak · sin²(π t)`.
    pub fn drift_m(&self, along_m: f64) -> f64 {
        self.phase(along_m)
            .map_or(0.0, |t| self.peak_m * (PI * t).sin().powi(2))
    }
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
            let mut walk = on.route_stream("outage-walk", route);
            let (mut wx, mut wy) = (0.0, 0.0);
            let mut inside = Vec::new();
            for &i in members {
                let t = &on.truth.recordings[i];
                let mut fix = on.recording_stream("outage-fix", &t.image_id);
                let (mut dx, mut dy) = (
                    self.fix_sigma_m * fix.normal(),
                    self.fix_sigma_m * fix.normal(),
                );
                let along = routes.along_m[i];
                if let Some(phase) = o.phase(along) {
                    wx += self.random_walk_step_m * walk.normal();
                    wy += self.random_walk_step_m * walk.normal();
                    let (s, c) = (t.heading_deg + o.relative_azimuth_deg)
                        .to_radians()
                        .sin_cos();
                    let drift = o.drift_m(along);
                    let taper = (PI * phase).sin();
                    dx += drift * s + taper * wx;
                    dy += drift * c + taper * wy;
                    inside.push(t.image_id.as_str());
                }
                let r = &mut out.recordings[i];
                r.x += dx;
                r.y += dy;
            }
            let span = match (inside.first(), inside.last()) {
                (Some(a), Some(b)) => format!("recordings {a} … {b}"),
                _ => "no recording".into(),
            };
            notes.push(format!(
                "`outage` route {route}: a GNSS outage from {:.1} m to {:.1} m along the route ({span}): a \
                 horizontal error of peak · sin²(π t) with peak {:.3} m at {:.1} m (t = 0 at the outage's start, \
                 1 at its end), pointing {:.1}° clockwise from the driving direction (so it turns with the \
                 vehicle), plus a random walk with N(0, {:.3} m) steps per recording and axis, tapered by \
                 sin(π t);",
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
