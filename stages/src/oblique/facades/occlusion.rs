//! Occlusion test of a façade plane (thesis 4.4.2, Fig. 4.5): sparse points between the plane and the centre
//! recording.
//!
//! Corridor: a point q occludes when it lies in front of the plane by more than the inlier band, nearer to the
//! plane than the recording (band < e_q < e_rec, e = signed distance along the normal, which points towards
//! the recording), and the sight line from the recording through q meets the plane inside the rectangle that
//! the inliers span in the plane's horizontal / vertical in-plane axes (the caller passes them). Ground points in front of the façade project
//! below the inliers and do not count; points of the other side or behind the recording never do.

use nalgebra::Vector3;

/// The plane in the frame of the points (any frame, metres), with its inliers' rectangle.
#[derive(Clone, Debug, PartialEq)]
pub struct OcclusionCorridor {
    pub centroid: Vector3<f64>,
    /// Unit normal pointing towards the recording.
    pub normal: Vector3<f64>,
    pub axis_u: Vector3<f64>,
    pub axis_v: Vector3<f64>,
    /// Extent of the inliers along `axis_u` and `axis_v` relative to the centroid: [min, max], m.
    pub u_range: [f64; 2],
    pub v_range: [f64; 2],
    pub band_m: f64,
}

impl OcclusionCorridor {
    /// The corridor of a plane whose inliers are `inliers`.
    pub fn new(
        centroid: Vector3<f64>,
        normal: Vector3<f64>,
        axis_u: Vector3<f64>,
        axis_v: Vector3<f64>,
        inliers: impl IntoIterator<Item = Vector3<f64>>,
        band_m: f64,
    ) -> Self {
        let mut u_range = [f64::INFINITY, f64::NEG_INFINITY];
        let mut v_range = [f64::INFINITY, f64::NEG_INFINITY];
        for p in inliers {
            let q = p - centroid;
            let (u, v) = (q.dot(&axis_u), q.dot(&axis_v));
            u_range = [u_range[0].min(u), u_range[1].max(u)];
            v_range = [v_range[0].min(v), v_range[1].max(v)];
        }
        Self {
            centroid,
            normal,
            axis_u,
            axis_v,
            u_range,
            v_range,
            band_m,
        }
    }

    /// True if `q` occludes the plane as seen from `recording` (module documentation).
    pub fn occludes(&self, recording: &Vector3<f64>, q: &Vector3<f64>) -> bool {
        let e_rec = self.normal.dot(&(recording - self.centroid));
        let e_q = self.normal.dot(&(q - self.centroid));
        if !(e_q > self.band_m && e_q < e_rec) {
            return false;
        }
        // Sight line recording → q, continued to the plane (e = 0).
        let hit = recording + (q - recording) * (e_rec / (e_rec - e_q)) - self.centroid;
        let (u, v) = (hit.dot(&self.axis_u), hit.dot(&self.axis_v));
        u >= self.u_range[0] && u <= self.u_range[1] && v >= self.v_range[0] && v <= self.v_range[1]
    }

    /// Number of `points` that occlude the plane as seen from `recording`.
    pub fn count(&self, recording: &Vector3<f64>, points: &[Vector3<f64>]) -> usize {
        points
            .iter()
            .filter(|q| self.occludes(recording, q))
            .count()
    }
}
