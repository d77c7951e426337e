//! Hand-made adjustment results for the export modules' known-answer tests.

use crate::adjustment::{
    AdjustConfig, AdjustmentRun, BlockPoint, PointKind, RunPoint, RunRecording,
};

/// A run recording at `x` east of 1000 m that the adjustment moved by `delta_m`.
pub fn recording(i: usize, x: f64, delta_m: [f64; 3]) -> RunRecording {
    let recorded = [1000.0 + x, 2000.0, 10.0];
    RunRecording {
        image_id: format!("r{i}"),
        recorded_world: recorded,
        adjusted_world: std::array::from_fn(|k| recorded[k] + delta_m[k]),
        yaw_correction_deg: 0.0,
        sigma_m: [0.1; 3],
        sigma_yaw_deg: 0.0,
        sigma_is_a_posteriori: true,
        held: Default::default(),
    }
}

/// A determined point of `kind` observed from the recordings `recs`.
pub fn point(kind: PointKind, recs: &[usize]) -> RunPoint {
    RunPoint {
        point: BlockPoint {
            id: format!("{kind:?}{recs:?}"),
            kind,
            pano: recs.iter().map(|&r| (r, 1.0, 1.0)).collect(),
            aerial: Vec::new(),
        },
        position_world: [0.0; 3],
        determined: true,
        control_rejected: false,
    }
}

/// An adjustment result with these recordings and points.
pub fn run(
    config: AdjustConfig,
    recordings: Vec<RunRecording>,
    points: Vec<RunPoint>,
) -> AdjustmentRun {
    AdjustmentRun {
        config,
        recordings,
        points,
        aerial_images: Vec::new(),
        iterations: 0,
        termination: String::new(),
        observations: Default::default(),
        rejected: Default::default(),
        rejected_total: 0,
        final_cost: 0.0,
        variance_factor: None,
        redundancy: 0,
        rejection_rounds: 0,
        build: Default::default(),
        relative_sigma: Default::default(),
        yaw_chains: Vec::new(),
    }
}
