//! Typed inputs: tuples mixing handles, raw files and collections reach the stage in order, with stable
//! labels; build-time dedupe merges identical nodes.

use skytie::dag::inputs::InputRef;
use skytie::dag::{DagBuilder, Handle, Mode, NodeCtx, RawFile, RawFileValue, Stage, StageError};
use skytie::testing::toy::{write_item, ToyParse};
use std::sync::Arc;

mod support;

/// value(a) * 1000 + first byte of file + sum(collection)
struct Mix;

impl Stage for Mix {
    skytie::stage_items!("mix", "1", () => f64, inputs: (Handle<f64>, RawFile, Vec<Handle<f64>>));
    fn run(
        &self,
        _: &(),
        (a, file, rest): (Arc<f64>, RawFileValue, Vec<Arc<f64>>),
        _: &NodeCtx,
    ) -> Result<f64, StageError> {
        let first = std::fs::read(&file.path)?[0] as f64;
        Ok(*a * 1000.0 + first + rest.iter().map(|v| **v).sum::<f64>())
    }
}

#[test]
fn tuple_inputs_arrive_in_order_with_position_labels() {
    let dir = tempfile::tempdir().unwrap();
    let files: Vec<_> = (0..3)
        .map(|i| {
            write_item(
                &dir.path().join("items"),
                &format!("i{i}.txt"),
                (i + 1) as f64,
            )
            .unwrap()
        })
        .collect();
    let mut b = DagBuilder::new();
    let hs: Vec<Handle<f64>> = files
        .iter()
        .map(|f| {
            b.add(
                ToyParse,
                &f.display().to_string(),
                Default::default(),
                RawFile(f.clone()),
            )
            .unwrap()
        })
        .collect();
    // Adding an identical node returns the same handle (build-time dedupe).
    let again = b
        .add(
            ToyParse,
            &files[0].display().to_string(),
            Default::default(),
            RawFile(files[0].clone()),
        )
        .unwrap();
    assert_eq!(again.id(), hs[0].id());
    let m = b
        .add(
            Mix,
            "",
            (),
            (hs[0], RawFile(files[1].clone()), vec![hs[1], hs[2]]),
        )
        .unwrap();
    b.request(m);
    let dag = b.build();
    assert_eq!(dag.len(), 4);
    let labels: Vec<(String, bool)> = dag.nodes()[3]
        .inputs
        .iter()
        .map(|(l, r)| (l.to_string(), matches!(r, InputRef::File(_))))
        .collect();
    assert_eq!(
        labels,
        vec![
            ("0".into(), false),
            ("1".into(), true),
            ("2.[0]".into(), false),
            ("2.[1]".into(), false)
        ]
    );
    let o = support::run(&dir.path().join("cache"), &dag, Mode::Run);
    // 1 * 1000 + b'2' (file i1.txt holds "2") + 2 + 3
    assert_eq!(*o.get(m).unwrap(), 1000.0 + b'2' as f64 + 5.0);
}
