//! The architecture's invariants, checked on the source text: the engine does not import the photogrammetry
//! crate or the layers built on the engine, and no crate has an import cycle among sibling modules.

mod support;

use std::path::Path;
use support::module_graph::ModuleGraph;

/// The engine's modules (root crate): they know nothing of photogrammetry, node wrappers or pipelines.
const ENGINE: &[&str] = &["dag", "store", "workflow", "codec", "hashing"];
/// What the engine must not refer to: the layers built on top of it.
const ABOVE_ENGINE: &[&[&str]] = &[
    &["nodes"],
    &["pipelines"],
    &["report"],
    &["cli"],
    &["exports"],
];

fn root(rel: &str) -> std::path::PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join(rel)
}

#[test]
fn the_engine_does_not_import_photogrammetry_nodes_or_pipelines() {
    let graph = ModuleGraph::read(&root("src"));
    let mut violations = Vec::new();
    for module in ENGINE {
        for (file, what) in graph.forbidden_refs(&[module], ABOVE_ENGINE, &["skytie_stages"]) {
            violations.push(format!("{} refers to {what}", file.display()));
        }
    }
    assert!(
        violations.is_empty(),
        "engine boundary crossed:\n{}",
        violations.join("\n")
    );
}

#[test]
fn no_crate_has_an_import_cycle_among_sibling_modules() {
    let mut found = Vec::new();
    for krate in ["src", "stages/src", "util/src"] {
        for cycle in ModuleGraph::read(&root(krate)).sibling_cycles() {
            found.push(format!("{krate}: {cycle}"));
        }
    }
    assert!(
        found.is_empty(),
        "import cycles among sibling modules:\n{}",
        found.join("\n")
    );
}

#[test]
fn the_checker_sees_a_cycle_and_a_forbidden_import() {
    let dir = tempfile::tempdir().unwrap();
    let src = dir.path().join("src");
    std::fs::create_dir_all(src.join("dag")).unwrap();
    std::fs::write(src.join("lib.rs"), "pub mod dag;\npub mod nodes;\n").unwrap();
    std::fs::write(
        src.join("dag/mod.rs"),
        "pub mod a;\npub mod b;\npub use a::Alpha;\n",
    )
    .unwrap();
    std::fs::write(
        src.join("dag/a.rs"),
        "use super::b::Beta; // crate::nodes in a comment\npub struct Alpha;\n",
    )
    .unwrap();
    std::fs::write(
        src.join("dag/b.rs"),
        "pub struct Beta;\nfn f() -> crate::dag::Alpha { let _ = \"crate::nodes\"; crate::nodes::x() }\n",
    )
    .unwrap();
    std::fs::write(src.join("nodes.rs"), "pub fn x() {}\n").unwrap();
    let graph = ModuleGraph::read(&src);
    assert_eq!(graph.sibling_cycles(), vec!["dag: {a, b}".to_string()]);
    let bad = graph.forbidden_refs(&["dag"], &[&["nodes"]], &[]);
    assert_eq!(bad.len(), 1, "{bad:?}");
    assert!(bad[0].0.ends_with("dag/b.rs"));
}

/// Prints the sibling edges of one module (`SKYTIE_MODULE=dag cargo test --test architecture -- --ignored
/// --nocapture`): a map for untangling a cycle the tests above report.
#[test]
#[ignore = "a diagnostic printout, not a check"]
fn print_sibling_edges() {
    let krate = std::env::var("SKYTIE_CRATE").unwrap_or_else(|_| "src".into());
    let module = std::env::var("SKYTIE_MODULE").unwrap_or_default();
    let path: Vec<String> = module
        .split("::")
        .filter(|s| !s.is_empty())
        .map(str::to_string)
        .collect();
    let graph = ModuleGraph::read(&root(&krate));
    for (from, to) in graph
        .sibling_edges()
        .get(&path)
        .cloned()
        .unwrap_or_default()
    {
        println!(
            "{from} -> {}",
            to.into_iter().collect::<Vec<_>>().join(", ")
        );
    }
}
