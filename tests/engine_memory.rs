//! Values are dropped as soon as no consumer needs them (leaf nodes right after their wave, inputs after
//! their last consumer), so a pipeline over many large images does not hold them all in memory.

use serde::{Deserialize, Serialize};
use skytie::dag::{DagBuilder, Handle, Mode, NodeCtx, Stage, StageError};
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::Arc;

mod support;

static LIVE: AtomicUsize = AtomicUsize::new(0);

/// An artifact that counts its live instances.
#[derive(Debug, Serialize, Deserialize)]
struct Tracked(u64);
skytie::serde_artifact!(Tracked);

impl Tracked {
    fn new(v: u64) -> Tracked {
        LIVE.fetch_add(1, Ordering::SeqCst);
        Tracked(v)
    }
}
impl Drop for Tracked {
    fn drop(&mut self) {
        LIVE.fetch_sub(1, Ordering::SeqCst);
    }
}

struct Make;
impl Stage for Make {
    skytie::stage_items!("make", "1", u64 => Tracked, inputs: ());
    fn run(&self, v: &u64, _: (), _: &NodeCtx) -> Result<Tracked, StageError> {
        Ok(Tracked::new(*v))
    }
}

/// Reads one Tracked and reports how many Tracked values are alive while it runs.
struct Observe;
impl Stage for Observe {
    skytie::stage_items!("observe", "1", () => u64, inputs: Handle<Tracked>);
    fn run(&self, _: &(), t: Arc<Tracked>, _: &NodeCtx) -> Result<u64, StageError> {
        Ok(t.0 * 1000 + LIVE.load(Ordering::SeqCst) as u64)
    }
}

#[test]
fn values_are_released_when_no_consumer_needs_them() {
    let dir = tempfile::tempdir().unwrap();
    let mut b = DagBuilder::new();
    // Wave 0: five leaves nobody reads and one value read by `observe`.
    for v in 0..5 {
        b.add(Make, &format!("leaf {v}"), v, ()).unwrap();
    }
    let read = b.add(Make, "read", 7, ()).unwrap();
    let obs = b.add(Observe, "", (), read).unwrap();
    b.request(obs);
    let dag = b.build();
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .unwrap();
    let o = pool.install(|| support::run(&dir.path().join("cache"), &dag, Mode::Run));
    assert_eq!(o.executed(), 7);
    // While `observe` ran, only the value it reads was alive: the five leaves had been dropped.
    assert_eq!(*o.get(obs).unwrap(), 7 * 1000 + 1);
    drop(o);
    assert_eq!(
        LIVE.load(Ordering::SeqCst),
        0,
        "nothing is kept after the run"
    );
}
