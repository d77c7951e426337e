//! The reference ellipsoid: geodetic (latitude, longitude, ellipsoidal height) ↔ earth-centred earth-fixed
//! (ECEF) coordinates, radii of curvature, and a local tangent east-north-up frame — a Cartesian frame in
//! metres around an origin, in which ray intersections and adjustments are free of map-projection scale and
//! earth curvature.

use nalgebra::{Matrix3, Vector3};

/// An ellipsoid of revolution by its semi-axes (metres).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Ellipsoid {
    /// Semi-major axis, m.
    pub a_m: f64,
    /// Semi-minor axis, m.
    pub b_m: f64,
}

impl Ellipsoid {
    /// GRS 1980 (ETRS89, NAD83).
    pub const GRS80: Self = Self {
        a_m: 6_378_137.0,
        b_m: 6_356_752.314_140_347,
    };

    /// An ellipsoid from its semi-axes.
    pub fn from_axes(a_m: f64, b_m: f64) -> Self {
        Self { a_m, b_m }
    }

    /// First eccentricity squared e² = (a² − b²)/a².
    pub fn e2(&self) -> f64 {
        (self.a_m * self.a_m - self.b_m * self.b_m) / (self.a_m * self.a_m)
    }

    /// Radius of curvature in the prime vertical N(φ), m.
    pub fn prime_vertical_radius_m(&self, lat_deg: f64) -> f64 {
        let s = lat_deg.to_radians().sin();
        self.a_m / (1.0 - self.e2() * s * s).sqrt()
    }

    /// Radius of curvature in the meridian M(φ), m.
    pub fn meridian_radius_m(&self, lat_deg: f64) -> f64 {
        let s = lat_deg.to_radians().sin();
        let e2 = self.e2();
        self.a_m * (1.0 - e2) / (1.0 - e2 * s * s).powf(1.5)
    }

    /// Geodetic → ECEF (m).
    pub fn to_ecef(&self, lat_deg: f64, lon_deg: f64, h_m: f64) -> Vector3<f64> {
        let (sp, cp) = lat_deg.to_radians().sin_cos();
        let (sl, cl) = lon_deg.to_radians().sin_cos();
        let n = self.prime_vertical_radius_m(lat_deg);
        Vector3::new(
            (n + h_m) * cp * cl,
            (n + h_m) * cp * sl,
            (n * (1.0 - self.e2()) + h_m) * sp,
        )
    }

    /// ECEF → geodetic (latitude °, longitude °, ellipsoidal height m), iterated to 1e-14 rad.
    pub fn from_ecef(&self, p: &Vector3<f64>) -> (f64, f64, f64) {
        let e2 = self.e2();
        let lon = p.y.atan2(p.x);
        let rho = p.x.hypot(p.y);
        let mut lat = p.z.atan2(rho * (1.0 - e2));
        let mut h = 0.0;
        for _ in 0..20 {
            let s = lat.sin();
            let n = self.a_m / (1.0 - e2 * s * s).sqrt();
            // Stable at every latitude: h = ρ cos φ + (z + e² N sin φ) sin φ − N.
            h = rho * lat.cos() + (p.z + e2 * n * s) * s - n;
            let next = p.z.atan2(rho * (1.0 - e2 * n / (n + h)));
            let done = (next - lat).abs() < 1e-14;
            lat = next;
            if done {
                break;
            }
        }
        (lat.to_degrees(), lon.to_degrees(), h)
    }

    /// Rotation whose columns are the east, north and up unit vectors at (lat, lon), in ECEF: maps ENU vectors
    /// to ECEF vectors.
    pub fn enu_to_ecef(lat_deg: f64, lon_deg: f64) -> Matrix3<f64> {
        let (sp, cp) = lat_deg.to_radians().sin_cos();
        let (sl, cl) = lon_deg.to_radians().sin_cos();
        Matrix3::new(-sl, -sp * cl, cp * cl, cl, -sp * sl, cp * sl, 0.0, cp, sp)
    }
}

/// A local tangent frame: x east, y north, z up at the origin, metres, Cartesian.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LocalTangentFrame {
    pub ellipsoid: Ellipsoid,
    /// Origin, geodetic (°, °, m).
    pub origin_lat_deg: f64,
    pub origin_lon_deg: f64,
    pub origin_h_m: f64,
    origin_ecef: Vector3<f64>,
    /// ENU → ECEF at the origin.
    enu_to_ecef: Matrix3<f64>,
}

impl LocalTangentFrame {
    /// The tangent frame at a geodetic origin.
    pub fn new(ellipsoid: Ellipsoid, lat_deg: f64, lon_deg: f64, h_m: f64) -> Self {
        Self {
            ellipsoid,
            origin_lat_deg: lat_deg,
            origin_lon_deg: lon_deg,
            origin_h_m: h_m,
            origin_ecef: ellipsoid.to_ecef(lat_deg, lon_deg, h_m),
            enu_to_ecef: Ellipsoid::enu_to_ecef(lat_deg, lon_deg),
        }
    }

    /// Geodetic → local (m).
    pub fn from_geodetic(&self, lat_deg: f64, lon_deg: f64, h_m: f64) -> Vector3<f64> {
        self.enu_to_ecef.transpose()
            * (self.ellipsoid.to_ecef(lat_deg, lon_deg, h_m) - self.origin_ecef)
    }

    /// Local (m) → geodetic (°, °, m).
    pub fn to_geodetic(&self, p_local: &Vector3<f64>) -> (f64, f64, f64) {
        self.ellipsoid
            .from_ecef(&(self.origin_ecef + self.enu_to_ecef * p_local))
    }

    /// Rotation mapping ENU vectors at a geodetic point to vectors of this local frame.
    pub fn enu_at(&self, lat_deg: f64, lon_deg: f64) -> Matrix3<f64> {
        self.enu_to_ecef.transpose() * Ellipsoid::enu_to_ecef(lat_deg, lon_deg)
    }
}
