//! `DagBuilder::add`: equal nodes dedupe (within and across variants); one identity `stage[item]` may denote
//! only one node per variant, and a clash is refused with an error naming stage, item and variants.

mod support;

use skytie::dag::{BuildError, DagBuilder, Handle, RawFile};
use skytie::testing::toy::{ToyParse, ToyParseParams, ToyScale, ToyScaleParams};
use std::path::{Path, PathBuf};
use support::*;

/// Adds the `toy_parse[a]` node reading `file`.
fn add_parse(b: &mut DagBuilder, file: &Path) -> Result<Handle<f64>, BuildError> {
    b.add(
        ToyParse,
        "a",
        ToyParseParams::default(),
        RawFile(file.to_path_buf()),
    )
}

/// A builder holding `toy_parse[a]` of the first of the toy items of `values` (written to `dir`), that node,
/// and the items.
fn builder_with_parse(dir: &Path, values: &[f64]) -> (DagBuilder, Handle<f64>, Vec<PathBuf>) {
    let items = make_items(dir, values);
    let mut b = DagBuilder::new();
    let parse = add_parse(&mut b, &items[0]).unwrap();
    (b, parse, items)
}

fn scale(factor: f64) -> ToyScaleParams {
    ToyScaleParams {
        factor,
        ..ToyScaleParams::default()
    }
}

#[test]
fn equal_nodes_dedupe_and_variants_may_differ() {
    let dir = tempfile::tempdir().unwrap();
    let (mut b, parse, _) = builder_with_parse(dir.path(), &[1.0]);
    let s1 = b.add(ToyScale, "a", scale(2.0), parse).unwrap();
    // Same identity, same key, same variant: the existing node.
    let again = b.add(ToyScale, "a", scale(2.0), parse).unwrap();
    assert_eq!(s1.id(), again.id());
    // Another variant may hold a different node of the same identity (that is what a sweep is).
    b.set_variant("other");
    let s2 = b.add(ToyScale, "a", scale(3.0), parse).unwrap();
    assert_ne!(s1.id(), s2.id());
    // ... and sharing the first one from a third variant is fine too.
    b.set_variant("third");
    assert_eq!(
        b.add(ToyScale, "a", scale(2.0), parse).unwrap().id(),
        s1.id()
    );
    let dag = b.build();
    assert_eq!(dag.len(), 3);
    assert_eq!(dag.nodes()[s1.id()].variants, vec!["default", "third"]);
    assert_eq!(dag.nodes()[s2.id()].variants, vec!["other"]);
}

#[test]
fn same_identity_with_another_key_in_one_variant_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let (mut b, parse, items) = builder_with_parse(dir.path(), &[1.0, 2.0]);
    b.add(ToyScale, "a", scale(2.0), parse).unwrap();
    let err = b.add(ToyScale, "a", scale(5.0), parse).unwrap_err();
    let m = &err.message;
    assert!(
        m.contains("stage toy_scale, item 'a'")
            && m.contains("toy_scale[a]")
            && m.contains("variant 'default'")
            && m.contains("factor: 2.0 -> 5.0"),
        "{m}"
    );
    // Different inputs, equal params: also a clash (another key), explained as such.
    let err = add_parse(&mut b, &items[1]).unwrap_err();
    assert!(
        err.message.contains("toy_parse[a]") && err.message.contains("different inputs"),
        "{}",
        err.message
    );
    // The refused adds left the graph unchanged.
    assert_eq!(b.len(), 2);
}

#[test]
fn a_shared_node_clashes_with_a_different_one_in_a_variant_that_uses_it() {
    let dir = tempfile::tempdir().unwrap();
    let (mut b, parse, _) = builder_with_parse(dir.path(), &[1.0]);
    b.add(ToyScale, "a", scale(2.0), parse).unwrap();
    b.set_variant("exp1");
    // exp1 shares the default's node ...
    b.add(ToyScale, "a", scale(2.0), parse).unwrap();
    // ... so a different toy_scale[a] in exp1 is ambiguous: both variants are named.
    let err = b.add(ToyScale, "a", scale(4.0), parse).unwrap_err();
    assert!(
        err.message
            .contains("first added for variant(s) 'default', 'exp1'")
            && err.message.contains("then again for variant 'exp1'"),
        "{}",
        err.message
    );
}
