//! Reading a run's output folder for the report: `metrics.json`, `provenance.json`, the per-variant folders
//! of a sweep, `sweep.csv`, and the CSV exports (`checkpoints.csv`, `verification.csv`,
//! `trajectory_adjusted.csv`, `correspondences.csv`). Everything is optional except `metrics.json`; a
//! missing file leaves its section out of the report.

use serde_json::Value;
use std::path::{Path, PathBuf};

/// One set of results: the whole run (not a sweep) or one variant of a sweep.
#[derive(Debug)]
pub struct ResultSet {
    /// Variant name, or "" for a plain run.
    pub name: String,
    /// Folder holding its metrics.json and exports.
    pub dir: PathBuf,
    pub metrics: Value,
}

impl ResultSet {
    /// What the HTML anchors and figure files of this set start with: nothing for a plain run, `variant-` for
    /// a sweep variant.
    pub fn anchor_prefix(&self) -> String {
        if self.name.is_empty() {
            String::new()
        } else {
            format!("{}-", super::slug(&self.name))
        }
    }

    /// What figure titles of this set end with: nothing for a plain run, ` (variant)` for a sweep variant.
    pub fn title_suffix(&self) -> String {
        if self.name.is_empty() {
            String::new()
        } else {
            format!(" ({})", self.name)
        }
    }
}

/// Everything the report reads from OUT.
#[derive(Debug)]
pub struct RunOutputs {
    pub out_dir: PathBuf,
    /// Top-level metrics.json (engine, stages; for a plain run also the sections).
    pub metrics: Value,
    pub provenance: Option<Value>,
    /// The plain run, or every variant of a sweep (in `metrics.variants` order).
    pub sets: Vec<ResultSet>,
    /// `sweep.csv` as (header, rows), when present.
    pub sweep: Option<CsvTable>,
    pub is_sweep: bool,
}

/// A CSV file held as strings (header and rows).
#[derive(Clone, Debug, Default)]
pub struct CsvTable {
    pub header: Vec<String>,
    pub rows: Vec<Vec<String>>,
}

impl CsvTable {
    /// A table from literal cells (tests and fixtures).
    pub fn from_cells(header: &[&str], rows: &[&[&str]]) -> Self {
        let owned = |r: &[&str]| r.iter().map(|c| (*c).to_string()).collect::<Vec<_>>();
        Self {
            header: owned(header),
            rows: rows.iter().map(|r| owned(r)).collect(),
        }
    }

    /// Index of a column.
    pub fn col(&self, name: &str) -> Option<usize> {
        self.header.iter().position(|h| h == name)
    }

    /// A cell parsed as a number (None when the column is missing, the cell empty or not a number).
    pub fn num(&self, row: &[String], name: &str) -> Option<f64> {
        let i = self.col(name)?;
        row.get(i)?.trim().parse::<f64>().ok()
    }

    /// A cell as text ("" when missing).
    pub fn text<'a>(&self, row: &'a [String], name: &str) -> &'a str {
        self.col(name)
            .and_then(|i| row.get(i))
            .map_or("", |s| s.as_str())
    }
}

/// Reads a CSV file with a header line. Errors name the file, and the row for malformed lines.
pub fn read_csv(path: &Path) -> Result<CsvTable, String> {
    let mut reader = csv::ReaderBuilder::new()
        .has_headers(true)
        .flexible(true)
        .from_path(path)
        .map_err(|e| format!("{}: cannot read: {e}", path.display()))?;
    let header = reader
        .headers()
        .map_err(|e| format!("{}: bad header: {e}", path.display()))?
        .iter()
        .map(|s| s.to_string())
        .collect();
    let mut rows = Vec::new();
    for (i, rec) in reader.records().enumerate() {
        let rec = rec.map_err(|e| format!("{}: row {}: {e}", path.display(), i + 2))?;
        rows.push(rec.iter().map(|s| s.to_string()).collect());
    }
    Ok(CsvTable { header, rows })
}

/// The header of a CSV file being streamed by [`for_each_row`]: cells of a row by column name.
pub struct CsvColumns {
    pub header: Vec<String>,
}

impl CsvColumns {
    /// Index of a column.
    pub fn col(&self, name: &str) -> Option<usize> {
        self.header.iter().position(|h| h == name)
    }
}

/// Streams the rows of a CSV file with a header line to `f` (one record buffer, reused), without holding the
/// file; returns the header, `Ok(None)` when the file does not exist. Errors name the file, and the row for
/// malformed lines.
pub fn for_each_row(
    path: &Path,
    mut f: impl FnMut(&CsvColumns, &csv::StringRecord),
) -> Result<Option<CsvColumns>, String> {
    if !path.exists() {
        return Ok(None);
    }
    let mut reader = csv::ReaderBuilder::new()
        .has_headers(true)
        .flexible(true)
        .from_path(path)
        .map_err(|e| format!("{}: cannot read: {e}", path.display()))?;
    let columns = CsvColumns {
        header: reader
            .headers()
            .map_err(|e| format!("{}: bad header: {e}", path.display()))?
            .iter()
            .map(|s| s.to_string())
            .collect(),
    };
    let mut rec = csv::StringRecord::new();
    let mut row = 2;
    loop {
        match reader.read_record(&mut rec) {
            Ok(true) => f(&columns, &rec),
            Ok(false) => break,
            Err(e) => return Err(format!("{}: row {row}: {e}", path.display())),
        }
        row += 1;
    }
    Ok(Some(columns))
}

/// Reads the rows of an optional CSV file whose `column` holds `value` (e.g. the `recording` rows of
/// `corrections.csv`, a few of every ten), streaming past the others: Ok(None) when the file does not exist.
pub fn read_csv_where(path: &Path, column: &str, value: &str) -> Result<Option<CsvTable>, String> {
    let mut rows = Vec::new();
    let mut at = None;
    let columns = for_each_row(path, |cols, rec| {
        let i = *at.get_or_insert_with(|| cols.col(column));
        if i.and_then(|i| rec.get(i)) == Some(value) {
            rows.push(rec.iter().map(|s| s.to_string()).collect());
        }
    })?;
    Ok(columns.map(|c| CsvTable {
        header: c.header,
        rows,
    }))
}

/// Reads an optional CSV file: Ok(None) when it does not exist.
pub fn read_csv_opt(path: &Path) -> Result<Option<CsvTable>, String> {
    if !path.exists() {
        return Ok(None);
    }
    read_csv(path).map(Some)
}

fn read_json(path: &Path) -> Result<Value, String> {
    let bytes = std::fs::read(path).map_err(|e| format!("{}: cannot read: {e}", path.display()))?;
    serde_json::from_slice(&bytes).map_err(|e| {
        format!(
            "{}: not valid JSON ({e}); re-run `skytie run` to rewrite it",
            path.display()
        )
    })
}

impl RunOutputs {
    /// Reads OUT. Err when `OUT/metrics.json` is missing or unreadable (the message says what to do).
    pub fn read(out_dir: &Path) -> Result<Self, String> {
        let mpath = out_dir.join("metrics.json");
        if !mpath.exists() {
            return Err(format!(
                "{} does not exist: OUT must be the output folder of `skytie run` (its --out)",
                mpath.display()
            ));
        }
        let metrics = read_json(&mpath)?;
        let ppath = out_dir.join("provenance.json");
        let provenance = if ppath.exists() {
            Some(read_json(&ppath)?)
        } else {
            None
        };
        let variant_names: Vec<String> = metrics
            .get("variants")
            .and_then(|v| v.as_array())
            .map(|a| {
                a.iter()
                    .filter_map(|v| v.as_str().map(str::to_string))
                    .collect()
            })
            .unwrap_or_default();
        let is_sweep = !variant_names.is_empty();
        let mut sets = Vec::new();
        if is_sweep {
            for name in &variant_names {
                let dir = out_dir.join("variants").join(name);
                let vm = dir.join("metrics.json");
                let m = if vm.exists() {
                    read_json(&vm)?
                } else {
                    Value::Null
                };
                sets.push(ResultSet {
                    name: name.clone(),
                    dir,
                    metrics: m,
                });
            }
        } else {
            sets.push(ResultSet {
                name: String::new(),
                dir: out_dir.to_path_buf(),
                metrics: metrics.clone(),
            });
        }
        let sweep = read_csv_opt(&out_dir.join("sweep.csv"))?;
        Ok(Self {
            out_dir: out_dir.to_path_buf(),
            metrics,
            provenance,
            sets,
            sweep,
            is_sweep,
        })
    }

    /// The campaign folder recorded in provenance.json: `campaign.path`, else (a generated `synth:`
    /// campaign) the folder of the hashed raw input `…/mm/recordings.csv`.
    pub fn campaign_dir(&self) -> Option<PathBuf> {
        let prov = self.provenance.as_ref()?;
        if let Some(p) = prov
            .get("campaign")
            .and_then(|c| c.get("path"))
            .and_then(|p| p.as_str())
        {
            return Some(PathBuf::from(p));
        }
        prov.get("raw_inputs")?
            .as_object()?
            .keys()
            .find_map(|k| k.strip_suffix("/mm/recordings.csv").map(PathBuf::from))
    }
}

/// A number at a dotted path in a JSON document (`"adjust.nadir.checkpoints.after.2d"`).
pub fn num_at(v: &Value, dotted: &str) -> Option<f64> {
    let mut cur = v;
    for part in dotted.split('.') {
        cur = cur.get(part)?;
    }
    cur.as_f64()
        .or_else(|| cur.as_bool().map(|b| if b { 1.0 } else { 0.0 }))
}

/// A string at a dotted path.
pub fn str_at<'a>(v: &'a Value, dotted: &str) -> Option<&'a str> {
    let mut cur = v;
    for part in dotted.split('.') {
        cur = cur.get(part)?;
    }
    cur.as_str()
}

/// The object at a dotted path.
pub fn obj_at<'a>(v: &'a Value, dotted: &str) -> Option<&'a serde_json::Map<String, Value>> {
    let mut cur = v;
    for part in dotted.split('.') {
        cur = cur.get(part)?;
    }
    cur.as_object()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn dotted_paths() {
        let v = serde_json::json!({"a": {"b": {"c": 1.5, "ok": true, "s": "x"}}});
        assert_eq!(num_at(&v, "a.b.c"), Some(1.5));
        assert_eq!(num_at(&v, "a.b.ok"), Some(1.0));
        assert_eq!(num_at(&v, "a.b.missing"), None);
        assert_eq!(str_at(&v, "a.b.s"), Some("x"));
        assert!(obj_at(&v, "a.b").is_some());
    }

    #[test]
    fn missing_metrics_is_an_error_that_says_what_to_do() {
        let d = tempfile::tempdir().unwrap();
        let e = RunOutputs::read(d.path()).unwrap_err();
        assert!(e.contains("metrics.json") && e.contains("--out"), "{e}");
    }

    #[test]
    fn filtered_rows_stream_past_the_others() {
        let d = tempfile::tempdir().unwrap();
        let p = d.path().join("c.csv");
        std::fs::write(&p, "id,kind\na,recording\n,between\nb,recording\n").unwrap();
        let t = read_csv_where(&p, "kind", "recording").unwrap().unwrap();
        assert_eq!(t.header, ["id", "kind"]);
        assert_eq!(t.rows.len(), 2);
        assert_eq!(t.text(&t.rows[1], "id"), "b");
        let empty = read_csv_where(&p, "kind", "nothing").unwrap().unwrap();
        assert!(empty.rows.is_empty() && empty.header.len() == 2);
        assert!(read_csv_where(&d.path().join("no.csv"), "kind", "x")
            .unwrap()
            .is_none());
    }

    #[test]
    fn csv_cells() {
        let d = tempfile::tempdir().unwrap();
        let p = d.path().join("a.csv");
        std::fs::write(&p, "id,v\n\"x,1\",2.5\ny,\n").unwrap();
        let t = read_csv(&p).unwrap();
        assert_eq!(t.text(&t.rows[0], "id"), "x,1");
        assert_eq!(t.num(&t.rows[0], "v"), Some(2.5));
        assert_eq!(t.num(&t.rows[1], "v"), None);
    }
}
