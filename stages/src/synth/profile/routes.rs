//! The driving routes of a trajectory table, as the error profiles need them: which recordings were driven in
//! one go (a route), how far along its route each recording lies, and its driving direction.
//!
//! Works from the true recordings alone (time order, positions, headings), so a profile can be applied to any
//! error-free campaign in the campaign format, not only to the generator's plan.

use super::Tables;
use crate::campaign::Recording;
use crate::synth::rng::{hash_str, Stream};

/// A new route starts where consecutive recordings (in time order) are more than this apart in time, s.
pub const ROUTE_TIME_GAP_S: f64 = 60.0;
/// … or more than this apart in space, m.
pub const ROUTE_DISTANCE_GAP_M: f64 = 50.0;

/// What the route-based components (outage, INS, vertical) draw their errors from: the seed, the true tables
/// and where each recording lies on its route.
#[derive(Clone, Copy, Debug)]
pub struct Draw<'a> {
    pub seed: u64,
    pub truth: &'a Tables,
    pub routes: &'a Routes,
}

impl Draw<'_> {
    /// The random stream of error component `what` on route `route` (the same for the same seed).
    pub fn route_stream(&self, what: &str, route: usize) -> Stream {
        Stream::new(&[self.seed, hash_str(what), route as u64])
    }

    /// The random stream of error component `what` for the recording `image_id`.
    pub fn recording_stream(&self, what: &str, image_id: &str) -> Stream {
        Stream::new(&[self.seed, hash_str(what), hash_str(image_id)])
    }
}

/// Where each recording lies on its route (indices refer to the table as given, not to time order).
#[derive(Clone, Debug, PartialEq)]
pub struct Routes {
    /// Route index of every recording (0, 1, … in the order the routes were driven).
    pub route_of: Vec<usize>,
    /// Distance of every recording from its route's first recording along the recordings, m.
    pub along_m: Vec<f64>,
    /// Length of every route (distance of its last recording), m.
    pub length_m: Vec<f64>,
    /// Recording indices of every route in driving (time) order.
    pub members: Vec<Vec<usize>>,
}

impl Routes {
    /// The routes of `recordings` (true positions and times).
    pub fn of(recordings: &[Recording]) -> Self {
        let mut order: Vec<usize> = (0..recordings.len()).collect();
        order.sort_by(|&a, &b| {
            recordings[a]
                .time_s
                .total_cmp(&recordings[b].time_s)
                .then_with(|| recordings[a].image_id.cmp(&recordings[b].image_id))
        });
        let n = recordings.len();
        let (mut route_of, mut along_m) = (vec![0usize; n], vec![0.0f64; n]);
        let (mut length_m, mut members): (Vec<f64>, Vec<Vec<usize>>) = (Vec::new(), Vec::new());
        let mut prev: Option<usize> = None;
        for &i in &order {
            let r = &recordings[i];
            let step = prev.map(|p| {
                let q = &recordings[p];
                ((r.x - q.x).hypot(r.y - q.y), r.time_s - q.time_s)
            });
            let new_route = match step {
                None => true,
                Some((d, dt)) => d > ROUTE_DISTANCE_GAP_M || dt > ROUTE_TIME_GAP_S,
            };
            if new_route {
                members.push(Vec::new());
                length_m.push(0.0);
            } else if let (Some(p), Some((d, _))) = (prev, step) {
                along_m[i] = along_m[p] + d;
            }
            let route = members.len() - 1;
            route_of[i] = route;
            members[route].push(i);
            length_m[route] = along_m[i];
            prev = Some(i);
        }
        Self {
            route_of,
            along_m,
            length_m,
            members,
        }
    }

    /// Number of routes.
    pub fn count(&self) -> usize {
        self.members.len()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn rec(id: &str, t: f64, x: f64, y: f64) -> Recording {
        Recording::new(id, t, [x, y, 2.0], 90.0, 2.2)
    }

    #[test]
    fn time_and_distance_gaps_split_routes_and_distances_add_up_in_time_order() {
        // Given out of order; route 1 starts an hour later, far away.
        let recs = vec![
            rec("b", 1.0, 3.0, 4.0),
            rec("a", 0.0, 0.0, 0.0),
            rec("c", 2.0, 6.0, 8.0),
            rec("d", 3600.0, 2000.0, 0.0),
            rec("e", 3601.0, 2005.0, 0.0),
        ];
        let r = Routes::of(&recs);
        assert_eq!(r.count(), 2);
        assert_eq!(r.route_of, vec![0, 0, 0, 1, 1]);
        assert_eq!(r.members, vec![vec![1, 0, 2], vec![3, 4]]);
        assert_eq!(r.along_m, vec![5.0, 0.0, 10.0, 0.0, 5.0]);
        assert_eq!(r.length_m, vec![10.0, 5.0]);
        assert_eq!(Routes::of(&[]).count(), 0);
    }
}
