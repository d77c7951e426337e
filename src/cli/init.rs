//! `skytie init DIR`: write an empty campaign skeleton — campaign.toml and every table with a commented
//! header explaining each column, its unit and frame — for a user who builds a campaign by hand or by
//! script. The tables hold no rows, so `skytie check` on the skeleton reports exactly what is still missing.

use clap::Args;
use skytie_stages::fsutil::atomic_write;
use std::path::{Path, PathBuf};

/// Arguments of `skytie init`.
#[derive(Args, Debug)]
pub struct InitArgs {
    /// The campaign folder to create (must not exist or be empty).
    pub dir: PathBuf,
    /// Campaign name written into campaign.toml.
    #[arg(long, default_value = "my campaign")]
    pub name: String,
    /// Campaign CRS, horizontal + vertical (e.g. EPSG:28992+5709 for RD New + NAP).
    #[arg(long, default_value = "EPSG:28992+5709")]
    pub crs: String,
}

const CAMPAIGN_TOML: &str = r#"# A skytie campaign (docs/campaign-format.md).
# name: free text shown in reports.
# crs: the projected CRS of every coordinate in this folder, horizontal + vertical EPSG codes,
#      e.g. "EPSG:28992+5709" (RD New + NAP height) or "EPSG:25832+7837" (ETRS89 / UTM 32N + DHHN2016).
# frame (optional): "projected" (default: x, y are map coordinates of crs; aerial rays are intersected in its
#      tangent frame) or "cartesian" (the coordinates already are a Cartesian frame, used as they are).
"#;

const RECORDINGS: &str = "# One row per panorama (equirectangular, width = 2 x height, in mm/panoramas/).
# image_id       unique id (text)
# file           path relative to mm/panoramas/
# time           acquisition time, ISO 8601 with zone, e.g. 2019-06-14T10:31:07.250Z
# x, y, z        panorama projection centre in the campaign CRS, metres (easting, northing, height)
# heading        driving direction, degrees clockwise from grid north
# camera_height  height of the projection centre above the road surface below it, metres
# sigma_xy, sigma_z   optional a-priori standard deviation of the position, metres
# yaw, pitch, roll    optional rotation of the panorama frame, degrees (default 0 = levelled, centre column to grid north)
image_id,file,time,x,y,z,heading,camera_height,sigma_xy,sigma_z,yaw,pitch,roll
";

const CAMERAS: &str = "# One row per aerial frame image in this folder.
# image_id, file      unique id; file relative to this folder
# x, y, z             projection centre in the campaign CRS, metres
# omega, phi, kappa   attitude, degrees: R = Rx(omega) Ry(phi) Rz(kappa) maps camera to world (0,0,0 looks down, image top north)
# focal_px            principal distance, pixels
# cx, cy              principal point, pixels from the top-left image corner (centre of the first pixel = 0.5)
# width, height       image size, pixels
# k1, k2, k3, k4      optional radial distortion (r^2, r^4, r^6, r^8), normalised image y up, default 0
# p1, p2              optional tangential distortion, default 0
# b1, b2              optional affinity and skew, pixels: u = cx + (focal_px + b1) x_d + b2 y_d, default 0
# sigma_px            optional image measurement precision, pixels, default 0.5
image_id,file,x,y,z,omega,phi,kappa,focal_px,cx,cy,width,height,k1,k2,k3,k4,p1,p2,b1,b2,sigma_px
";

const CHECKPOINTS: &str = "# Surveyed check points (evaluation only, never used as control).
# point_id           unique id
# x, y, z            campaign CRS, metres
# sigma_xy, sigma_z  optional standard deviations, metres
point_id,x,y,z,sigma_xy,sigma_z
";

const OBSERVATIONS: &str = "# Where each check point was measured in a panorama.
# point_id   id from checkpoints.csv
# image_id   id from mm/recordings.csv
# u, v       pixel position, continuous: image corner (0, 0), first pixel centre (0.5, 0.5), v downwards
point_id,image_id,u,v
";

/// Run `skytie init`; returns the exit code.
pub fn main(a: &InitArgs) -> i32 {
    if let Err(e) = skytie_stages::crs::Crs::parse(&a.crs) {
        eprintln!("error: --crs: {e}");
        return 2;
    }
    if a.dir.exists()
        && std::fs::read_dir(&a.dir)
            .map(|mut d| d.next().is_some())
            .unwrap_or(true)
    {
        eprintln!(
            "error: {}: already exists and is not empty — choose a new folder",
            a.dir.display()
        );
        return 2;
    }
    match write_skeleton(&a.dir, &a.name, &a.crs) {
        Ok(()) => {
            println!("campaign skeleton written to {}; fill in the tables, put the images next to them and run `skytie check {}`", a.dir.display(), a.dir.display());
            0
        }
        Err(e) => {
            eprintln!("error: {}: {e}", a.dir.display());
            2
        }
    }
}

fn write_skeleton(dir: &Path, name: &str, crs: &str) -> std::io::Result<()> {
    for sub in ["mm/panoramas", "aerial/nadir", "aerial/oblique", "control"] {
        std::fs::create_dir_all(dir.join(sub))?;
    }
    let toml = format!(
        "{CAMPAIGN_TOML}name = {}\ncrs = {}\n",
        toml_string(name),
        toml_string(crs)
    );
    atomic_write(&dir.join("campaign.toml"), toml.as_bytes())?;
    atomic_write(&dir.join("mm/recordings.csv"), RECORDINGS.as_bytes())?;
    atomic_write(&dir.join("aerial/nadir/cameras.csv"), CAMERAS.as_bytes())?;
    atomic_write(&dir.join("aerial/oblique/cameras.csv"), CAMERAS.as_bytes())?;
    atomic_write(&dir.join("control/checkpoints.csv"), CHECKPOINTS.as_bytes())?;
    atomic_write(
        &dir.join("control/observations.csv"),
        OBSERVATIONS.as_bytes(),
    )
}

fn toml_string(s: &str) -> String {
    format!("\"{}\"", s.replace('\\', "\\\\").replace('"', "\\\""))
}
