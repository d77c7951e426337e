//! Running one cell of an evaluation: a workflow that includes the matrix's workflow and sets the campaign
//! (`synth:<preset>`), the seed and the error profile, run by this same `skytie` binary in a child process
//! (`skytie run … --quiet`) with the evaluation's shared cache, so the renderings of a scene are made once and
//! reused by every table-only profile. The child's output goes to the cell's `run.log`.

use super::matrix::Cell;
use std::path::{Path, PathBuf};
use std::process::Command;

/// How a cell's run ended.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum CellRun {
    /// `skytie run` finished (exit 0, or 3 for a flagged result such as an adjustment that corrected nothing —
    /// graded like any other; the `corrected` column counts it); results in the folder.
    Done(PathBuf),
    /// It exited non-zero: what the log's last line says.
    Failed(String),
}

/// The workflow text of `cell` (includes the matrix workflow by its absolute path).
pub fn cell_workflow(cell: &Cell) -> Result<String, String> {
    let base = std::fs::canonicalize(&cell.workflow)
        .map_err(|e| format!("{}: {e}", cell.workflow.display()))?;
    Ok(format!(
        "# Evaluation cell {} (written by skytie eval)\ninclude = [{:?}]\nname = \"eval\"\n\
         campaign = \"synth:{}\"\nseed = {}\n\n[synth]\nprofile = {:?}\n",
        cell.label(),
        base.to_string_lossy(),
        cell.preset,
        cell.seed,
        cell.profile
    ))
}

/// The last non-empty line of `text`.
fn last_line(text: &str) -> String {
    text.lines()
        .rev()
        .find(|l| !l.trim().is_empty())
        .unwrap_or("(no output)")
        .to_string()
}

/// Run `cell` with `skytie` (`exe`) into `out_root/<label>` with the cache `cache`; `Err` only when the cell
/// could not be started at all (a setup error that every other cell would hit too).
pub fn run_cell(exe: &Path, cell: &Cell, out_root: &Path, cache: &Path) -> Result<CellRun, String> {
    let dir = out_root.join(cell.label());
    std::fs::create_dir_all(&dir).map_err(|e| format!("{}: {e}", dir.display()))?;
    let wf = dir.join("workflow.toml");
    std::fs::write(&wf, cell_workflow(cell)?).map_err(|e| format!("{}: {e}", wf.display()))?;
    let out = dir.join("out");
    let output = Command::new(exe)
        .arg("run")
        .arg(&wf)
        .arg("--cache")
        .arg(cache)
        .arg("--out")
        .arg(&out)
        .arg("--quiet")
        .output()
        .map_err(|e| format!("cannot start {}: {e}", exe.display()))?;
    let log = [output.stdout.as_slice(), output.stderr.as_slice()].concat();
    let log_path = dir.join("run.log");
    std::fs::write(&log_path, &log).map_err(|e| format!("{}: {e}", log_path.display()))?;
    let text = String::from_utf8_lossy(&output.stderr);
    match output.status.code() {
        Some(0 | 3) => Ok(CellRun::Done(out)),
        Some(2) => Err(format!(
            "{}: skytie run refused the workflow: {} (see {})",
            cell.label(),
            last_line(&text),
            log_path.display()
        )),
        _ => Ok(CellRun::Failed(last_line(&text))),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_cell_workflow_includes_the_base_and_sets_campaign_seed_and_profile() {
        let dir = tempfile::tempdir().unwrap();
        let base = dir.path().join("base.toml");
        std::fs::write(&base, "name = \"x\"\n").unwrap();
        let cell = Cell {
            preset: "demo".into(),
            row: "demo".into(),
            profile: "thesis+ins".into(),
            seed: 101,
            workflow: base.clone(),
        };
        let t = cell_workflow(&cell).unwrap();
        let v: toml::Table = toml::from_str(&t).unwrap();
        assert_eq!(v["campaign"].as_str(), Some("synth:demo"));
        assert_eq!(v["seed"].as_integer(), Some(101));
        assert_eq!(v["synth"]["profile"].as_str(), Some("thesis+ins"));
        let inc = v["include"].as_array().unwrap()[0].as_str().unwrap();
        assert_eq!(Path::new(inc), std::fs::canonicalize(&base).unwrap());
        assert_eq!(last_line("a\nb\n\n"), "b");
    }
}
