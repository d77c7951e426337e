//! Profile `vertical`: the height errors of a GNSS/INS trajectory, larger than the horizontal ones (satellite
//! geometry), as a bias per route plus noise per recording, and an error of the recorded camera height above
//! the road (a mis-measured mounting, the suspension): a constant per campaign plus a little noise. The camera
//! height sets the scale of every ortho image, so its error reaches the nadir registration directly.

use super::{check_non_negative, check_range, signed_draw, Routes, Tables};
use crate::synth::rng::{hash_str, Stream};
use serde::{Deserialize, Serialize};

/// Parameters of the `vertical` component (`[synth.vertical]`).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct VerticalParams {
    /// Size of the height bias per route, m: drawn uniformly from this range, with a random sign.
    pub z_bias_m: [f64; 2],
    /// SD of the height noise per recording, m.
    pub z_sigma_m: f64,
    /// Size of the camera-height error of the campaign, m: drawn uniformly, with a random sign.
    pub camera_height_bias_m: [f64; 2],
    /// SD of the camera-height noise per recording, m.
    pub camera_height_sigma_m: f64,
}

impl Default for VerticalParams {
    fn default() -> Self {
        Self {
            z_bias_m: [0.10, 0.30],
            z_sigma_m: 0.05,
            camera_height_bias_m: [0.02, 0.05],
            camera_height_sigma_m: 0.01,
        }
    }
}

impl VerticalParams {
    /// Every invalid field as (field, problem).
    pub fn problems(&self) -> Vec<(String, String)> {
        let mut p = Vec::new();
        check_range(&mut p, "vertical.z_bias_m", self.z_bias_m);
        check_non_negative(&mut p, "vertical.z_sigma_m", self.z_sigma_m);
        check_range(
            &mut p,
            "vertical.camera_height_bias_m",
            self.camera_height_bias_m,
        );
        check_non_negative(
            &mut p,
            "vertical.camera_height_sigma_m",
            self.camera_height_sigma_m,
        );
        p
    }

    /// Add the height and camera-height errors; returns the README lines.
    pub fn apply(
        &self,
        seed: u64,
        truth: &Tables,
        routes: &Routes,
        out: &mut Tables,
    ) -> Vec<String> {
        let mut notes = Vec::new();
        let camera_bias = signed_draw(
            &mut Stream::new(&[seed, hash_str("camera-height-bias")]),
            self.camera_height_bias_m,
        );
        for (route, members) in routes.members.iter().enumerate() {
            let z_bias = signed_draw(
                &mut Stream::new(&[seed, hash_str("z-bias"), route as u64]),
                self.z_bias_m,
            );
            for &i in members {
                let t = &truth.recordings[i];
                let mut n = Stream::new(&[seed, hash_str("vertical-noise"), hash_str(&t.image_id)]);
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
