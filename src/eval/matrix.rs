//! The evaluation matrix (`benches/eval/matrix.toml`): which presets, error profiles and held-out seeds an
//! evaluation runs, with which workflow, and which seeds were used while developing (never reported).
//!
//! ```toml
//! workflow = "../../workflows/default.toml"   # relative to this file
//! [development]                              # seeds looked at while tuning: refused as held-out seeds
//! demo = [1, 2, 3]
//! [[preset]]
//! name = "demo"
//! seeds = [101, 102, 103, 104, 105]
//! profiles = ["thesis", "outage", "ins"]
//! ```

use serde::Deserialize;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

/// One preset's part of the matrix.
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PresetCells {
    /// `tiny`, `demo` (the `paper` preset renders for hours: not for a matrix).
    pub name: String,
    /// Held-out seeds.
    pub seeds: Vec<u64>,
    /// Error profiles (`skytie synth --profile` names).
    pub profiles: Vec<String>,
    /// Workflow of this preset, relative to the matrix file (default: the matrix's `workflow`).
    pub workflow: Option<PathBuf>,
    /// Name of its rows in the table and of its output folder (default: `name`): one preset rendered two
    /// ways (another workflow, e.g. with `[synth] panorama_width_px`) needs two labels.
    pub label: Option<String>,
}

impl PresetCells {
    /// The rows' name: `label`, else `name`.
    pub fn row(&self) -> &str {
        self.label.as_deref().unwrap_or(&self.name)
    }
}

/// The whole matrix.
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Matrix {
    /// Workflow run for every cell, relative to the matrix file; its `campaign`, `seed` and `[synth] profile`
    /// are replaced per cell.
    pub workflow: PathBuf,
    /// Seeds used while developing, per preset.
    #[serde(default)]
    pub development: BTreeMap<String, Vec<u64>>,
    #[serde(rename = "preset")]
    pub presets: Vec<PresetCells>,
}

/// One run of the matrix.
#[derive(Clone, Debug, PartialEq, Eq, PartialOrd, Ord)]
pub struct Cell {
    /// The synthetic preset rendered (`synth:<preset>`).
    pub preset: String,
    /// The preset's row name in the table ([`PresetCells::row`]).
    pub row: String,
    pub profile: String,
    pub seed: u64,
    /// Absolute or working-directory-relative workflow path.
    pub workflow: PathBuf,
}

impl Cell {
    /// `preset/profile/seedN`, also the cell's output folder below the evaluation's.
    pub fn label(&self) -> String {
        format!("{}/{}/seed{}", self.row, self.profile, self.seed)
    }
}

impl Matrix {
    /// Read and check `path`; the error names the file and what is wrong.
    pub fn load(path: &Path) -> Result<Self, String> {
        let text = std::fs::read_to_string(path).map_err(|e| format!("{}: {e}", path.display()))?;
        let m: Matrix = toml::from_str(&text).map_err(|e| format!("{}: {e}", path.display()))?;
        m.check().map_err(|e| format!("{}: {e}", path.display()))?;
        Ok(m)
    }

    /// Held-out seeds must not be development seeds, and every list must be non-empty.
    fn check(&self) -> Result<(), String> {
        if self.presets.is_empty() {
            return Err("no [[preset]]: name at least one preset with seeds and profiles".into());
        }
        for (i, p) in self.presets.iter().enumerate() {
            if self.presets[..i].iter().any(|q| q.row() == p.row()) {
                return Err(format!(
                    "two [[preset]] entries are labelled '{}': give each a distinct `label`",
                    p.row()
                ));
            }
            if p.seeds.is_empty() || p.profiles.is_empty() {
                return Err(format!("preset '{}' needs seeds and profiles", p.name));
            }
            let dev = self.development.get(&p.name).cloned().unwrap_or_default();
            if let Some(s) = p.seeds.iter().find(|s| dev.contains(s)) {
                return Err(format!(
                    "seed {s} of preset '{}' is a development seed: held-out results must come from seeds \
                     never looked at while tuning",
                    p.name
                ));
            }
        }
        Ok(())
    }

    /// Every cell, preset by preset, profile by profile, seed by seed; `only_presets` (names or labels) and
    /// `only_profiles` (empty = all) and `max_seeds` (0 = all) select a part. Workflow paths are resolved against `matrix_dir`.
    pub fn cells(
        &self,
        matrix_dir: &Path,
        only_presets: &[String],
        only_profiles: &[String],
        max_seeds: usize,
    ) -> Vec<Cell> {
        let mut out = Vec::new();
        for p in &self.presets {
            if !only_presets.is_empty()
                && !only_presets.iter().any(|o| *o == p.name || o == p.row())
            {
                continue;
            }
            let workflow = matrix_dir.join(p.workflow.as_ref().unwrap_or(&self.workflow));
            let seeds = if max_seeds == 0 {
                &p.seeds[..]
            } else {
                &p.seeds[..max_seeds.min(p.seeds.len())]
            };
            for profile in &p.profiles {
                if !only_profiles.is_empty() && !only_profiles.contains(profile) {
                    continue;
                }
                for &seed in seeds {
                    out.push(Cell {
                        preset: p.name.clone(),
                        row: p.row().to_string(),
                        profile: profile.clone(),
                        seed,
                        workflow: workflow.clone(),
                    });
                }
            }
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cells_follow_the_matrix_and_development_seeds_are_refused() {
        let m: Matrix = toml::from_str(
            "workflow = \"wf.toml\"\n[development]\ndemo = [1, 2]\n\
             [[preset]]\nname = \"demo\"\nseeds = [7, 8]\nprofiles = [\"thesis\", \"outage\"]\n\
             [[preset]]\nname = \"tiny\"\nseeds = [5]\nprofiles = [\"thesis\"]\nworkflow = \"t.toml\"\n",
        )
        .unwrap();
        assert!(m.check().is_ok());
        let cells = m.cells(Path::new("/m"), &[], &[], 0);
        let labels: Vec<String> = cells.iter().map(|c| c.label()).collect();
        assert_eq!(
            labels,
            [
                "demo/thesis/seed7",
                "demo/thesis/seed8",
                "demo/outage/seed7",
                "demo/outage/seed8",
                "tiny/thesis/seed5"
            ]
        );
        assert_eq!(cells[4].workflow, Path::new("/m/t.toml"));
        assert_eq!(cells[0].workflow, Path::new("/m/wf.toml"));
        let some = m.cells(Path::new("/m"), &["demo".into()], &["outage".into()], 1);
        assert_eq!(some.len(), 1);
        let bad: Matrix = toml::from_str(
            "workflow = \"wf.toml\"\n[development]\ndemo = [1]\n\
             [[preset]]\nname = \"demo\"\nseeds = [1, 9]\nprofiles = [\"thesis\"]\n",
        )
        .unwrap();
        let e = bad.check().unwrap_err();
        assert!(e.contains("seed 1") && e.contains("development"), "{e}");
    }

    #[test]
    fn a_preset_rendered_two_ways_needs_two_labels() {
        let two = |label: &str| {
            format!(
                "workflow = \"wf.toml\"\n\
                 [[preset]]\nname = \"demo\"\nseeds = [7]\nprofiles = [\"thesis\"]\n\
                 [[preset]]\nname = \"demo\"\n{label}seeds = [7]\nprofiles = [\"thesis\"]\nworkflow = \"hi.toml\"\n"
            )
        };
        let same: Matrix = toml::from_str(&two("")).unwrap();
        let e = same.check().unwrap_err();
        assert!(e.contains("'demo'") && e.contains("label"), "{e}");
        let m: Matrix = toml::from_str(&two("label = \"demo-hi\"\n")).unwrap();
        assert!(m.check().is_ok());
        let cells = m.cells(Path::new("/m"), &[], &[], 0);
        assert_eq!(cells[1].label(), "demo-hi/thesis/seed7");
        assert_eq!(
            (cells[1].preset.as_str(), cells[1].row.as_str()),
            ("demo", "demo-hi")
        );
        assert_eq!(cells[1].workflow, Path::new("/m/hi.toml"));
        // Selected by name (both) or by label (that one).
        assert_eq!(m.cells(Path::new("/m"), &["demo".into()], &[], 0).len(), 2);
        assert_eq!(
            m.cells(Path::new("/m"), &["demo-hi".into()], &[], 0).len(),
            1
        );
    }
}
