//! Profile `ins`: the orientation errors of the inertial unit. Its heading is biased by a constant of
//! 0.1–0.5° per route (an alignment error) that slowly wanders (a random walk), and pitch and roll carry white
//! noise. The panoramas are rendered with their true orientation; the recorded `yaw`, `pitch`, `roll` columns
//! (campaign-format.md: the residual rotation of the panorama frame) and the `heading` column (also from the
//! inertial unit) get the errors, exactly as a provider who north-aligns panoramas with a biased heading
//! delivers them.

use super::{signed_draw, Draw, Tables};
use crate::synth::rng::{hash_str, Stream};

crate::params! {
    /// Parameters of the `ins` component (`[synth.ins]`).
    pub struct InsParams {
        /// Size of the heading bias per route: drawn uniformly from this range [low, high], with a random sign.
        heading_bias_deg: [f64; 2] = [0.1, 0.5], unit "deg", min 0.0;
        /// SD of one random-walk step of the heading error per recording.
        heading_walk_step_deg: f64 = 0.01, unit "deg", min 0.0;
        /// SD of the white noise on pitch and on roll.
        pitch_roll_sigma_deg: f64 = 0.02, unit "deg", min 0.0;
    }
    check(p, v) {
        super::check_ordered("heading_bias_deg", p.heading_bias_deg, v);
    }
}

impl InsParams {
    /// The signed heading bias of route `route`, degrees.
    pub fn bias_deg(&self, seed: u64, route: usize) -> f64 {
        signed_draw(
            &mut Stream::new(&[seed, hash_str("ins-bias"), route as u64]),
            self.heading_bias_deg,
        )
    }

    /// Add the orientation errors to the recorded yaw, pitch, roll and heading; returns the README lines.
    pub fn apply(&self, on: &Draw<'_>, out: &mut Tables) -> Vec<String> {
        let mut notes = Vec::new();
        for (route, members) in on.routes.members.iter().enumerate() {
            let bias = self.bias_deg(on.seed, route);
            let mut walk = on.route_stream("ins-walk", route);
            let mut wander = 0.0;
            let mut largest: f64 = 0.0;
            for &i in members {
                wander += self.heading_walk_step_deg * walk.normal();
                let mut n = on.recording_stream("ins-noise", &on.truth.recordings[i].image_id);
                let r = &mut out.recordings[i];
                let dyaw = bias + wander;
                r.yaw_deg += dyaw;
                r.heading_deg = (r.heading_deg + dyaw).rem_euclid(360.0);
                r.pitch_deg += self.pitch_roll_sigma_deg * n.normal();
                r.roll_deg += self.pitch_roll_sigma_deg * n.normal();
                largest = largest.max(dyaw.abs());
            }
            notes.push(format!(
                "`ins` route {route}: heading error {bias:+.3}° (added to `yaw` and `heading`) plus a random walk \
                 with N(0, {:.4}°) steps per recording (largest total heading error {largest:.3}°);",
                self.heading_walk_step_deg
            ));
        }
        notes.push(format!(
            "`ins`: plus N(0, {:.3}°) added to `pitch` and, independently, to `roll` of every panorama;",
            self.pitch_roll_sigma_deg
        ));
        notes
    }
}
