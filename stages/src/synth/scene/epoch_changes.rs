//! What differs between the aerial and the mobile-mapping epoch beyond sun and parked cars, when a campaign's
//! error profile asks for it (`epoch`): road markings repainted or removed, roadworks (a patch of fresh asphalt
//! over one lane with traffic cones along it), and tree crowns grown by the time of the flight. Every choice is
//! hashed from the scene seed and the element's index, so the rest of the scene is the same as without changes.

use super::epoch_draw::{changed_epochs, draw};
use super::markings::StreetAxis;
use super::objects::{Material, Object, Shape, IN_MM};

/// The knobs (a [`super::SceneSpec`] field; `None` = no such changes).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct EpochChangeSpec {
    /// Fraction of the painted elements present in one epoch only.
    pub changed_marking_fraction: f64,
    /// Roadworks patches per street.
    pub roadworks_per_street: usize,
    /// Tree crowns of the aerial epoch are larger by this radius, m.
    pub crown_growth_m: f64,
}

/// A roadworks patch in the street coordinates of street `street`: fresh asphalt over s × q, in `epochs`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Roadworks {
    pub street: usize,
    pub s_m: (f64, f64),
    pub q_m: (f64, f64),
    pub epochs: u8,
}

impl Roadworks {
    /// Whether street coordinates (s, q) of its street lie on the patch.
    pub fn contains(&self, s: f64, q: f64) -> bool {
        (self.s_m.0..=self.s_m.1).contains(&s) && (self.q_m.0..=self.q_m.1).contains(&q)
    }
}

/// Orange of the cones.
const CONE_RGB: [f32; 3] = [0.80, 0.22, 0.04];
/// Cone radius and height, m.
const CONE_RADIUS_M: f64 = 0.16;
const CONE_HEIGHT_M: f64 = 0.7;
/// Spacing of the cones along the patch, m.
const CONE_SPACING_M: f64 = 2.0;

/// Roadworks of one street marked along s in `s_range` with carriageway half width `half_width_m`: each
/// 8–14 m long over the left-hand (oncoming) lane, so the recording car's lane stays free.
pub fn place_roadworks(
    spec: &EpochChangeSpec,
    seed: u64,
    street: usize,
    s_range: (f64, f64),
    half_width_m: f64,
) -> Vec<Roadworks> {
    (0..spec.roadworks_per_street)
        .filter_map(|k| {
            let key = (street as u64) << 16 | k as u64;
            let length = 8.0 + 6.0 * draw(seed, 0xF0AD, key);
            let room = s_range.1 - s_range.0 - length - 10.0;
            (room > 0.0).then(|| Roadworks {
                street,
                s_m: {
                    let s0 = s_range.0 + 5.0 + room * draw(seed, 0xF0AE, key);
                    (s0, s0 + length)
                },
                q_m: (0.2, half_width_m - 0.3),
                epochs: changed_epochs(seed, 0xF0AF, key, 1.0).unwrap_or(IN_MM),
            })
        })
        .collect()
}

/// Traffic cones along both long sides of a patch (world heights from `ground_z(x, y)`).
pub fn cones(r: &Roadworks, axis: StreetAxis, ground_z: impl Fn(f64, f64) -> f64) -> Vec<Object> {
    let mut out = Vec::new();
    let n = ((r.s_m.1 - r.s_m.0) / CONE_SPACING_M).floor() as usize;
    for q in [r.q_m.0, r.q_m.1] {
        for i in 0..=n {
            let [x, y] = axis.to_xy(r.s_m.0 + i as f64 * CONE_SPACING_M, q);
            let z = ground_z(x, y);
            out.push(Object::new(
                Shape::Cylinder {
                    cx: x,
                    cy: y,
                    r: CONE_RADIUS_M,
                    z0: z,
                    z1: z + CONE_HEIGHT_M,
                },
                Material::CarBody { rgb: CONE_RGB },
                r.epochs,
            ));
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::synth::scene::objects::IN_AERIAL;

    #[test]
    fn roadworks_lie_on_the_oncoming_lane_within_the_street_and_have_one_epoch() {
        let spec = EpochChangeSpec {
            changed_marking_fraction: 0.0,
            roadworks_per_street: 3,
            crown_growth_m: 0.0,
        };
        let rw = place_roadworks(&spec, 7, 0, (0.0, 200.0), 4.5);
        assert_eq!(rw.len(), 3);
        for r in &rw {
            assert!(r.s_m.0 >= 5.0 && r.s_m.1 <= 195.0 && r.s_m.1 - r.s_m.0 >= 8.0);
            assert!(r.q_m.0 > 0.0 && r.q_m.1 < 4.5);
            assert!(r.epochs == IN_MM || r.epochs == IN_AERIAL);
            let c = cones(r, StreetAxis::AlongX, |_, _| 1.0);
            assert!(c.len() >= 10 && c.iter().all(|o| o.epochs == r.epochs));
        }
        assert!(
            place_roadworks(&spec, 7, 0, (0.0, 15.0), 4.5).is_empty(),
            "no room"
        );
        // About the asked fraction of elements changes.
        let n = (0..10_000)
            .filter(|&i| changed_epochs(3, 1, i, 0.15).is_some())
            .count();
        assert!((1300..1700).contains(&n), "{n}");
    }
}
