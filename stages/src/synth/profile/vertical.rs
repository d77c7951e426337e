//! Profile `vertical`: the height errors of a GNSS/INS trajectory, larger than the horizontal ones (satellite
//! geometry), as a bias per route plus noise per recording, and an error of the recorded camera height above
//! the road (a mis-measured mounting, the suspension): a constant per campaign plus a little noise. The camera
//! height sets the scale of every ortho image, so its error reaches the nadir registration directly.

use super::{signed_draw, Draw, Tables};
use crate::synth::rng::{hash_str, Stream};

crate::params! {
    /// Parameters of the `vertical` component (`[synth.vertical]`).
    pub struct VerticalParams {
        /// Size of the height bias per route: drawn uniformly from this range [low, high], with a random sign.
        z_bias_m: [f64; 2] = [0.10, 0.30], unit "m", min 0.0;
        /// SD of the height noise per recording.
        z_sigma_m: f64 = 0.05, unit "m", min 0.0;
        /// Size of the camera-height error of the campaign: drawn uniformly from [low, high], with a random
        /// sign.
        camera_height_bias_m: [f64; 2] = [0.02, 0.05], unit "m", min 0.0;
        /// SD of the camera-height noise per recording.
        camera_height_sigma_m: f64 = 0.01, unit "m", min 0.0;
    }
    check(p, v) {
        super::check_ordered("z_bias_m", p.z_bias_m, v);
        super::check_ordered("camera_height_bias_m", p.camera_height_bias_m, v);
    }
}

impl VerticalParams {
    /// Add the height and camera-height errors; returns the README lines.
    pub fn apply(&self, on: &Draw<'_>, out: &mut Tables) -> Vec<String> {
        let mut notes = Vec::new();
        let camera_bias = signed_draw(
            &mut Stream::new(&[on.seed, hash_str("camera-height-bias")]),
            self.camera_height_bias_m,
        );
        for (route, members) in on.routes.members.iter().enumerate() {
            let z_bias = signed_draw(&mut on.route_stream("z-bias", route), self.z_bias_m);
            for &i in members {
                let mut n = on.recording_stream("vertical-noise", &on.truth.recordings[i].image_id);
                let r = &mut out.recordings[i];
                r.z += z_bias + self.z_sigma_m * n.normal();
                r.camera_height_m += camera_bias + self.camera_height_sigma_m * n.normal();
            }
            notes.push(format!(
                "`vertical` route {route}: a height bias of {z_bias:+.3} m plus N(0, {:.3} m) per panorama added \
                 to z;",
                self.z_sigma_m
            ));
        }
        notes.push(format!(
            "`vertical`: the recorded `camera_height` is off by {camera_bias:+.3} m plus N(0, {:.3} m) per \
             panorama;",
            self.camera_height_sigma_m
        ));
        notes
    }
}
