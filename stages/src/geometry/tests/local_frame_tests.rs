//! Local origin: round trip and precision at RD-New-like coordinates.

use crate::geometry::LocalOrigin;
use nalgebra::Vector3;

#[test]
fn round_trip_and_mean() {
    let pts = [
        Vector3::new(92_000.125, 437_000.5, 1.0),
        Vector3::new(92_010.125, 437_004.5, 3.0),
        Vector3::new(91_990.125, 436_996.5, 2.0),
    ];
    let local = LocalOrigin::at_mean(pts.iter()).unwrap();
    assert_eq!(local.origin, Vector3::new(92_000.125, 437_000.5, 2.0));
    assert_eq!(local.to_local(&pts[1]), Vector3::new(10.0, 4.0, 1.0));
    for p in &pts {
        assert_eq!(local.to_world(&local.to_local(p)), *p);
    }
    assert_eq!(LocalOrigin::at_mean(std::iter::empty()), None);
    assert_eq!(LocalOrigin::new(Vector3::zeros()).to_local(&pts[0]), pts[0]);
}
