//! A synthetic DAG shaped like a city campaign of the `skytie` pipeline, built from cheap toy stages (a few
//! integer mixes each, an 8-byte artifact): it measures the engine — building, keys, cache checks, records —
//! and not photogrammetry. Used by `benches/engine_city.rs` and the engine's tests.
//!
//! Per recording `r` of `R` (in trajectory order):
//! * `city_recording` → `city_ortho`;
//! * `city_mm_match` over the window of `r` and its next one or two recordings (2–3 members);
//! * per overlapping aerial nadir image (2–4 of them; an image is shared by the recordings it covers):
//!   `city_ortho_aerial` → `city_transform` → `city_agreement` (reads every transform of `r`) → `city_refine`
//!   (reads the recording's window, optionally);
//! * `city_control` over the window and the recording's refinements (optional inputs);
//! * per triplet `r, r+1, r+2`: `city_sparse_cloud` → `city_facades` → per overlapping oblique image (1–3)
//!   `city_patches`.
//!
//! Campaign-wide fan-in nodes: `city_consensus` (every patch), `city_adjust` (every control and the consensus),
//! `city_verify` (the adjustment and every recording) and `city_summary` (every window, agreement, refinement
//! and control). Aerial and oblique images are source nodes of their own (`city_aerial`, `city_oblique`).

use crate::dag::{
    optional_all, BuildError, DagBuilder, Handle, InputsOf, NodeCtx, Optional, RunResult, Stage,
};
use serde::{Deserialize, Serialize};
use std::sync::Arc;

/// Parameters of every city stage: the item's index for source nodes (so that each source has a key and an
/// output of its own), a salt shared by the whole campaign (change it to make every key new).
#[derive(Clone, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct CityParams {
    /// Index of the recording, aerial or oblique image of a source node (0 for the others).
    pub index: u64,
    /// Campaign-wide salt.
    pub salt: u64,
}

/// SplitMix64 finaliser: a cheap, well-mixed 64-bit step.
fn mix(mut z: u64) -> u64 {
    z = z.wrapping_add(0x9E37_79B9_7F4A_7C15);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

/// Folds a stage's input values into one number, in input order (deterministic whatever the thread count).
pub trait Digest {
    /// The running digest `acc` combined with this value.
    fn fold(&self, acc: u64) -> u64;
}

impl Digest for () {
    fn fold(&self, acc: u64) -> u64 {
        mix(acc)
    }
}
impl Digest for Arc<u64> {
    fn fold(&self, acc: u64) -> u64 {
        mix(acc ^ **self)
    }
}
impl Digest for Option<Arc<u64>> {
    fn fold(&self, acc: u64) -> u64 {
        match self {
            Some(v) => v.fold(acc),
            None => mix(acc ^ 0xA5A5),
        }
    }
}
impl<T: Digest> Digest for Vec<T> {
    fn fold(&self, acc: u64) -> u64 {
        self.iter()
            .fold(mix(acc ^ self.len() as u64), |a, v| v.fold(a))
    }
}
impl<A: Digest, B: Digest> Digest for (A, B) {
    fn fold(&self, acc: u64) -> u64 {
        self.1.fold(self.0.fold(acc))
    }
}
impl<A: Digest, B: Digest, C: Digest> Digest for (A, B, C) {
    fn fold(&self, acc: u64) -> u64 {
        self.2.fold(self.1.fold(self.0.fold(acc)))
    }
}
impl<A: Digest, B: Digest, C: Digest, D: Digest> Digest for (A, B, C, D) {
    fn fold(&self, acc: u64) -> u64 {
        self.3.fold(self.2.fold(self.1.fold(self.0.fold(acc))))
    }
}

macro_rules! city_stage {
    ($(#[$doc:meta])* $ty:ident, $name:literal, $inputs:ty) => {
        $(#[$doc])*
        pub struct $ty;
        impl Stage for $ty {
            crate::stage_items!($name, "1", CityParams => u64, inputs: $inputs);
            fn run(&self, p: &CityParams, v: InputsOf<Self>, _ctx: &NodeCtx) -> RunResult<Self> {
                let seed = mix(p.salt ^ mix(p.index ^ $name.len() as u64));
                Ok(v.fold(seed))
            }
        }
    };
}

type H = Handle<u64>;

city_stage!(/// The campaign (global source node).
    CityCampaign, "city_campaign", ());
city_stage!(/// One recording's row.
    CityRecording, "city_recording", H);
city_stage!(/// One aerial nadir image's row.
    CityAerial, "city_aerial", H);
city_stage!(/// One oblique image's row.
    CityOblique, "city_oblique", H);
city_stage!(/// A recording's ground ortho image.
    CityOrtho, "city_ortho", H);
city_stage!(/// MM-to-MM matching over a window of recordings: (rows, orthos).
    CityMmMatch, "city_mm_match", (Vec<H>, Vec<H>));
city_stage!(/// A recording's ortho in an aerial image's frame: (recording, aerial).
    CityOrthoAerial, "city_ortho_aerial", (H, H));
city_stage!(/// Initial transform of a pair: (recording, ortho, aerial).
    CityTransform, "city_transform", (H, H, H));
city_stage!(/// Agreement of a pair's transform with the recording's others: (transform, all of the recording's).
    CityAgreement, "city_agreement", (H, Vec<H>));
city_stage!(/// Refinement of a pair: (ortho, aerial, agreement, window).
    CityRefine, "city_refine", (H, H, H, Optional<u64>));
city_stage!(/// Control points of a recording: (window, refinements).
    CityControl, "city_control", (Optional<u64>, Vec<Optional<u64>>));
city_stage!(/// Sparse cloud of a triplet of recordings.
    CitySparseCloud, "city_sparse_cloud", Vec<H>);
city_stage!(/// Façades of a triplet's cloud.
    CityFacades, "city_facades", H);
city_stage!(/// Patches of a triplet's façades in one oblique image: (facades, oblique).
    CityPatches, "city_patches", (H, H));
city_stage!(/// Consensus over every patch (campaign-wide).
    CityConsensus, "city_consensus", Vec<Optional<u64>>);
city_stage!(/// The adjustment: (every control, consensus).
    CityAdjust, "city_adjust", (Vec<Optional<u64>>, Optional<u64>));
city_stage!(/// Verification: (adjustment, every recording).
    CityVerify, "city_verify", (H, Vec<H>));
city_stage!(/// Summary: (windows, agreements, refinements, controls).
    CitySummary, "city_summary", (Vec<Optional<u64>>, Vec<Optional<u64>>, Vec<Optional<u64>>, Vec<Optional<u64>>));

/// The campaign-wide nodes of a city DAG.
#[derive(Clone, Copy, Debug)]
pub struct CityGraph {
    pub campaign: H,
    pub adjust: H,
    pub verify: H,
    pub summary: H,
    /// The recording nodes (the seeds of a sharded run), in trajectory order.
    pub recordings: usize,
}

/// Recordings covered by one aerial nadir image (neighbouring recordings share images).
const RECORDINGS_PER_AERIAL: usize = 4;
/// Triplets covered by one oblique image.
const TRIPLETS_PER_OBLIQUE: usize = 3;

/// Aerial images recording `r` overlaps: 2–4 consecutive ones, starting at its own.
fn aerials_of(r: usize, aerial_count: usize) -> impl Iterator<Item = usize> {
    let first = r / RECORDINGS_PER_AERIAL;
    (first..first + 2 + r % 3).map(move |a| a % aerial_count)
}

/// Builds the city DAG for `recordings` recordings (≥ 3) into `b`; every node's params carry `salt`. The
/// recordings' node ids are returned in `seeds` (trajectory order).
pub fn build_city(
    b: &mut DagBuilder,
    recordings: usize,
    salt: u64,
    seeds: &mut Vec<usize>,
) -> Result<CityGraph, BuildError> {
    let n = recordings.max(3);
    let p = |index: usize| CityParams {
        index: index as u64,
        salt,
    };
    let campaign = b.add(CityCampaign, "", p(0), ())?;
    let aerial_count = n.div_ceil(RECORDINGS_PER_AERIAL) + 3;
    let oblique_count = n.div_ceil(TRIPLETS_PER_OBLIQUE) + 2;
    let aerials: Vec<H> = (0..aerial_count)
        .map(|a| b.add(CityAerial, &format!("nadir {a:06}"), p(a), campaign))
        .collect::<Result<_, _>>()?;
    let obliques: Vec<H> = (0..oblique_count)
        .map(|o| b.add(CityOblique, &format!("oblique {o:06}"), p(o), campaign))
        .collect::<Result<_, _>>()?;
    let labels: Vec<String> = (0..n).map(|r| format!("rec {r:06}")).collect();
    let rows: Vec<H> = (0..n)
        .map(|r| b.add(CityRecording, &labels[r], p(r), campaign))
        .collect::<Result<_, _>>()?;
    seeds.extend(rows.iter().map(|h| h.id()));
    let orthos: Vec<H> = (0..n)
        .map(|r| b.add(CityOrtho, &labels[r], p(0), rows[r]))
        .collect::<Result<_, _>>()?;
    let (mut windows, mut agreements, mut refinements, mut controls, mut patches) =
        (Vec::new(), Vec::new(), Vec::new(), Vec::new(), Vec::new());
    for r in 0..n {
        let end = (r + 2 + r % 2).min(n);
        let window = if end - r >= 2 {
            let w = b.add(
                CityMmMatch,
                &labels[r],
                p(0),
                (rows[r..end].to_vec(), orthos[r..end].to_vec()),
            )?;
            windows.push(w);
            Some(w)
        } else {
            None
        };
        let mut pairs = Vec::new();
        for a in aerials_of(r, aerial_count) {
            let pair = format!("{} × nadir {a:06}", labels[r]);
            let oa = b.add(CityOrthoAerial, &pair, p(0), (rows[r], aerials[a]))?;
            let t = b.add(CityTransform, &pair, p(0), (rows[r], oa, aerials[a]))?;
            pairs.push((pair, oa, t, a));
        }
        let transforms: Vec<H> = pairs.iter().map(|x| x.2).collect();
        let mut rec_refinements = Vec::new();
        for (pair, oa, t, a) in pairs {
            let ag = b.add(CityAgreement, &pair, p(0), (t, transforms.clone()))?;
            agreements.push(ag);
            let window_in = window.unwrap_or(rows[r]).optional();
            let rf = b.add(CityRefine, &pair, p(0), (oa, aerials[a], ag, window_in))?;
            refinements.push(rf);
            rec_refinements.push(rf);
        }
        let window_in = window.unwrap_or(rows[r]).optional();
        let control = (window_in, optional_all(&rec_refinements));
        controls.push(b.add(CityControl, &labels[r], p(0), control)?);
        if r + 3 <= n {
            let cloud = b.add(CitySparseCloud, &labels[r], p(0), orthos[r..r + 3].to_vec())?;
            let facades = b.add(CityFacades, &labels[r], p(0), cloud)?;
            let first = r / TRIPLETS_PER_OBLIQUE;
            for o in (first..first + 1 + r % 3).map(|o| o % oblique_count) {
                let label = format!("{} × oblique {o:06}", labels[r]);
                patches.push(b.add(CityPatches, &label, p(0), (facades, obliques[o]))?);
            }
        }
    }
    let consensus = b.add(CityConsensus, "", p(0), optional_all(&patches))?;
    let adjust = b.add(
        CityAdjust,
        "",
        p(0),
        (optional_all(&controls), consensus.optional()),
    )?;
    let verify = b.add(CityVerify, "", p(0), (adjust, rows.clone()))?;
    let summary = b.add(
        CitySummary,
        "",
        p(0),
        (
            optional_all(&windows),
            optional_all(&agreements),
            optional_all(&refinements),
            optional_all(&controls),
        ),
    )?;
    for h in [adjust, verify, summary] {
        b.request(h);
    }
    Ok(CityGraph {
        campaign,
        adjust,
        verify,
        summary,
        recordings: n,
    })
}

/// Number of recordings whose city DAG has about `nodes` nodes (at least 3 recordings).
pub fn recordings_for_nodes(nodes: usize) -> usize {
    const PROBE: usize = 600;
    let mut b = DagBuilder::new();
    let mut seeds = Vec::new();
    // A wiring error is impossible here (fixed structure); fall back to a typical ratio if it happened.
    let per_recording = match build_city(&mut b, PROBE, 0, &mut seeds) {
        Ok(_) => b.len() as f64 / PROBE as f64,
        Err(_) => 20.0,
    };
    ((nodes as f64 / per_recording).round() as usize).max(3)
}
