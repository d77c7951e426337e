//! The generator's orthophoto and DTM: an orthographic nadir render of each area's scene (every pixel the
//! first surface straight below it, in the aerial epoch, with the aerial look) at a chosen GSD around the
//! route, displaced by a known smooth planimetric warp, and the terrain heights on a 1 m grid — both written as
//! GeoTIFFs in the campaign CRS and declared in `campaign.toml` (`[orthophoto]`, `[dtm]`). The warp and its
//! parameters go to `truth/orthophoto.toml` (grading only).
//!
//! Warp: what the orthophoto shows at world (x, y) lies at (x, y) − d(x, y) with
//! d = e·(cos(2πx/λ + φx), sin(2πy/λ + φy)), λ = [`WARP_WAVELENGTH_M`], phases from the seed: the RMS of |d|
//! over an area is `e` (`error_m`, the RMS planimetric error), σ per axis e/√2, which `campaign.toml` states.

use super::postprocess::{apply_look, EpochLook};
use super::rng::{hash_str, Stream};
use super::scene::{Epoch, Scene};
use super::SynthError;
use crate::campaign::Recording;
use crate::imaging::georef::{geotiff_tags, GeoTransform};
use crate::imaging::tiff_write::{TiffCompression, TiledTiffSpec, TiledTiffWriter};
use crate::imaging::RgbImage;
use nalgebra::Vector3;
use rayon::prelude::*;
use serde::{Deserialize, Serialize};
use std::path::Path;

/// Wavelength of the planimetric warp, m.
pub const WARP_WAVELENGTH_M: f64 = 150.0;
/// The orthophoto and DTM cover the ground within this distance of a recording, m.
pub const COVER_M: f64 = 30.0;
/// DTM grid spacing, m.
pub const DTM_CELL_M: f64 = 1.0;
/// Stated height accuracy of the generated DTM (it is exact), m.
pub const DTM_SIGMA_M: f64 = 0.05;
/// The generator's CRS code (campaign.toml `EPSG:28992`).
const EPSG: u16 = 28992;
/// Rows rendered and post-processed at a time (one tile row of the TIFF).
const BAND_ROWS: usize = 256;
/// Sub-samples per pixel axis.
const SPP_AXIS: usize = 2;

/// What orthophoto to generate.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct OrthophotoOptions {
    /// Ground sampling distance, m.
    pub gsd_m: f64,
    /// RMS planimetric displacement of the orthophoto (2-D), m.
    pub error_m: f64,
    /// Leave the nadir frames out of the campaign (the orthophoto is its only nadir source).
    #[serde(default)]
    pub without_nadir: bool,
}

impl OrthophotoOptions {
    /// `Err` naming the option when a value is out of range.
    pub fn check(&self) -> Result<(), SynthError> {
        let bad = |option: &str, message: String| SynthError::InvalidOption {
            option: option.into(),
            message,
        };
        if !(self.gsd_m.is_finite() && (0.01..=1.0).contains(&self.gsd_m)) {
            return Err(bad(
                "orthophoto_gsd_m",
                format!("{} m; give a GSD in [0.01, 1] m", self.gsd_m),
            ));
        }
        if !(self.error_m.is_finite() && (0.0..=5.0).contains(&self.error_m)) {
            return Err(bad(
                "orthophoto_error_m",
                format!("{} m; give an RMS error in [0, 5] m", self.error_m),
            ));
        }
        Ok(())
    }

    /// The per-axis σ written into `campaign.toml` (at least 5 mm: no orthophoto is exact).
    pub fn stated_sigma_m(&self) -> f64 {
        (self.error_m / std::f64::consts::SQRT_2).max(0.005)
    }

    /// The warp's phases (φx, φy) for `seed` and `area`.
    fn phases(seed: u64, area: usize) -> [f64; 2] {
        let mut s = Stream::new(&[seed, hash_str("orthophoto warp"), area as u64]);
        let tau = std::f64::consts::TAU;
        [tau * s.uniform(), tau * s.uniform()]
    }

    /// d(x, y) of the module documentation for `seed` and `area`, m.
    pub fn displacement_m(&self, seed: u64, area: usize, x_m: f64, y_m: f64) -> [f64; 2] {
        let [px, py] = Self::phases(seed, area);
        let k = std::f64::consts::TAU / WARP_WAVELENGTH_M;
        [
            self.error_m * (k * x_m + px).cos(),
            self.error_m * (k * y_m + py).sin(),
        ]
    }
}

/// The files written for one area (relative to the campaign folder).
pub struct AreaFiles {
    pub orthophoto: String,
    pub dtm: String,
}

/// The north-up grid with pixel `pixel_m` covering `truth` grown by [`COVER_M`], and its size.
fn grid(truth: &[Recording], pixel_m: f64) -> (GeoTransform, usize, usize) {
    let (mut x0, mut y0) = (f64::INFINITY, f64::INFINITY);
    let (mut x1, mut y1) = (f64::NEG_INFINITY, f64::NEG_INFINITY);
    for r in truth {
        (x0, y0, x1, y1) = (x0.min(r.x), y0.min(r.y), x1.max(r.x), y1.max(r.y));
    }
    let snap = |v: f64| (v / pixel_m).floor() * pixel_m;
    let (ox, oy) = (snap(x0 - COVER_M), snap(y1 + COVER_M) + pixel_m);
    let w = ((x1 + COVER_M - ox) / pixel_m).ceil() as usize;
    let h = ((oy - (y0 - COVER_M)) / pixel_m).ceil() as usize;
    let t = GeoTransform {
        origin_x_m: ox,
        origin_y_m: oy,
        pixel_m,
    };
    (t, w.max(1), h.max(1))
}

/// Cells of [`COVER_M`]/4 within [`COVER_M`] of a recording, for skipping the ground far from the route.
struct Cover {
    cell_m: f64,
    t: GeoTransform,
    w: usize,
    h: usize,
    on: Vec<bool>,
}

impl Cover {
    fn new(truth: &[Recording], t: &GeoTransform, w_m: f64, h_m: f64) -> Self {
        let cell_m = COVER_M / 4.0;
        let (w, h) = (
            (w_m / cell_m).ceil() as usize + 1,
            (h_m / cell_m).ceil() as usize + 1,
        );
        let mut on = vec![false; w * h];
        let reach = (COVER_M / cell_m).ceil() as isize + 1;
        for r in truth {
            let (c, q) = (
                ((r.x - t.origin_x_m) / cell_m) as isize,
                ((t.origin_y_m - r.y) / cell_m) as isize,
            );
            for dq in -reach..=reach {
                for dc in -reach..=reach {
                    let (cc, qq) = (c + dc, q + dq);
                    if cc >= 0 && qq >= 0 && (cc as usize) < w && (qq as usize) < h {
                        on[qq as usize * w + cc as usize] = true;
                    }
                }
            }
        }
        Self {
            cell_m,
            t: *t,
            w,
            h,
            on,
        }
    }

    fn contains(&self, x_m: f64, y_m: f64) -> bool {
        let c = ((x_m - self.t.origin_x_m) / self.cell_m).floor();
        let q = ((self.t.origin_y_m - y_m) / self.cell_m).floor();
        c >= 0.0
            && q >= 0.0
            && (c as usize) < self.w
            && (q as usize) < self.h
            && self.on[q as usize * self.w + c as usize]
    }
}

/// Linear RGB of orthophoto pixel (col, row): the mean of the sub-samples' first surfaces straight below the
/// warped ground point.
fn ortho_pixel(
    scene: &Scene,
    o: &OrthophotoOptions,
    (seed, area): (u64, usize),
    t: &GeoTransform,
    (col, row): (usize, usize),
) -> [f32; 3] {
    let down = Vector3::new(0.0, 0.0, -1.0);
    let mut acc = [0.0f32; 3];
    for j in 0..SPP_AXIS {
        for i in 0..SPP_AXIS {
            let u = col as f64 + (i as f64 + 0.5) / SPP_AXIS as f64;
            let v = row as f64 + (j as f64 + 0.5) / SPP_AXIS as f64;
            let [x, y] = t.pixel_to_world(u, v);
            let [dx, dy] = o.displacement_m(seed, area, x, y);
            let (sx, sy) = (x - dx, y - dy);
            let top = scene.ground_height_m(sx, sy) + 300.0;
            let c = scene.radiance(&Vector3::new(sx, sy, top), &down, Epoch::Aerial);
            for k in 0..3 {
                acc[k] += c[k];
            }
        }
    }
    let n = (SPP_AXIS * SPP_AXIS) as f32;
    acc.map(|a| a / n)
}

/// Render and write the orthophoto of one area to `path` (tiled, Deflate, 8-bit RGB GeoTIFF).
fn write_orthophoto(
    scene: &Scene,
    truth: &[Recording],
    o: &OrthophotoOptions,
    (seed, area): (u64, usize),
    path: &Path,
) -> Result<(), SynthError> {
    let io = |e: std::io::Error| SynthError::io(path, e);
    let (t, w, h) = grid(truth, o.gsd_m);
    let cover = Cover::new(truth, &t, w as f64 * o.gsd_m, h as f64 * o.gsd_m);
    let spec = TiledTiffSpec {
        width: w,
        height: h,
        channels: 3,
        bytes_per_sample: 1,
        tile_side: BAND_ROWS,
        compression: TiffCompression::Deflate,
        big: (w * h * 3) as u64 > (3u64 << 30),
    };
    let mut writer = TiledTiffWriter::create(path, spec).map_err(io)?;
    writer.set_geotiff(&geotiff_tags(&t, EPSG));
    for (band, r0) in (0..h).step_by(BAND_ROWS).enumerate() {
        let rows = BAND_ROWS.min(h - r0);
        let lines: Vec<Vec<f32>> = (r0..r0 + rows)
            .into_par_iter()
            .map(|row| {
                let mut line = vec![0.0f32; w * 3];
                for col in 0..w {
                    let [x, y] = t.pixel_to_world(col as f64 + 0.5, row as f64 + 0.5);
                    if cover.contains(x, y) {
                        let c = ortho_pixel(scene, o, (seed, area), &t, (col, row));
                        line[col * 3..col * 3 + 3].copy_from_slice(&c);
                    }
                }
                line
            })
            .collect();
        let linear = RgbImage {
            width: w,
            height: rows,
            data: lines.concat(),
        };
        let key = hash_str(&format!("orthophoto {area} band {band}"));
        let img = apply_look(&linear, &EpochLook::aerial(), seed, key);
        for line in img.data.chunks_exact(w * 3) {
            let row: Vec<u8> = line
                .iter()
                .map(|v| (v.clamp(0.0, 1.0) * 255.0 + 0.5) as u8)
                .collect();
            writer.push_row_u8(&row).map_err(io)?;
        }
    }
    writer.finish().map_err(io)
}

/// Write the DTM of one area (terrain heights at the cell centres, Float32 GeoTIFF) to `path`.
fn write_dtm(scene: &Scene, truth: &[Recording], path: &Path) -> Result<(), SynthError> {
    use tiff::encoder::{colortype, TiffEncoder};
    use tiff::tags::Tag;
    let (t, w, h) = grid(truth, DTM_CELL_M);
    let mut heights = Vec::with_capacity(w * h);
    for row in 0..h {
        for col in 0..w {
            let [x, y] = t.pixel_to_world(col as f64 + 0.5, row as f64 + 0.5);
            heights.push(scene.ground_height_m(x, y) as f32);
        }
    }
    let tags = geotiff_tags(&t, EPSG);
    let encode = || -> tiff::TiffResult<Vec<u8>> {
        let mut buf = std::io::Cursor::new(Vec::new());
        let mut enc = TiffEncoder::new(&mut buf)?;
        let mut img = enc.new_image::<colortype::Gray32Float>(w as u32, h as u32)?;
        let e = img.encoder();
        e.write_tag(
            Tag::ModelPixelScaleTag,
            &tags.model_pixel_scale.clone().unwrap_or_default()[..],
        )?;
        e.write_tag(
            Tag::ModelTiepointTag,
            &tags.model_tiepoints.clone().unwrap_or_default()[..],
        )?;
        e.write_tag(
            Tag::GeoKeyDirectoryTag,
            &tags.geo_key_directory.clone().unwrap_or_default()[..],
        )?;
        img.write_data(&heights)?;
        Ok(buf.into_inner())
    };
    let bytes = encode().map_err(|e| SynthError::io(path, std::io::Error::other(e.to_string())))?;
    crate::fsutil::atomic_write(path, &bytes).map_err(|e| SynthError::io(path, e))
}

/// Write the orthophoto and DTM of area `area` under `root/orthophoto/`; returns their relative names.
pub fn write_area(
    scene: &Scene,
    truth: &[Recording],
    o: &OrthophotoOptions,
    seed: u64,
    area: usize,
    root: &Path,
) -> Result<AreaFiles, SynthError> {
    let files = AreaFiles {
        orthophoto: format!("orthophoto/ortho_{area}.tif"),
        dtm: format!("orthophoto/dtm_{area}.tif"),
    };
    write_orthophoto(scene, truth, o, (seed, area), &root.join(&files.orthophoto))?;
    write_dtm(scene, truth, &root.join(&files.dtm))?;
    Ok(files)
}

/// The `[orthophoto]` and `[dtm]` tables of `campaign.toml` for `files`.
pub fn campaign_tables(o: &OrthophotoOptions, files: &[AreaFiles]) -> String {
    let list = |f: &dyn Fn(&AreaFiles) -> &str| {
        files
            .iter()
            .map(|a| format!("\"{}\"", f(a)))
            .collect::<Vec<_>>()
            .join(", ")
    };
    format!(
        "\n[orthophoto]\nfiles = [{}]\nsigma_m = {}\n\n[dtm]\nfiles = [{}]\nsigma_m = {}\n",
        list(&|a| &a.orthophoto),
        o.stated_sigma_m(),
        list(&|a| &a.dtm),
        DTM_SIGMA_M
    )
}

/// `truth/orthophoto.toml`: the warp of each area, for grading.
pub fn truth_toml(o: &OrthophotoOptions, seed: u64, areas: usize) -> String {
    let mut s = format!(
        "# What the orthophoto shows at (x, y) lies at (x, y) - d, d = (error_m cos(2 pi x / wavelength_m + phase_x),\n\
         # error_m sin(2 pi y / wavelength_m + phase_y)).\ngsd_m = {}\nerror_m = {}\nwavelength_m = {}\n",
        o.gsd_m, o.error_m, WARP_WAVELENGTH_M
    );
    for area in 0..areas {
        let [px, py] = OrthophotoOptions::phases(seed, area);
        s.push_str(&format!("\n[[area]]\nphase_x = {px}\nphase_y = {py}\n"));
    }
    s
}

/// Append to `campaign.toml` at `to` every table of the `campaign.toml` at `from` (the orthophoto tables of a
/// rendered campaign carried into the campaign its profile makes).
pub fn carry_tables(from: &Path, to: &Path) -> Result<(), SynthError> {
    let read = |p: &Path| std::fs::read_to_string(p).map_err(|e| SynthError::io(p, e));
    let source: toml::Table = toml::from_str(&read(from)?)
        .map_err(|e| SynthError::io(from, std::io::Error::other(e.to_string())))?;
    let tables: toml::Table = source.into_iter().filter(|(_, v)| v.is_table()).collect();
    if tables.is_empty() {
        return Ok(());
    }
    let extra = toml::to_string(&tables)
        .map_err(|e| SynthError::io(from, std::io::Error::other(e.to_string())))?;
    let text = format!("{}\n{extra}", read(to)?);
    crate::fsutil::atomic_write(to, text.as_bytes()).map_err(|e| SynthError::io(to, e))
}
