//! `skytie tool …`: the pipeline's building blocks on plain files, for debugging, figures and side-by-side
//! comparisons with other software. Pixel conventions as in campaign-format.md (continuous coordinates, centre of
//! the first pixel at (0.5, 0.5)); tables are CSV with a header row; single results are printed on one line.
//! One file per pipeline: `nadir.rs` (thesis ch. 3), the oblique tools in their own files (ch. 4).

mod nadir;
mod oblique;

use clap::Subcommand;
use nadir::*;
use oblique::*;
use skytie_stages::campaign::{read_campaign, Recording};
use skytie_stages::imaging::io::load_gray;
use skytie_stages::imaging::GrayImage;
use skytie_stages::params::Violation;
use skytie_util::fsutil::atomic_write;
use std::path::{Path, PathBuf};

/// The tools.
#[derive(Subcommand, Debug)]
pub enum ToolCommand {
    /// Ortho-project one recording's panorama onto the ground plane (thesis 3.4.3).
    Ortho(OrthoArgs),
    /// KAZE keypoints (x, y, size, response[, descriptor…]) as CSV.
    Kaze(KazeArgs),
    /// Förstner corners (x, y, weight, roundness) as CSV.
    Forstner(ForstnerArgs),
    /// Wallis filter an image.
    Wallis(WallisArgs),
    /// Phase correlation of two equally sized images: prints "dx dy peak" (shift of B relative to A, px).
    Phasecorr(PairArgs),
    /// NCC template matching (TM_CCOEFF_NORMED): prints "x y score" of the template centre in IMAGE.
    Ncc(NccArgs),
    /// AGAST (OAST 9-16) corners (x, y, score) as CSV (thesis 4.4.1).
    Agast(AgastArgs),
    /// DAISY descriptors at the points of a CSV (x, y columns): x, y, inside, d0… as CSV (thesis 4.4.1).
    Daisy(DaisyArgs),
    /// Mattes MI translation registration of MOVING to FIXED by the (1+1)-ES: prints "dx dy mi iterations"
    /// (MOVING's content is FIXED's moved by (dx, dy) px; thesis 4.4.6).
    MiRegister(MiRegisterArgs),
    /// Perspective view of one recording's panorama (thesis 4.4.1, eq. 4/1–4/4).
    Perspective(PerspectiveArgs),
}

/// Run a tool; returns the exit code (0 ok, 1 the computation failed, 2 bad input).
pub fn main(cmd: &ToolCommand) -> i32 {
    let result = match cmd {
        ToolCommand::Ortho(a) => ortho(a),
        ToolCommand::Kaze(a) => kaze(a),
        ToolCommand::Forstner(a) => forstner(a),
        ToolCommand::Wallis(a) => wallis(a),
        ToolCommand::Phasecorr(a) => phasecorr(a),
        ToolCommand::Ncc(a) => ncc(a),
        ToolCommand::Agast(a) => agast(a),
        ToolCommand::Daisy(a) => daisy(a),
        ToolCommand::MiRegister(a) => mi_register(a),
        ToolCommand::Perspective(a) => perspective(a),
    };
    match result {
        Ok(()) => 0,
        Err(e) => {
            eprintln!("error: {e}");
            2
        }
    }
}

/// Write a text output atomically (never a half-written file).
pub(crate) fn write_text(path: &Path, text: &str) -> Result<(), String> {
    atomic_write(path, text.as_bytes())
        .map_err(|e| format!("{}: cannot write: {e}", path.display()))
}

/// Write a CSV listing atomically and say on stdout how many `what` (e.g. "corners") it holds.
pub(crate) fn write_listing(
    path: &Path,
    csv: &str,
    count: usize,
    what: &str,
) -> Result<(), String> {
    write_text(path, csv)?;
    println!("{count} {what} -> {}", path.display());
    Ok(())
}

/// An input image as grey values, or the decoder's message.
pub(crate) fn read_gray(path: &Path) -> Result<GrayImage, String> {
    load_gray(path).map_err(|e| e.to_string())
}

/// The recording `id` of the campaign folder `campaign` and the path of its panorama file; a missing or rejected
/// recording is an error naming `mm/recordings.csv` (or the problem that rejected the row).
pub(crate) fn campaign_recording(
    campaign: &Path,
    id: &str,
) -> Result<(Recording, PathBuf), String> {
    let (c, problems) = read_campaign(campaign).map_err(|e| e.to_string())?;
    let rec = c
        .recordings
        .into_iter()
        .find(|r| r.image_id == id)
        .ok_or_else(
            || match problems.iter().find(|p| p.to_string().contains(id)) {
                Some(p) => format!("recording '{id}' was rejected: {p}"),
                None => format!(
                "no recording '{id}' in {}/mm/recordings.csv; the ids are in its image_id column",
                campaign.display()
            ),
            },
        )?;
    let pano = campaign.join("mm/panoramas").join(&rec.file);
    Ok((rec, pano))
}

/// `(field, message)` range errors of a parameter struct as one line naming the command-line options: a field
/// listed in `options` as `(field, option)` is reported as `--option`, any other as `--field` with `-` for `_`.
pub(crate) fn option_errors(errs: &[Violation], options: &[(&str, &str)]) -> String {
    errs.iter()
        .map(|v| {
            let opt = options
                .iter()
                .find(|(field, _)| *field == v.field)
                .map_or_else(|| v.field.replace('_', "-"), |(_, o)| (*o).to_string());
            format!("--{opt}: {}", v.message)
        })
        .collect::<Vec<_>>()
        .join("; ")
}
