//! `skytie tool …`: the pipeline's building blocks on plain files, for debugging, figures and side-by-side
//! comparisons with other software. Pixel conventions as in campaign-format.md (continuous coordinates, centre of
//! the first pixel at (0.5, 0.5)); tables are CSV with a header row; single results are printed on one line.
//! One file per pipeline: `nadir.rs` (thesis ch. 3), the oblique tools in their own files (ch. 4).

mod nadir;

use clap::Subcommand;
use nadir::*;
use skytie_stages::fsutil::atomic_write;
use std::path::Path;

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
