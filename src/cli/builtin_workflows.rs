//! The shipped workflows of `workflows/`, built into the program so that `skytie run nadir --campaign DIR`
//! works from any folder. A file path is still accepted wherever a workflow is named; a name that is not an
//! existing file is looked up here (`nadir`, `nadir.toml` and `workflows/nadir.toml` all name the same one).

use crate::workflow::{Workflow, WorkflowError};
use std::path::Path;

/// `(file name, text)` of each named file of `workflows/`, compiled into the binary.
macro_rules! workflow_files {
    ($($name:literal),* $(,)?) => {
        &[$(($name, include_str!(concat!("../../workflows/", $name)))),*]
    };
}

/// Every shipped workflow file: (file name, text).
pub const BUILT_IN: &[(&str, &str)] = workflow_files![
    "adjust-sweep.toml",
    "default.toml",
    "nadir-baseline.toml",
    "nadir.toml",
    "oblique-sweep.toml",
    "oblique.toml",
    "orthophoto.toml",
    "paper.toml",
    "tiny.toml",
];

/// The workflow `spec` names: an existing file, else a built-in workflow.
pub fn load(spec: &Path) -> Result<Workflow, WorkflowError> {
    if spec.is_file() {
        return Workflow::load(spec);
    }
    let name = spec
        .to_string_lossy()
        .trim_start_matches("./")
        .trim_start_matches("workflows/")
        .to_string();
    let plain = !name.contains('/') && !name.contains('\\');
    if plain
        && BUILT_IN
            .iter()
            .any(|(n, _)| *n == name || n.trim_end_matches(".toml") == name)
    {
        return Workflow::built_in(&name, BUILT_IN);
    }
    Err(WorkflowError::in_file(
        spec,
        format!(
            "no such workflow file, and no built-in workflow of that name (built in: {}); \
             `skytie workflows` lists them, `skytie workflows show NAME` prints one to copy",
            names().join(", ")
        ),
    ))
}

/// Names of the built-in workflows (file names without `.toml`).
pub fn names() -> Vec<&'static str> {
    BUILT_IN
        .iter()
        .map(|(n, _)| n.trim_end_matches(".toml"))
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_shipped_workflow_is_built_in_and_loads() {
        let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("workflows");
        let mut on_disk: Vec<String> = std::fs::read_dir(&dir)
            .unwrap()
            .flatten()
            .map(|e| e.file_name().to_string_lossy().into_owned())
            .filter(|n| n.ends_with(".toml"))
            .collect();
        on_disk.sort();
        let built_in: Vec<String> = BUILT_IN.iter().map(|(n, _)| n.to_string()).collect();
        assert_eq!(built_in, on_disk, "add new workflow files to BUILT_IN");
        for name in names() {
            let wf = Workflow::built_in(name, BUILT_IN).unwrap_or_else(|e| panic!("{name}: {e}"));
            assert!(!wf.stages.is_empty(), "{name}");
        }
    }

    #[test]
    fn names_paths_and_unknown_names() {
        let from_name = load(Path::new("nadir-baseline")).unwrap();
        let from_path = load(Path::new("workflows/nadir-baseline.toml")).unwrap();
        assert_eq!(from_name.stages, from_path.stages);
        let err = load(Path::new("nadr")).unwrap_err().to_string();
        assert!(err.contains("built in:") && err.contains("nadir"), "{err}");
    }
}
