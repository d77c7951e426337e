//! `skytie tool` building blocks of the oblique pipeline (thesis ch. 4): agast, daisy, mi-register, perspective.
//! Each tool calls the same stages-crate function the pipeline uses (`features::agast`, `features::daisy`,
//! `oblique::patch_registration::search::mi_search`, `geometry::perspective`).

use super::{campaign_recording, option_errors, read_gray, write_listing, write_text};
use clap::{Args, ValueEnum};
use skytie_stages::estimators::one_plus_one::OnePlusOneParams;
use skytie_stages::features::agast::{detect_agast, AgastParams};
use skytie_stages::features::daisy::{DaisyExtractor, DaisyNormalization, DaisyParams};
use skytie_stages::geometry::perspective::PerspectiveView;
use skytie_stages::geometry::PanoramaCamera;
use skytie_stages::imaging::io::{load_rgb, save_rgb};
use skytie_stages::matching::mattes_mi::MiError;
use skytie_stages::oblique::patch_registration::search::mi_search;
use skytie_stages::params::Params;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

#[derive(Args, Debug)]
pub struct AgastArgs {
    pub image: PathBuf,
    /// Segment-test threshold in 0..255 grey levels (OpenCV's scale, default 10).
    #[arg(long, default_value_t = 10.0)]
    pub threshold: f32,
    /// Keep at most this many corners (strongest first).
    #[arg(long)]
    pub max: Option<usize>,
    /// Keep every corner (no 3×3 non-maximum suppression).
    #[arg(long)]
    pub no_nms: bool,
    #[arg(long)]
    pub out: PathBuf,
}

/// DAISY normalisation on the command line.
#[derive(Clone, Copy, Debug, ValueEnum)]
pub enum NormArg {
    /// Each histogram to unit L2 (Tola; the pipeline's default).
    Partial,
    /// None (OpenCV's effective default).
    None,
    /// The whole descriptor to unit L2.
    Full,
    /// Unit L2, clip at 0.154, renormalise.
    Sift,
}

impl From<NormArg> for DaisyNormalization {
    fn from(n: NormArg) -> Self {
        match n {
            NormArg::Partial => DaisyNormalization::Partial,
            NormArg::None => DaisyNormalization::None,
            NormArg::Full => DaisyNormalization::Full,
            NormArg::Sift => DaisyNormalization::Sift,
        }
    }
}

#[derive(Args, Debug)]
pub struct DaisyArgs {
    pub image: PathBuf,
    /// CSV with a header row and columns x, y (continuous pixels), e.g. the output of `skytie tool agast`.
    #[arg(long)]
    pub points: PathBuf,
    /// Radius of the outermost ring, px.
    #[arg(long, default_value_t = 15.0)]
    pub radius_px: f64,
    #[arg(long, value_enum, default_value_t = NormArg::Partial)]
    pub normalization: NormArg,
    #[arg(long)]
    pub out: PathBuf,
}

#[derive(Args, Debug)]
pub struct MiRegisterArgs {
    pub fixed: PathBuf,
    pub moving: PathBuf,
    /// Histogram bins.
    #[arg(long, default_value_t = 50)]
    pub bins: usize,
    /// Fixed-image samples (distinct pixels drawn with --seed); default: every pixel.
    #[arg(long)]
    pub samples: Option<usize>,
    /// Seed of the sampling and of the ES.
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
    /// Translations farther than this from (0, 0), per axis, are not considered, px.
    #[arg(long, default_value_t = 10.0)]
    pub max_shift_px: f64,
    /// Start the ES at the best of an exhaustive MI scan over ±max-shift-px at this integer step (px); without
    /// it the ES starts at (0, 0).
    #[arg(long)]
    pub scan_step_px: Option<usize>,
    /// ES iteration limit.
    #[arg(long, default_value_t = 200)]
    pub iterations: usize,
    /// ES initial search radius, px (ITK 1.01).
    #[arg(long, default_value_t = 1.01)]
    pub initial_radius_px: f64,
    /// ES stops when its search matrix' norm falls to this, px (ITK 1.5e-4).
    #[arg(long, default_value_t = 1.5e-4)]
    pub epsilon_px: f64,
}

#[derive(Args, Debug)]
pub struct PerspectiveArgs {
    #[arg(long)]
    pub campaign: PathBuf,
    #[arg(long)]
    pub recording: String,
    /// Azimuth of the optical axis, degrees clockwise from grid north (from the driving direction with
    /// --from-heading).
    #[arg(long, allow_hyphen_values = true)]
    pub yaw_deg: f64,
    /// Measure --yaw-deg from the recording's heading (the sparse cloud's views: 300/270/240 left, 60/90/120
    /// right).
    #[arg(long)]
    pub from_heading: bool,
    /// Elevation of the optical axis above the horizon, degrees.
    #[arg(long, default_value_t = 30.0, allow_hyphen_values = true)]
    pub pitch_deg: f64,
    /// Vertical (= horizontal) field of view, degrees.
    #[arg(long, default_value_t = 90.0)]
    pub fov_deg: f64,
    /// Width = height of the view, px.
    #[arg(long, default_value_t = 512)]
    pub width: u32,
    #[arg(long)]
    pub out: PathBuf,
}

pub fn agast(a: &AgastArgs) -> Result<(), String> {
    let p = AgastParams {
        threshold: a.threshold,
        nonmax_suppression: !a.no_nms,
        max_corners: a.max,
    };
    p.validate()
        .map_err(|errs| option_errors(&errs, &[("max_corners", "max")]))?;
    let img = read_gray(&a.image)?;
    let corners = detect_agast(&img, &p);
    let mut s = String::from("x,y,score\n");
    for c in &corners {
        let _ = writeln!(s, "{},{},{}", c.x_px, c.y_px, c.score);
    }
    write_listing(&a.out, &s, corners.len(), "corners")
}

pub fn daisy(a: &DaisyArgs) -> Result<(), String> {
    let p = DaisyParams {
        radius_px: a.radius_px,
        normalization: a.normalization.into(),
        ..DaisyParams::default()
    };
    p.validate().map_err(|errs| option_errors(&errs, &[]))?;
    let points = read_points(&a.points)?;
    let img = read_gray(&a.image)?;
    let ex = DaisyExtractor::new(&img, &p);
    let len = ex.descriptor_len();
    let mut s = String::from("x,y,inside");
    for i in 0..len {
        let _ = write!(s, ",d{i}");
    }
    s.push('\n');
    let mut d = vec![0f32; len];
    let mut outside = 0usize;
    for &(x, y) in &points {
        if ex.describe(x, y, &mut d) {
            let _ = write!(s, "{x},{y},1");
            for v in &d {
                let _ = write!(s, ",{v}");
            }
        } else {
            outside += 1;
            let _ = write!(s, "{x},{y},0{}", ",".repeat(len));
        }
        s.push('\n');
    }
    write_text(&a.out, &s)?;
    println!(
        "{} points ({} too close to the border: inside = 0, empty descriptor), {len} values each -> {}",
        points.len(),
        outside,
        a.out.display()
    );
    Ok(())
}

/// The (x, y) columns of a points CSV with a header row. Every error names the file and, for a bad value, its
/// line (the header is line 1) and what to do.
fn read_points(path: &Path) -> Result<Vec<(f64, f64)>, String> {
    let file = path.display();
    let mut rdr = csv::ReaderBuilder::new()
        .trim(csv::Trim::All)
        .from_path(path)
        .map_err(|e| {
            format!("{file}: cannot open ({e}); check that the file exists and is readable")
        })?;
    let headers = rdr
        .headers()
        .map_err(|e| format!("{file}: cannot read the header row ({e})"))?
        .clone();
    let column = |name: &str| {
        headers.iter().position(|h| h == name).ok_or_else(|| {
            format!(
                "{file}: no column '{name}' in the header row ({}); the points file needs x and y columns, \
                 e.g. the output of `skytie tool agast`",
                headers.iter().collect::<Vec<_>>().join(",")
            )
        })
    };
    let (cx, cy) = (column("x")?, column("y")?);
    let mut points = Vec::new();
    for record in rdr.records() {
        let record = record.map_err(|e| {
            let line = e.position().map_or(0, |p| p.line());
            format!("{file}: line {line}: {e}; every row needs as many fields as the header")
        })?;
        let line = record.position().map_or(0, |p| p.line());
        let value = |c: usize, name: &str| -> Result<f64, String> {
            let text = record.get(c).unwrap_or("");
            text.parse::<f64>()
                .ok()
                .filter(|v| v.is_finite())
                .ok_or_else(|| {
                    format!(
                        "{file}: line {line}: {name} = '{text}' is not a finite number; fix or delete the row"
                    )
                })
        };
        points.push((value(cx, "x")?, value(cy, "y")?));
    }
    Ok(points)
}

pub fn mi_register(a: &MiRegisterArgs) -> Result<(), String> {
    let es = OnePlusOneParams {
        max_iterations: a.iterations,
        epsilon: a.epsilon_px,
        initial_radius: a.initial_radius_px,
        seed: a.seed,
        ..OnePlusOneParams::default()
    };
    es.validate().map_err(|errs| {
        option_errors(
            &errs,
            &[
                ("max_iterations", "iterations"),
                ("epsilon", "epsilon-px"),
                ("initial_radius", "initial-radius-px"),
            ],
        )
    })?;
    if !(a.max_shift_px.is_finite() && a.max_shift_px > 0.0) {
        return Err(format!(
            "--max-shift-px: must be finite and > 0, got {}",
            a.max_shift_px
        ));
    }
    if a.samples == Some(0) {
        return Err("--samples: must be ≥ 1 (omit it to use every pixel)".into());
    }
    let fixed = read_gray(&a.fixed)?;
    let moving = read_gray(&a.moving)?;
    let r = mi_search(
        &fixed,
        &moving,
        a.bins,
        a.samples,
        [0.0, 0.0],
        a.max_shift_px,
        a.scan_step_px,
        &es,
    )
    .map_err(|e| match e {
        MiError::NoValidPixels { which } | MiError::ConstantImage { which, .. } => {
            let path = if which == "fixed" { &a.fixed } else { &a.moving };
            format!("{}: {e}; MI needs an image with contrast", path.display())
        }
        MiError::TooFewBins { .. } => format!("--bins: {e}"),
        _ => format!(
            "{} and {}: {e}; check that the images overlap, or raise --max-shift-px / use --scan-step-px",
            a.fixed.display(),
            a.moving.display()
        ),
    })?;
    println!(
        "{} {} {} {}",
        r.translation_px[0], r.translation_px[1], r.mi, r.iterations
    );
    Ok(())
}

pub fn perspective(a: &PerspectiveArgs) -> Result<(), String> {
    let mut errs = Vec::new();
    if !(1..=16384).contains(&a.width) {
        errs.push(format!(
            "--width: must be in [1, 16384] px, got {}",
            a.width
        ));
    }
    if !(a.fov_deg.is_finite() && a.fov_deg >= 1.0 && a.fov_deg <= 179.0) {
        errs.push(format!(
            "--fov-deg: must be in [1, 179] degrees, got {}",
            a.fov_deg
        ));
    }
    if !(a.pitch_deg.is_finite() && (-90.0..=90.0).contains(&a.pitch_deg)) {
        errs.push(format!(
            "--pitch-deg: must be in [-90, 90] degrees, got {}",
            a.pitch_deg
        ));
    }
    if !a.yaw_deg.is_finite() {
        errs.push(format!(
            "--yaw-deg: must be a finite angle, got {}",
            a.yaw_deg
        ));
    }
    if !errs.is_empty() {
        return Err(errs.join("; "));
    }
    let (rec, pano_path) = campaign_recording(&a.campaign, &a.recording)?;
    let pano = load_rgb(&pano_path).map_err(|e| e.to_string())?;
    let cam = PanoramaCamera::from_recording(&rec, pano.width as u32, pano.height as u32);
    let yaw_deg = if a.from_heading {
        rec.heading_deg + a.yaw_deg
    } else {
        a.yaw_deg
    };
    let view = PerspectiveView::of_panorama(&cam, a.width, a.fov_deg, yaw_deg, a.pitch_deg);
    let img = view.render_rgb(&pano, &cam);
    save_rgb(&a.out, &img, 95).map_err(|e| e.to_string())?;
    println!(
        "{}: {}×{} px, f = {:.3} px, yaw {:.3}°, pitch {:.3}°, centre {:.3} {:.3} {:.3}",
        a.out.display(),
        a.width,
        a.width,
        view.focal_px,
        yaw_deg.rem_euclid(360.0),
        a.pitch_deg,
        rec.x,
        rec.y,
        rec.z
    );
    Ok(())
}
