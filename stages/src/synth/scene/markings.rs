//! Road markings and manhole covers: layout per street (in street coordinates s along, q to the left),
//! point lookup for shading, and the exact feature points offered as check-point candidates.
//!
//! Per street segment between junctions: dashed centre line (3 m dash, 6 m gap), edge lines (solid next
//! to a parking strip, else dashed), and on every junction approach: a turn arrow in the right-hand lane,
//! a stop line across that lane, and a zebra crossing (0.5 m stripes, 1.0 m period: repetitive on purpose)
//! across the whole carriageway. Manhole covers (r = 0.3 m) sit in the lanes at a fixed spacing.

use super::epoch_draw::changed_epochs;
use super::objects::IN_BOTH;

/// Maps street coordinates (s, q) to local XY and back. Main street: s = x, q = y.
/// Cross street (crown at x = xj, running along +y): s = y, q = xj − x (left of +y is −x).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum StreetAxis {
    AlongX,
    AlongY { crown_x: f64 },
}

impl StreetAxis {
    #[inline]
    pub fn to_sq(&self, x: f64, y: f64) -> (f64, f64) {
        match *self {
            StreetAxis::AlongX => (x, y),
            StreetAxis::AlongY { crown_x } => (y, crown_x - x),
        }
    }
    #[inline]
    pub fn to_xy(&self, s: f64, q: f64) -> [f64; 2] {
        match *self {
            StreetAxis::AlongX => [s, q],
            StreetAxis::AlongY { crown_x } => [crown_x - q, s],
        }
    }
}

/// One painted element in street coordinates.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Paint {
    /// Axis-aligned rectangle (solid line, stop line).
    Rect {
        s0: f64,
        s1: f64,
        q0: f64,
        q1: f64,
        stop_line: bool,
    },
    /// Dashes of length `dash` repeating every `period` from s0 (last dash clipped to s1), centred on q.
    Dashes {
        s0: f64,
        s1: f64,
        q: f64,
        width: f64,
        dash: f64,
        period: f64,
    },
    /// Zebra: stripes of width `stripe` across q (period `period`), running along s from s0 to s1.
    Zebra {
        s0: f64,
        s1: f64,
        q0: f64,
        n_stripes: usize,
        stripe: f64,
        period: f64,
    },
    /// Straight-ahead arrow, tip at (s_tip, q), pointing to +s (dir = 1) or −s (dir = −1).
    Arrow { s_tip: f64, q: f64, dir: f64 },
}

const ARROW_HEAD_LEN: f64 = 1.0;
const ARROW_HEAD_HALF_W: f64 = 0.3;
const ARROW_SHAFT_LEN: f64 = 2.5;
const ARROW_SHAFT_HALF_W: f64 = 0.08;
/// Manhole cover radius, m.
pub const MANHOLE_RADIUS_M: f64 = 0.3;

impl Paint {
    /// Street-coordinate bounding box (s_lo, s_hi, q_lo, q_hi).
    fn bbox(&self) -> (f64, f64, f64, f64) {
        match *self {
            Paint::Rect { s0, s1, q0, q1, .. } => (s0, s1, q0, q1),
            Paint::Dashes {
                s0, s1, q, width, ..
            } => (s0, s1, q - 0.5 * width, q + 0.5 * width),
            Paint::Zebra {
                s0,
                s1,
                q0,
                n_stripes,
                period,
                stripe,
            } => (
                s0,
                s1,
                q0,
                q0 + (n_stripes.max(1) - 1) as f64 * period + stripe,
            ),
            Paint::Arrow { s_tip, q, dir } => {
                let tail = s_tip - dir * (ARROW_HEAD_LEN + ARROW_SHAFT_LEN);
                (
                    s_tip.min(tail),
                    s_tip.max(tail),
                    q - ARROW_HEAD_HALF_W,
                    q + ARROW_HEAD_HALF_W,
                )
            }
        }
    }

    fn contains(&self, s: f64, q: f64) -> bool {
        match *self {
            Paint::Rect { .. } => true, // bbox already checked
            Paint::Dashes {
                s0, dash, period, ..
            } => (s - s0).rem_euclid(period) < dash,
            Paint::Zebra {
                q0, period, stripe, ..
            } => (q - q0).rem_euclid(period) < stripe,
            Paint::Arrow { s_tip, q: qc, dir } => {
                let u = (s_tip - s) * dir; // distance behind the tip
                let v = (q - qc).abs();
                if u < 0.0 {
                    false
                } else if u <= ARROW_HEAD_LEN {
                    v <= ARROW_HEAD_HALF_W * u / ARROW_HEAD_LEN
                } else {
                    u <= ARROW_HEAD_LEN + ARROW_SHAFT_LEN && v <= ARROW_SHAFT_HALF_W
                }
            }
        }
    }

    /// Feature points (s, q, kind) of this element.
    fn features(&self, out: &mut Vec<(&'static str, f64, f64)>) {
        match *self {
            Paint::Rect {
                s0,
                s1,
                q0,
                q1,
                stop_line,
            } => {
                if stop_line {
                    for (s, q) in [(s0, q0), (s1, q0), (s0, q1), (s1, q1)] {
                        out.push(("stop_line_corner", s, q));
                    }
                }
            }
            Paint::Dashes {
                s0,
                s1,
                q,
                dash,
                period,
                ..
            } => {
                let mut a = s0;
                while a + dash <= s1 + 1e-9 {
                    out.push(("dash_end", a, q));
                    out.push(("dash_end", a + dash, q));
                    a += period;
                }
            }
            Paint::Zebra {
                s0,
                s1,
                q0,
                n_stripes,
                stripe,
                period,
            } => {
                for k in 0..n_stripes {
                    let qa = q0 + k as f64 * period;
                    for (s, q) in [(s0, qa), (s1, qa), (s0, qa + stripe), (s1, qa + stripe)] {
                        out.push(("zebra_corner", s, q));
                    }
                }
            }
            Paint::Arrow { s_tip, q, .. } => out.push(("arrow_tip", s_tip, q)),
        }
    }
}

/// What the ground shows at a point.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum GroundMark {
    None,
    Paint,
    /// Manhole cover; offset of the point from the cover's centre in street coordinates (m).
    Manhole {
        ds: f64,
        dq: f64,
    },
    /// Fresh asphalt of roadworks (covers any marking).
    Roadworks,
}

/// Layout inputs for one street's markings.
#[derive(Clone, Debug)]
pub struct StreetMarkingInput {
    pub axis: StreetAxis,
    /// Marked range along s.
    pub s_range: (f64, f64),
    pub half_width_m: f64,
    pub parking_width_m: f64,
    /// Junctions on this street: (s of the crossing crown, half width of the crossing carriageway).
    pub junctions: Vec<(f64, f64)>,
    pub paint: bool,
    pub manhole_spacing_m: f64,
    /// Seed-derived phase for the manholes (0..1).
    pub manhole_phase: f64,
}

/// A painted element with its bounding box (s_min, s_max, q_min, q_max in street coordinates, m) and the epochs
/// it is painted in.
type PlacedPaint = (Paint, (f64, f64, f64, f64), u8);

/// All markings of one street.
#[derive(Clone, Debug)]
pub struct StreetMarkings {
    pub axis: StreetAxis,
    half_width_m: f64,
    /// Each element with its bounding box and the epochs it is painted in.
    paints: Vec<PlacedPaint>,
    manholes: Vec<(f64, f64)>,
}

impl StreetMarkings {
    pub fn layout(inp: &StreetMarkingInput) -> Self {
        let hw = inp.half_width_m;
        let lane_edge = if inp.parking_width_m > 0.0 {
            hw - inp.parking_width_m
        } else {
            hw - 0.3
        };
        let lane_centre = 0.5 * lane_edge;
        let mut paints = Vec::new();
        let mut manholes = Vec::new();
        let (s_lo, s_hi) = inp.s_range;
        // segments between junctions
        let mut cuts: Vec<(f64, f64)> = inp.junctions.clone();
        cuts.sort_by(|a, b| a.0.total_cmp(&b.0));
        let mut bounds: Vec<(f64, bool, f64, bool)> = Vec::new(); // (a, a_is_junction, b, b_is_junction)
        let mut a = s_lo;
        let mut a_j = false;
        for &(sj, hj) in &cuts {
            let b = sj - hj;
            if b > a {
                bounds.push((a, a_j, b, true));
            }
            a = sj + hj;
            a_j = true;
        }
        if s_hi > a {
            bounds.push((a, a_j, s_hi, false));
        }
        for &(a, a_j, b, b_j) in &bounds {
            let mut line_a = a + 0.5;
            let mut line_b = b - 0.5;
            let mut zone_a = a;
            let mut zone_b = b;
            if inp.paint && b_j && b - a > 25.0 {
                // approach towards +s ends at b: arrow, stop line (right lane q < 0), zebra
                let z1 = b - 1.0;
                let z0 = z1 - 4.0;
                paints.push(zebra_crossing(z0, z1, hw));
                let st1 = z0 - 1.5;
                let st0 = st1 - 0.3;
                paints.push(Paint::Rect {
                    s0: st0,
                    s1: st1,
                    q0: -lane_edge + 0.05,
                    q1: -0.1,
                    stop_line: true,
                });
                paints.push(Paint::Arrow {
                    s_tip: st0 - 2.0,
                    q: -lane_centre,
                    dir: 1.0,
                });
                line_b = st0 - 0.5;
                zone_b = st0 - 8.0;
            }
            if inp.paint && a_j && b - a > 25.0 {
                let z0 = a + 1.0;
                let z1 = z0 + 4.0;
                paints.push(zebra_crossing(z0, z1, hw));
                let st0 = z1 + 1.5;
                let st1 = st0 + 0.3;
                paints.push(Paint::Rect {
                    s0: st0,
                    s1: st1,
                    q0: 0.1,
                    q1: lane_edge - 0.05,
                    stop_line: true,
                });
                paints.push(Paint::Arrow {
                    s_tip: st1 + 2.0,
                    q: lane_centre,
                    dir: -1.0,
                });
                line_a = st1 + 0.5;
                zone_a = st1 + 8.0;
            }
            if inp.paint && line_b - line_a > 3.0 {
                paints.push(Paint::Dashes {
                    s0: line_a,
                    s1: line_b,
                    q: 0.0,
                    width: 0.10,
                    dash: 3.0,
                    period: 9.0,
                });
                for side in [-1.0, 1.0] {
                    let q = side * lane_edge;
                    if inp.parking_width_m > 0.0 {
                        paints.push(Paint::Rect {
                            s0: line_a,
                            s1: line_b,
                            q0: q - 0.05,
                            q1: q + 0.05,
                            stop_line: false,
                        });
                    } else {
                        paints.push(Paint::Dashes {
                            s0: line_a,
                            s1: line_b,
                            q,
                            width: 0.10,
                            dash: 1.0,
                            period: 2.0,
                        });
                    }
                }
            }
            if inp.manhole_spacing_m > 0.0 {
                let sp = inp.manhole_spacing_m;
                let mut s = zone_a + 2.0 + inp.manhole_phase * sp;
                let mut k = 0;
                while s < zone_b - 2.0 {
                    let q = if k % 2 == 0 {
                        0.45 * lane_edge
                    } else {
                        -0.6 * lane_edge
                    };
                    manholes.push((s, q));
                    s += sp;
                    k += 1;
                }
            }
        }
        let paints = paints.into_iter().map(|p| (p, p.bbox(), IN_BOTH)).collect();
        Self {
            axis: inp.axis,
            half_width_m: hw,
            paints,
            manholes,
        }
    }

    /// Make a `fraction` of the painted elements present in one epoch only (repainted or removed between the
    /// epochs); which ones and in which epoch is hashed from (`seed`, `street`, element index).
    pub fn vary_epochs(&mut self, seed: u64, street: usize, fraction: f64) {
        for (k, (_, _, epochs)) in self.paints.iter_mut().enumerate() {
            let key = (street as u64) << 32 | k as u64;
            if let Some(e) = changed_epochs(seed, 0x9A17, key, fraction) {
                *epochs = e;
            }
        }
    }

    /// The mark at street coordinates (s, q) in the epoch(s) `epoch_bits` (`IN_MM`, `IN_AERIAL`).
    pub fn mark_at(&self, s: f64, q: f64, epoch_bits: u8) -> GroundMark {
        if q.abs() > self.half_width_m {
            return GroundMark::None;
        }
        for &(s0, q0) in &self.manholes {
            let (ds, dq) = (s - s0, q - q0);
            if ds * ds + dq * dq <= MANHOLE_RADIUS_M * MANHOLE_RADIUS_M {
                return GroundMark::Manhole { ds, dq };
            }
        }
        for (p, (sl, sh, ql, qh), epochs) in &self.paints {
            if epochs & epoch_bits != 0
                && s >= *sl
                && s <= *sh
                && q >= *ql
                && q <= *qh
                && p.contains(s, q)
            {
                return GroundMark::Paint;
            }
        }
        GroundMark::None
    }

    /// Feature points in local XY with their kind (of elements painted in both epochs).
    pub fn features_local(&self) -> Vec<(&'static str, [f64; 2])> {
        let mut f = Vec::new();
        for (p, _, epochs) in &self.paints {
            if *epochs == IN_BOTH {
                p.features(&mut f);
            }
        }
        let mut out: Vec<(&'static str, [f64; 2])> = f
            .into_iter()
            .map(|(k, s, q)| (k, self.axis.to_xy(s, q)))
            .collect();
        for &(s, q) in &self.manholes {
            out.push(("manhole_centre", self.axis.to_xy(s, q)));
        }
        out
    }
}

/// A zebra crossing from `s0` to `s1` along the street across a carriageway of half width `hw`: 0.5 m stripes
/// every metre, centred on the axis, 0.3 m clear of each kerb.
fn zebra_crossing(s0: f64, s1: f64, hw: f64) -> Paint {
    let n = ((2.0 * (hw - 0.3)) / 1.0).floor() as usize;
    Paint::Zebra {
        s0,
        s1,
        q0: -(n as f64 - 1.0) * 0.5 - 0.25,
        n_stripes: n,
        stripe: 0.5,
        period: 1.0,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn street() -> StreetMarkings {
        StreetMarkings::layout(&StreetMarkingInput {
            axis: StreetAxis::AlongX,
            s_range: (0.0, 200.0),
            half_width_m: 4.5,
            parking_width_m: 2.0,
            junctions: vec![(120.0, 4.0)],
            paint: true,
            manhole_spacing_m: 30.0,
            manhole_phase: 0.3,
        })
    }

    #[test]
    fn zebra_stripes_and_dashes_are_where_laid_out() {
        let m = street();
        // zebra before the junction: s in [111, 115]
        let mut stripes = 0;
        let mut prev = false;
        for i in 0..900 {
            let q = -4.5 + i as f64 * 0.01;
            let on = m.mark_at(113.0, q, IN_BOTH) == GroundMark::Paint;
            if on && !prev {
                stripes += 1;
            }
            prev = on;
        }
        assert_eq!(stripes, 8);
        // first dash starts at s = 0.5 on the crown
        assert_eq!(m.mark_at(0.6, 0.0, IN_BOTH), GroundMark::Paint);
        assert_eq!(m.mark_at(3.6, 0.0, IN_BOTH), GroundMark::None);
        assert_eq!(m.mark_at(9.6, 0.0, IN_BOTH), GroundMark::Paint);
        // stop line corner is exactly on the paint boundary; its inside is painted
        let f = m.features_local();
        let stop: Vec<_> = f.iter().filter(|(k, _)| *k == "stop_line_corner").collect();
        assert_eq!(stop.len(), 8);
        let arrows: Vec<_> = f.iter().filter(|(k, _)| *k == "arrow_tip").collect();
        assert_eq!(arrows.len(), 2);
        // just behind the arrow tip (towards −s for dir +1) is paint, in front is not
        let tip = arrows.iter().find(|(_, p)| p[0] < 120.0).unwrap().1;
        assert_eq!(m.mark_at(tip[0] - 0.05, tip[1], IN_BOTH), GroundMark::Paint);
        assert_eq!(m.mark_at(tip[0] + 0.05, tip[1], IN_BOTH), GroundMark::None);
        assert!(f.iter().any(|(k, _)| *k == "manhole_centre"));
    }

    #[test]
    fn cross_street_axis_round_trips() {
        let a = StreetAxis::AlongY { crown_x: 120.0 };
        let (s, q) = a.to_sq(118.0, -30.0);
        assert_eq!((s, q), (-30.0, 2.0));
        assert_eq!(a.to_xy(s, q), [118.0, -30.0]);
    }
}
