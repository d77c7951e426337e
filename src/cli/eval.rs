//! `skytie eval`: the held-out evaluation. Runs every cell of a matrix (presets × error profiles × held-out
//! seeds, `benches/eval/matrix.toml`) through its workflow with one shared cache, grades each run against the
//! campaign's truth, prints one table (mean and worst case per preset and profile) and writes it to
//! `OUT/table.md` and `OUT/eval.json`. With `--compare BASELINE` it exits 1 when a number got worse than the
//! baseline's beyond its noise band (the regression guard); `--write-baseline FILE` records the table as the
//! new baseline. A cell whose run fails is counted, not fatal; a workflow that does not load stops everything.

use crate::eval::{
    build_table, compare, grade_cell, render_markdown, run_cell, Baseline, CellRun, Matrix, Table,
};
use clap::Args;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// Arguments of `skytie eval`.
#[derive(Args, Debug)]
pub struct EvalArgs {
    /// The matrix of presets, profiles and held-out seeds.
    #[arg(long, default_value = "benches/eval/matrix.toml")]
    pub matrix: PathBuf,
    /// Output folder: one sub-folder per cell (workflow, run log, run output), table.md, eval.json.
    #[arg(long, default_value = "out/eval")]
    pub out: PathBuf,
    /// Cache shared by all cells (renderings are reused across table-only profiles).
    #[arg(long, default_value = "cache")]
    pub cache: PathBuf,
    /// Compare with this baseline; exit 1 on a regression.
    #[arg(long)]
    pub compare: Option<PathBuf>,
    /// Write the table as a new baseline to this file.
    #[arg(long)]
    pub write_baseline: Option<PathBuf>,
    /// Only these presets, by name or `label` (repeatable; default all of the matrix).
    #[arg(long = "preset")]
    pub presets: Vec<String>,
    /// Only these profiles (repeatable; default all of the matrix).
    #[arg(long = "profile")]
    pub profiles: Vec<String>,
    /// Only the first N seeds of each preset (0 = all).
    #[arg(long, default_value_t = 0)]
    pub seeds: usize,
    /// Grade the cells already in OUT without running anything (e.g. after changing the grading).
    #[arg(long)]
    pub grade_only: bool,
}

/// Run (or only grade) every selected cell; the rows of the table input.
fn run_cells(
    a: &EvalArgs,
    matrix: &Matrix,
) -> Result<Vec<(String, u64, Option<crate::eval::CellMetrics>)>, String> {
    let dir = a.matrix.parent().unwrap_or(Path::new("."));
    let cells = matrix.cells(dir, &a.presets, &a.profiles, a.seeds);
    if cells.is_empty() {
        return Err("no cell selected: check --preset / --profile against the matrix".into());
    }
    let exe = std::env::current_exe().map_err(|e| format!("cannot find the skytie binary: {e}"))?;
    let mut rows = Vec::new();
    for (i, cell) in cells.iter().enumerate() {
        let start = Instant::now();
        let out = if a.grade_only {
            Some(a.out.join(cell.label()).join("out"))
        } else {
            match run_cell(&exe, cell, &a.out, &a.cache)? {
                CellRun::Done(out) => Some(out),
                CellRun::Failed(why) => {
                    eprintln!(
                        "[{}/{}] {}: run failed: {why}",
                        i + 1,
                        cells.len(),
                        cell.label()
                    );
                    None
                }
            }
        };
        let metrics = match out.map(|o| grade_cell(&o)) {
            Some(Ok(m)) => Some(m),
            Some(Err(e)) => {
                eprintln!(
                    "[{}/{}] {}: cannot grade: {e}",
                    i + 1,
                    cells.len(),
                    cell.label()
                );
                None
            }
            None => None,
        };
        if metrics.is_some() {
            eprintln!(
                "[{}/{}] {} graded ({:.0} s)",
                i + 1,
                cells.len(),
                cell.label(),
                start.elapsed().as_secs_f64()
            );
        }
        rows.push((format!("{}/{}", cell.row, cell.profile), cell.seed, metrics));
    }
    Ok(rows)
}

/// Write `text` to `path` (creating its folder); the error names the file.
fn write(path: &Path, text: &str) -> Result<(), String> {
    if let Some(d) = path.parent().filter(|d| !d.as_os_str().is_empty()) {
        std::fs::create_dir_all(d).map_err(|e| format!("{}: {e}", d.display()))?;
    }
    skytie_stages::fsutil::atomic_write(path, text.as_bytes())
        .map_err(|e| format!("{}: {e}", path.display()))
}

/// The command line that made the table (for the baseline and the docs).
fn command_line() -> String {
    let mut args: Vec<String> = std::env::args().skip(1).collect();
    args.insert(0, "skytie".into());
    args.join(" ")
}

/// Compare `table` with the baseline file; prints the findings, returns whether any regressed.
fn guard(path: &Path, table: &Table) -> Result<bool, String> {
    let text = std::fs::read_to_string(path).map_err(|e| format!("{}: {e}", path.display()))?;
    let base: Baseline =
        serde_json::from_str(&text).map_err(|e| format!("{}: {e}", path.display()))?;
    let findings = compare(&base.table, table);
    let regressions = findings.iter().filter(|f| f.regression).count();
    for f in &findings {
        let tag = if f.regression { "REGRESSION" } else { "note" };
        println!("{tag}: {}: {}", f.row, f.what);
    }
    println!(
        "compared with {} (made by `{}`): {regressions} regression(s)",
        path.display(),
        base.command
    );
    Ok(regressions > 0)
}

/// Run `skytie eval`; returns the exit code.
pub fn main(a: &EvalArgs) -> i32 {
    let result = (|| -> Result<i32, String> {
        let matrix = Matrix::load(&a.matrix)?;
        let rows = run_cells(a, &matrix)?;
        let table = build_table(&rows);
        let md = render_markdown(&table);
        println!("{md}");
        write(&a.out.join("table.md"), &md)?;
        let baseline = Baseline {
            command: command_line(),
            table: table.clone(),
        };
        let json = serde_json::to_string_pretty(&baseline).map_err(|e| e.to_string())?;
        write(&a.out.join("eval.json"), &json)?;
        if let Some(p) = &a.write_baseline {
            write(p, &json)?;
            println!("baseline written to {}", p.display());
        }
        match &a.compare {
            Some(p) if guard(p, &table)? => Ok(1),
            _ => Ok(0),
        }
    })();
    result.unwrap_or_else(|e| {
        eprintln!("error: {e}");
        2
    })
}
