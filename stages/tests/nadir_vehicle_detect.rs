//! The recording vehicle found from the panoramas alone (`nadir::vehicle_detect`): eight panoramas of the demo
//! street rendered with the synthetic car under the camera (its own box model, not the mask's), the detected
//! box is checked against where the rendered car really is: ground the car hides must be masked, and no more of
//! the visible ground than by the hand-made box of the car's silhouette.

use nalgebra::Vector3;
use skytie_stages::geometry::PanoramaCamera;
use skytie_stages::nadir::vehicle_detect::{detect_vehicle, spread_indices, VehicleDetectParams};
use skytie_stages::nadir::VehicleMask;
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
    // Compare with the rendered body on the ground around a recording (the 30 m ortho square): ground points
    // the car hides must be masked; of the visible ground, the box may hide no more than the hand-made box of
    // the synthetic car's silhouette (the default mask) does, plus 1 %.
    let rec = &area.truth[picks[3]];
    let body = VehicleBody::standard(rec.heading_deg, rec.camera_height_m);
    let cam = Vector3::new(rec.x, rec.y, rec.z);
    let hand_made = VehicleMask::default();
    let (mut hidden, mut caught, mut visible, mut lost, mut lost_hand) = (0, 0, 0, 0, 0);
    for i in -150..150 {
        for j in -150..150 {
            let g = Vector3::new(
                rec.x + i as f64 * 0.05,
                rec.y + j as f64 * 0.05,
                rec.z - rec.camera_height_m,
            );
            let dir = (g - cam).normalize();
            let masked = d.mask.hides(&cam, rec.heading_deg, &g);
            if body.hit(&dir).is_some() {
                hidden += 1;
                caught += masked as usize;
            } else {
                visible += 1;
                lost += masked as usize;
                lost_hand += hand_made.hides(&cam, rec.heading_deg, &g) as usize;
            }
        }
    }
    let (caught, lost, lost_hand) = (
        caught as f64 / hidden as f64,
        lost as f64 / visible as f64,
        lost_hand as f64 / visible as f64,
    );
    eprintln!("hidden ground masked {caught:.4}; visible ground masked {lost:.4} (hand-made box {lost_hand:.4})");
    assert!(caught > 0.99, "the mask misses the car: {caught}");
    assert!(
        lost <= lost_hand + 0.01,
        "the mask hides too much ground: {lost} vs {lost_hand}"
    );
    for (got, want) in [
        (d.mask.front_m, hand_made.front_m),
        (d.mask.rear_m, hand_made.rear_m),
        (d.mask.half_width_m, hand_made.half_width_m),
    ] {
        assert!(
            (got - want).abs() < 0.1,
            "{:?} vs the hand-made {hand_made:?}",
            d.mask
        );
    }
}
