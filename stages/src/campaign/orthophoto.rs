//! The optional orthophoto and DTM of a campaign (`campaign.toml` tables `[orthophoto]` and `[dtm]`, see
//! docs/campaign-format.md): GeoTIFF tiles with their headers (size, north-up geotransform, CRS) and stated
//! accuracies, validated like every other input — each problem names the file or key and what to do.

use super::problem::{Problem, ProblemKind};
use crate::imaging::georef::{campaign_epsg, read_header, RasterHeader};
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};

const TOML: &str = "campaign.toml";
/// Height σ of a DTM whose table states none, m.
pub const DEFAULT_DTM_SIGMA_M: f64 = 0.25;

/// One GeoTIFF tile and its header.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct RasterFile {
    /// As written in `campaign.toml` (relative to the campaign folder, or absolute).
    pub file: String,
    pub header: RasterHeader,
}

impl RasterFile {
    /// The file's path for a campaign in `root`.
    pub fn path(&self, root: &Path) -> PathBuf {
        root.join(&self.file)
    }
}

/// `[orthophoto]`: the tiles and the stated planimetric accuracy.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct OrthophotoSource {
    pub tiles: Vec<RasterFile>,
    /// Stated planimetric accuracy, σ per axis, m.
    pub sigma_m: f64,
}

impl OrthophotoSource {
    /// The tile holding world (x, y) at least `margin_m` inside, else the first that holds it at all.
    pub fn tile_at(&self, x_m: f64, y_m: f64, margin_m: f64) -> Option<usize> {
        let find = |m: f64| {
            self.tiles
                .iter()
                .position(|t| t.header.contains(x_m, y_m, m))
        };
        find(margin_m).or_else(|| find(0.0))
    }
}

/// `[dtm]`: the tiles (heights in the campaign's vertical datum) and their stated accuracy.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct DtmSource {
    pub tiles: Vec<RasterFile>,
    /// Stated height accuracy, σ, m.
    pub sigma_m: f64,
}

/// Line (1-based) of the table header `[name]` in `text`, for messages.
fn table_line(text: &str, name: &str) -> Option<usize> {
    let header = format!("[{name}]");
    text.lines().position(|l| l.trim() == header).map(|i| i + 1)
}

/// A key of `campaign.toml` (`field`, in the table on line `row` when known) and the hint its problems give.
struct TomlKey {
    row: Option<usize>,
    field: String,
    hint: String,
}

impl TomlKey {
    /// An error in the key's value.
    fn error(&self, message: impl Into<String>) -> Problem {
        Problem::error(
            TOML,
            self.row,
            Some(&self.field),
            message,
            self.hint.as_str(),
        )
    }

    /// The key's value `value` is not of the `expected` type.
    fn wrong_type(&self, value: &toml::Value, expected: &str) -> Problem {
        self.error(format!("is of type {}, not {expected}", value.type_str()))
    }

    /// The key is absent.
    fn missing(&self) -> Problem {
        self.error("required key is missing")
            .with_kind(ProblemKind::Missing)
    }
}

/// The table `name` of `campaign.toml`, on line `row` when known.
struct TomlTable<'a> {
    table: &'a toml::Table,
    name: &'a str,
    row: Option<usize>,
}

impl TomlTable<'_> {
    /// The table's key `key`, whose problems give `hint`.
    fn key(&self, key: &str, hint: String) -> TomlKey {
        TomlKey {
            row: self.row,
            field: format!("{}.{key}", self.name),
            hint,
        }
    }
}

/// The `file`/`files` of `table` as strings; problems for anything else.
fn files(table: &TomlTable, problems: &mut Vec<Problem>) -> Vec<String> {
    let name = table.name;
    let key = table.key(
        "files",
        format!("write files = [\"{name}/tile.tif\", …] (paths relative to the campaign folder)"),
    );
    let table = table.table;
    let value = table.get("files").or_else(|| table.get("file"));
    let list: Vec<&toml::Value> = match value {
        Some(toml::Value::Array(a)) => a.iter().collect(),
        Some(v @ toml::Value::String(_)) => vec![v],
        Some(other) => {
            problems.push(key.wrong_type(other, "a list of paths"));
            return Vec::new();
        }
        None => {
            problems.push(key.missing());
            return Vec::new();
        }
    };
    let mut out = Vec::new();
    for v in list {
        match v.as_str().map(str::trim).filter(|s| !s.is_empty()) {
            Some(s) => out.push(s.to_string()),
            None => problems.push(key.error(format!("entry {v} is not a path"))),
        }
    }
    out
}

/// `sigma_m` of `table` (`default` when absent and allowed).
fn sigma(table: &TomlTable, default: Option<f64>, problems: &mut Vec<Problem>) -> Option<f64> {
    let name = table.name;
    let key = table.key(
        "sigma_m",
        format!("state the {name}'s accuracy as sigma_m = 0.05 (metres, 1σ)"),
    );
    let v = match table.table.get("sigma_m") {
        None => {
            if default.is_none() {
                problems.push(key.missing());
            }
            return default;
        }
        Some(toml::Value::Float(f)) => *f,
        Some(toml::Value::Integer(i)) => *i as f64,
        Some(other) => {
            problems.push(key.wrong_type(other, "a number"));
            return None;
        }
    };
    if v.is_finite() && v > 0.0 && v <= 100.0 {
        Some(v)
    } else {
        problems.push(key.error(format!("is {v}; it must be in (0, 100] m")));
        None
    }
}

/// Headers of `files`, each checked (readable GeoTIFF, north-up, CRS of the campaign).
fn headers(
    root: &Path,
    name: &str,
    files: Vec<String>,
    crs: &str,
    problems: &mut Vec<Problem>,
) -> Vec<RasterFile> {
    let want = campaign_epsg(crs);
    let mut out = Vec::new();
    for file in files {
        let rel = PathBuf::from(&file);
        let header = match read_header(&root.join(&rel)) {
            Ok(h) => h,
            Err(message) => {
                let kind = if root.join(&rel).is_file() {
                    ProblemKind::ImageFormat
                } else {
                    ProblemKind::ImageMissing
                };
                problems.push(
                    Problem::error(
                        &rel,
                        None,
                        None,
                        message,
                        format!("give a north-up GeoTIFF as {name}.files in campaign.toml"),
                    )
                    .with_kind(kind),
                );
                continue;
            }
        };
        match (header.epsg, want) {
            (Some(got), Some(want)) if got != want => {
                problems.push(
                    Problem::error(
                        &rel,
                        None,
                        None,
                        format!("is in EPSG:{got}, the campaign in EPSG:{want}"),
                        format!("reproject it into the campaign CRS first (gdalwarp -t_srs EPSG:{want})"),
                    )
                    .with_kind(ProblemKind::Reference),
                );
                continue;
            }
            (None, _) => problems.push(Problem::warning(
                &rel,
                None,
                None,
                "names no EPSG code (ProjectedCSTypeGeoKey); taken to be in the campaign CRS",
                "check that it is, or write the CRS into the file (gdal_edit.py -a_srs)",
            )),
            _ => {}
        }
        out.push(RasterFile { file, header });
    }
    out
}

/// One table (`orthophoto` or `dtm`): its tiles and σ; `None` when absent or unusable (with problems).
fn read_table(
    root: &Path,
    text: &str,
    table: &toml::Table,
    name: &str,
    crs: &str,
    default_sigma: Option<f64>,
    problems: &mut Vec<Problem>,
) -> Option<(Vec<RasterFile>, f64)> {
    let value = table.get(name)?;
    let row = table_line(text, name);
    let Some(t) = value.as_table() else {
        let key = TomlKey {
            row,
            field: name.to_string(),
            hint: format!("write it as a table: [{name}] with files = [...] and sigma_m = ..."),
        };
        problems.push(key.wrong_type(value, "a table"));
        return None;
    };
    let t = TomlTable {
        table: t,
        name,
        row,
    };
    let files = files(&t, problems);
    let sigma_m = sigma(&t, default_sigma, problems);
    let tiles = headers(root, name, files, crs, problems);
    (!tiles.is_empty()).then_some(())?;
    Some((tiles, sigma_m?))
}

/// The `[orthophoto]` and `[dtm]` tables of the parsed `campaign.toml` (`text`) of the campaign in `root`
/// whose CRS is `crs`. A DTM without an orthophoto is reported (it has no use) and dropped.
pub fn read_orthophoto_tables(
    root: &Path,
    text: &str,
    table: &toml::Table,
    crs: &str,
    problems: &mut Vec<Problem>,
) -> (Option<OrthophotoSource>, Option<DtmSource>) {
    let ortho = read_table(root, text, table, "orthophoto", crs, None, problems)
        .map(|(tiles, sigma_m)| OrthophotoSource { tiles, sigma_m });
    let dtm = read_table(
        root,
        text,
        table,
        "dtm",
        crs,
        Some(DEFAULT_DTM_SIGMA_M),
        problems,
    )
    .map(|(tiles, sigma_m)| DtmSource { tiles, sigma_m });
    if dtm.is_some() && !table.contains_key("orthophoto") {
        problems.push(Problem::warning(
            TOML,
            table_line(text, "dtm"),
            Some("dtm"),
            "a DTM without an [orthophoto] table is not used",
            "add the [orthophoto] table, or remove [dtm]",
        ));
    }
    (ortho, dtm)
}
