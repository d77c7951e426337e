//! Render throughput of the synthetic campaign (`cargo bench -p skytie-stages --bench render`).
//!
//! 1. Per image kind (panorama, nadir, oblique) of the `demo` scene: primary rays per second.
//! 2. Whole `tiny` and `demo` generation: wall time and primary rays per second (set
//!    `SKYTIE_BENCH_SKIP_DEMO=1` to skip the demo generation; `SKYTIE_BENCH_KINDS_ONLY=1` stops after 1.).
//! 3. `paper`: an ESTIMATE, not a measurement of the whole preset: one paper panorama, one nadir and one
//!    oblique frame are rendered and timed, and the totals are extrapolated by the image counts of the plan.

use nalgebra::Vector3;
use skytie_stages::geometry::{FrameCamera, PanoramaCamera};
use skytie_stages::synth::generate::{plan_campaign, CampaignPlan};
use skytie_stages::synth::render::{primary_rays, render_frame, render_panorama_with_vehicle};
use skytie_stages::synth::scene::Epoch;
use skytie_stages::synth::vehicle::VehicleBody;
use skytie_stages::synth::{generate, Preset, SynthOptions};
use std::time::Instant;

/// Seconds and primary rays of rendering one panorama, one nadir and one oblique of `plan`'s first area.
fn time_one_of_each(plan: &CampaignPlan) -> [(f64, u64); 3] {
    let p = &plan.params;
    let area = &plan.areas[0];
    let rec = &area.truth[area.truth.len() / 2];
    let cam = PanoramaCamera::new(
        p.panorama_width_px,
        p.panorama_height_px(),
        Vector3::new(rec.x, rec.y, rec.z),
        rec.yaw_deg,
        rec.pitch_deg,
        rec.roll_deg,
    );
    let vehicle = VehicleBody::standard(rec.heading_deg, rec.camera_height_m);
    let t = Instant::now();
    std::hint::black_box(render_panorama_with_vehicle(
        &area.scene,
        &cam,
        Some(&vehicle),
        Epoch::MobileMapping,
        p.panorama_spp_axis,
    ));
    let pano = (
        t.elapsed().as_secs_f64(),
        primary_rays(cam.width_px, cam.height_px, p.panorama_spp_axis),
    );
    let frame = |a: &skytie_stages::campaign::AerialImage| {
        let cam = FrameCamera::from_aerial(a);
        let t = Instant::now();
        std::hint::black_box(render_frame(
            &area.scene,
            &cam,
            Epoch::Aerial,
            p.aerial_spp_axis,
        ));
        (
            t.elapsed().as_secs_f64(),
            primary_rays(a.width_px, a.height_px, p.aerial_spp_axis),
        )
    };
    let nadir = frame(&area.nadir[area.nadir.len() / 2]);
    let oblique = frame(&area.oblique[area.oblique.len() / 2]);
    [pano, nadir, oblique]
}

fn report_kinds(label: &str, kinds: &[(f64, u64); 3]) {
    for (name, (s, rays)) in ["panorama", "nadir", "oblique"].iter().zip(kinds) {
        println!(
            "{label} {name:9}: {s:7.2} s for {rays:>10} primary rays = {:.3e} rays/s",
            *rays as f64 / s.max(1e-9)
        );
    }
}

fn main() {
    let threads = rayon::current_num_threads();
    println!("render bench: {threads} rayon threads");

    let demo = plan_campaign(&SynthOptions::new(Preset::Demo, 1)).expect("plan demo");
    report_kinds("demo ", &time_one_of_each(&demo));
    if std::env::var_os("SKYTIE_BENCH_KINDS_ONLY").is_some() {
        return;
    }

    // SKYTIE_BENCH_KEEP=DIR keeps the generated campaigns in DIR (for inspection) instead of a temp folder.
    let tmp = tempfile::tempdir().expect("temp dir");
    let keep = std::env::var_os("SKYTIE_BENCH_KEEP").map(std::path::PathBuf::from);
    let dir_path = keep.as_deref().unwrap_or(tmp.path());
    let skip_demo = std::env::var_os("SKYTIE_BENCH_SKIP_DEMO").is_some();
    let presets: &[Preset] = if skip_demo {
        &[Preset::Tiny]
    } else {
        &[Preset::Tiny, Preset::Demo]
    };
    for &preset in presets {
        let out = dir_path.join(preset.name());
        let s = generate(&SynthOptions::new(preset, 1), &out).expect("generate");
        println!(
            "generate {:5}: {:7.2} s wall ({:.2} s rendering), {} panoramas + {} nadir + {} oblique, \
             {} primary rays = {:.3e} rays/s",
            preset.name(),
            s.seconds,
            s.render_seconds,
            s.recordings,
            s.nadir_images,
            s.oblique_images,
            s.primary_rays,
            s.rays_per_second()
        );
    }

    let paper = plan_campaign(&SynthOptions::new(Preset::Paper, 1)).expect("plan paper");
    let kinds = time_one_of_each(&paper);
    report_kinds("paper", &kinds);
    let n_pano: usize = paper.areas.iter().map(|a| a.truth.len()).sum();
    let n_nadir: usize = paper.areas.iter().map(|a| a.nadir.len()).sum();
    let n_obl: usize = paper.areas.iter().map(|a| a.oblique.len()).sum();
    let est = n_pano as f64 * kinds[0].0 + n_nadir as f64 * kinds[1].0 + n_obl as f64 * kinds[2].0;
    println!(
        "paper ESTIMATE (extrapolated from one image of each kind, not measured): {n_pano} panoramas + \
         {n_nadir} nadir + {n_obl} oblique ≈ {est:.0} s ≈ {:.1} h rendering",
        est / 3600.0
    );
}
