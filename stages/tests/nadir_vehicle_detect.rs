//! The recording vehicle found from the panoramas alone (`nadir::vehicle_detect`): eight panoramas of the demo
//! street rendered with the synthetic car under the camera (its own box model, not the mask's), the detected
//! box is checked against where the rendered car really is: directions the car covers must be masked, and the
//! ground beyond the car must stay visible.

use nalgebra::Vector3;
use skytie_stages::geometry::PanoramaCamera;
use skytie_stages::nadir::vehicle_detect::{detect_vehicle, spread_indices, VehicleDetectParams};
use skytie_stages::synth::generate::plan_campaign;
use skytie_stages::synth::render::render_panorama_with_vehicle;
use skytie_stages::synth::scene::Epoch;
use skytie_stages::synth::vehicle::VehicleBody;
use skytie_stages::synth::{Preset, SynthOptions};

#[test]
fn the_car_is_found_where_it_was_rendered() {
    let plan = plan_campaign(&SynthOptions::new(Preset::Demo, 2)).unwrap();
    let area = &plan.areas[0];
    let picks = spread_indices(area.truth.len(), 8);
    let views: Vec<_> = picks
        .iter()
        .map(|&i| {
            let rec = &area.truth[i];
            let cam = PanoramaCamera::from_recording(rec, 720, 360);
            let body = VehicleBody::standard(rec.heading_deg, rec.camera_height_m);
            let img = render_panorama_with_vehicle(
                &area.scene,
                &cam,
                Some(&body),
                Epoch::MobileMapping,
                1,
            );
            (rec.clone(), img.to_gray())
        })
        .collect();
    let refs: Vec<_> = views.iter().map(|(r, i)| (r, i)).collect();
    let d = detect_vehicle(&refs, &VehicleDetectParams::default()).expect("a car is found");
    eprintln!("{:?} (threshold {:.4})", d.mask, d.threshold);
    // Compare with the rendered body on a fan of downward directions around a recording.
    let rec = &area.truth[picks[3]];
    let body = VehicleBody::standard(rec.heading_deg, rec.camera_height_m);
    let cam = Vector3::new(rec.x, rec.y, rec.z);
    let (mut covered, mut masked_covered, mut free, mut masked_free) = (0, 0, 0, 0);
    for az in 0..180 {
        for dep in 12..90 {
            let (a, e) = ((az as f64 * 2.0).to_radians(), (dep as f64).to_radians());
            let dir = Vector3::new(a.sin() * e.cos(), a.cos() * e.cos(), -e.sin());
            let ground = cam + dir * (rec.camera_height_m / e.sin());
            let hidden = d.mask.hides(&cam, rec.heading_deg, &ground);
            if body.hit(&dir).is_some() {
                covered += 1;
                masked_covered += hidden as usize;
            } else {
                free += 1;
                masked_free += hidden as usize;
            }
        }
    }
    let caught = masked_covered as f64 / covered as f64;
    let lost = masked_free as f64 / free as f64;
    eprintln!("car directions masked {caught:.3}, free directions masked {lost:.3}");
    assert!(caught > 0.97, "the mask misses the car: {caught}");
    assert!(lost < 0.05, "the mask hides too much ground: {lost}");
}
