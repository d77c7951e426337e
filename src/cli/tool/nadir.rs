//! `skytie tool` building blocks of the nadir pipeline (thesis ch. 3): ortho, kaze, forstner, wallis, phasecorr,
//! ncc.

use super::{campaign_recording, option_errors, read_gray, write_listing};
use clap::Args;
use skytie_stages::features::forstner::{forstner_corners, ForstnerParams};
use skytie_stages::features::kaze::{detect_and_describe, KazeParams};
use skytie_stages::imaging::io::save_gray;
use skytie_stages::imaging::wallis::{wallis_filter, WallisParams};
use skytie_stages::matching::ncc::match_template;
use skytie_stages::matching::phase_correlation::{phase_correlate, PhaseCorrelationParams};
use skytie_stages::nadir::{ortho_project_whole, OrthoParams};
use skytie_stages::params::Params;
use std::fmt::Write as _;
use std::path::PathBuf;

#[derive(Args, Debug)]
pub struct OrthoArgs {
    #[arg(long)]
    pub campaign: PathBuf,
    #[arg(long)]
    pub recording: String,
    /// Ground pixel spacing, m.
    #[arg(long, default_value_t = 0.03)]
    pub gsd: f64,
    /// Azimuth of the image's up direction, degrees clockwise from grid north.
    #[arg(long, default_value_t = 0.0)]
    pub rotate_deg: f64,
    /// Do not mask the recording vehicle.
    #[arg(long)]
    pub no_mask: bool,
    #[arg(long)]
    pub out: PathBuf,
}

#[derive(Args, Debug)]
pub struct KazeArgs {
    pub image: PathBuf,
    #[arg(long, default_value_t = 0.001)]
    pub threshold: f32,
    #[arg(long, default_value_t = 4)]
    pub octaves: usize,
    #[arg(long)]
    pub upright: bool,
    #[arg(long)]
    pub extended: bool,
    /// Append the descriptor values to each row.
    #[arg(long)]
    pub descriptors: bool,
    #[arg(long)]
    pub out: PathBuf,
}

#[derive(Args, Debug)]
pub struct ForstnerArgs {
    pub image: PathBuf,
    /// Keep at most this many corners (strongest first).
    #[arg(long)]
    pub max: Option<usize>,
    #[arg(long)]
    pub out: PathBuf,
}

#[derive(Args, Debug)]
pub struct WallisArgs {
    pub image: PathBuf,
    /// Statistics window side, px.
    #[arg(long, default_value_t = 21)]
    pub window: usize,
    #[arg(long)]
    pub out: PathBuf,
}

#[derive(Args, Debug)]
pub struct PairArgs {
    pub a: PathBuf,
    pub b: PathBuf,
}

#[derive(Args, Debug)]
pub struct NccArgs {
    pub template: PathBuf,
    pub image: PathBuf,
}

pub fn ortho(a: &OrthoArgs) -> Result<(), String> {
    let (rec, pano_path) = campaign_recording(&a.campaign, &a.recording)?;
    let pano = read_gray(&pano_path)?;
    let mut params = OrthoParams {
        gsd_m: a.gsd,
        rotation_deg: a.rotate_deg,
        ..OrthoParams::default()
    };
    params.vehicle.enabled = !a.no_mask;
    Params::validate(&params).map_err(|errs| {
        option_errors(&errs, &[("gsd_m", "gsd"), ("rotation_deg", "rotate-deg")])
    })?;
    let ortho = ortho_project_whole(&pano, &rec, &params);
    save_gray(&a.out, &ortho.image).map_err(|e| e.to_string())?;
    let g = &ortho.georef;
    println!(
        "{}: {}×{} px, {} m/px, up = {}°, centre (foot point) {:.3} {:.3} {:.3}",
        a.out.display(),
        g.width_px,
        g.height_px,
        g.gsd_m,
        g.rotation_deg,
        g.foot_world[0],
        g.foot_world[1],
        g.foot_world[2]
    );
    Ok(())
}

pub fn kaze(a: &KazeArgs) -> Result<(), String> {
    let img = read_gray(&a.image)?;
    if a.octaves == 0 || a.octaves > 8 || !(a.threshold.is_finite() && a.threshold > 0.0) {
        return Err("--octaves must be in 1..=8 and --threshold finite and > 0".into());
    }
    let p = KazeParams {
        threshold: a.threshold,
        octaves: a.octaves,
        upright: a.upright,
        extended: a.extended,
        ..KazeParams::default()
    };
    let f = detect_and_describe(&img, &p);
    let mut s = String::from("x,y,size,response");
    if a.descriptors {
        for i in 0..f.descriptor_len {
            let _ = write!(s, ",d{i}");
        }
    }
    s.push('\n');
    for (i, k) in f.keypoints.iter().enumerate() {
        let _ = write!(s, "{},{},{},{}", k.u_px, k.v_px, k.size_px, k.response);
        if a.descriptors {
            for v in f.descriptor(i) {
                let _ = write!(s, ",{v}");
            }
        }
        s.push('\n');
    }
    write_listing(&a.out, &s, f.len(), "keypoints")
}

pub fn forstner(a: &ForstnerArgs) -> Result<(), String> {
    let img = read_gray(&a.image)?;
    let p = ForstnerParams {
        max_corners: a.max,
        ..ForstnerParams::default()
    };
    let corners = forstner_corners(&img, &p);
    let mut s = String::from("x,y,weight,roundness\n");
    for c in &corners {
        let _ = writeln!(s, "{},{},{},{}", c.u_px, c.v_px, c.weight, c.roundness);
    }
    write_listing(&a.out, &s, corners.len(), "corners")
}

pub fn wallis(a: &WallisArgs) -> Result<(), String> {
    let img = read_gray(&a.image)?;
    let p = WallisParams {
        window_px: a.window,
        ..WallisParams::default()
    };
    let out = wallis_filter(&img, &p).map_err(|e| e.to_string())?;
    save_gray(&a.out, &out).map_err(|e| e.to_string())?;
    println!("-> {}", a.out.display());
    Ok(())
}

pub fn phasecorr(a: &PairArgs) -> Result<(), String> {
    let ia = read_gray(&a.a)?;
    let ib = read_gray(&a.b)?;
    let s =
        phase_correlate(&ia, &ib, &PhaseCorrelationParams::default()).map_err(|e| e.to_string())?;
    println!("{} {} {}", s.dx_px, s.dy_px, s.peak);
    Ok(())
}

pub fn ncc(a: &NccArgs) -> Result<(), String> {
    let t = read_gray(&a.template)?;
    let i = read_gray(&a.image)?;
    // A constant template has no normalised correlation anywhere (every score would be 0 at an arbitrary place).
    if t.data.windows(2).all(|p| p[0] == p[1]) {
        return Err(format!(
            "{}: the template is constant (every pixel {}), so its normalised cross-correlation is undefined; \
             crop a part with texture",
            a.template.display(),
            t.data.first().copied().unwrap_or(0.0)
        ));
    }
    let m = match_template(&i, &t).map_err(|e| e.to_string())?;
    println!("{} {} {}", m.u_px, m.v_px, m.score);
    Ok(())
}
