//! Grid-based datum shifts: NTv2 grid files (`.gsb`, the format of national transformations such as
//! RDNAPTRANS's `rdtrans2018.gsb` for RD New, BeTA2007 for Germany or OSTN15's NTv2 version for Great
//! Britain), read by `proj4rs` (its NTv2 reader: header records, then per sub-grid latitude and longitude
//! shifts in arc-seconds, longitudes positive west) into its process-wide grid catalogue, where a proj4
//! definition's `+nadgrids=<key>` finds them. A grid shifts latitude/longitude from the datum of the CRS that
//! names it to ETRS89/WGS84 and is interpolated bilinearly; a point outside every sub-grid cannot be
//! transformed (an error naming the point, never a silent Helmert fallback).
//!
//! Each file is loaded once per process under its path (later changes to the file on disk are not seen by
//! a running process).

use std::path::{Path, PathBuf};
use std::sync::Mutex;

/// A datum grid that cannot be used.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum DatumGridError {
    #[error("datum grid {}: does not exist — give the path of the NTv2 (.gsb) file of the national transformation (e.g. rdtrans2018.gsb for RD New), relative to the file that names it", path.display())]
    Missing { path: PathBuf },
    #[error("datum grid {}: the path cannot be named in a CRS definition ({reason}) — move or rename the file", path.display())]
    BadPath { path: PathBuf, reason: String },
    #[error("datum grid {}: cannot be read as an NTv2 grid ({reason}) — give an NTv2 .gsb file (GS_TYPE SECONDS)", path.display())]
    Unreadable { path: PathBuf, reason: String },
}

/// Grids loaded so far (their keys), so that a grid is read once even when several threads ask for it.
static LOADED: Mutex<Vec<String>> = Mutex::new(Vec::new());

/// Load the NTv2 grid at `path` into `proj4rs`' catalogue (once) and return the key a proj4 definition names
/// it by (`+nadgrids=<key>`).
pub fn load(path: &Path) -> Result<String, DatumGridError> {
    if !path.is_file() {
        return Err(DatumGridError::Missing {
            path: path.to_path_buf(),
        });
    }
    let absolute = std::fs::canonicalize(path).map_err(|e| DatumGridError::Unreadable {
        path: path.to_path_buf(),
        reason: e.to_string(),
    })?;
    let key = absolute
        .to_str()
        .filter(|k| !k.contains(char::is_whitespace) && !k.contains(',') && !k.starts_with('@'))
        .ok_or_else(|| DatumGridError::BadPath {
            path: path.to_path_buf(),
            reason: "it contains white space, a comma or characters that are not UTF-8".into(),
        })?
        .to_string();
    let mut loaded = LOADED.lock().unwrap_or_else(|e| e.into_inner());
    if loaded.contains(&key) {
        return Ok(key);
    }
    proj4rs::nadgrids::catalog::with_catalog(|c| proj4rs::nadgrids::files::read_from_file(c, &key))
        .map_err(|e| DatumGridError::Unreadable {
            path: path.to_path_buf(),
            reason: e.to_string(),
        })?;
    loaded.push(key.clone());
    Ok(key)
}
