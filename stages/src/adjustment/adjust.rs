//! The adjustment driver (thesis 5.4, 5.7): solve with LM, reject observations
//! whose |normalised residual| exceeds k (per tie
//! point only the worst one per round), re-solve from the current estimate, repeat until nothing is
//! rejected (or the round limit); then posterior σ per recording.
//!
//! Normalised residual: the residual divided by its a-priori σ (σ0 = 1), per component — the angular
//! components of a panorama observation in units of its σ_θ (without the 5.7 weighting factor, so the test is
//! the same for every weighting method), the pixel residual of an aerial observation in units of its σ_px and
//! the whitened coordinate residual `L⁻¹·e` of a control point. We do
//! not divide by σ̂0 (exact synthetic data would make it 0) nor by the redundancy numbers (they would need the
//! full inverse). Priors and relative constraints are never rejected; with
//! [`AdjustOptions::relative_release_threshold`] the relative constraints that the evidence contradicts are
//! widened before the adjustment ([`super::relative_release`]).

use super::covariance::{recording_covariances, recording_covariances_with_pairs};
use super::error::AdjustError;
use super::prepared::{Prepared, Rejected};
use super::problem::{AdjustOptions, Block};
use super::relative_release::{self, release, Evidence};
use super::residuals::{pano_residual, State};
use super::solver::{solve, SolveReport, Termination};
use super::yaw_support;
use nalgebra::Vector3;

/// One adjusted recording.
#[derive(Clone, Debug, PartialEq)]
pub struct AdjustedRecording {
    /// Adjusted projection centre, world frame, metres.
    pub position_world: Vector3<f64>,
    /// Yaw correction added to the recorded yaw, degrees (0 unless estimated).
    pub yaw_correction_deg: f64,
    /// A-priori σ (σ0 = 1) of x, y, z, metres (0 for fixed coordinates).
    pub sigma_a_priori_m: Vector3<f64>,
    /// A-posteriori σ of x, y, z, metres: the a-priori σ scaled by σ̂0 when σ̂0 > 1, never below the a-priori
    /// σ ([`posterior_scale`]); `None` without redundancy.
    pub sigma_a_posteriori_m: Option<Vector3<f64>>,
    /// A-priori σ of the yaw correction, degrees (0 if not estimated).
    pub sigma_yaw_a_priori_deg: f64,
}

/// Observation counts per type.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub struct ObservationCounts {
    pub pano: usize,
    pub control: usize,
    /// Aerial image observations.
    pub aerial: usize,
    /// Prior components of the recorded positions, and observed heights of the recordings.
    pub priors: usize,
    pub relative: usize,
}

/// One solve and the rejections that followed it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RoundReport {
    pub solve: SolveReport,
    pub rejected_pano: usize,
    pub rejected_control: usize,
    pub rejected_aerial: usize,
}

/// The result of [`adjust`].
#[derive(Clone, Debug, PartialEq)]
pub struct Adjustment {
    pub recordings: Vec<AdjustedRecording>,
    /// Adjusted tie points, world frame, metres (undetermined points keep their initial value).
    pub points_world: Vec<Vector3<f64>>,
    /// Whether each tie point was determined in the final solve (≥ 2 rays or a control point).
    pub point_determined: Vec<bool>,
    pub rounds: Vec<RoundReport>,
    /// Accepted LM steps over all rounds.
    pub iterations: usize,
    /// Cost ½Σρ of the final solve.
    pub final_cost: f64,
    pub termination: Termination,
    /// σ̂0² of the final solve (`None` without redundancy).
    pub variance_factor: Option<f64>,
    pub redundancy: i64,
    /// Input observations per type.
    pub observations: ObservationCounts,
    /// Rejected observations per type (priors and relative constraints are never rejected).
    pub rejected: ObservationCounts,
    /// Indices of rejected panorama observations / control points, ascending.
    pub rejected_pano: Vec<usize>,
    pub rejected_control: Vec<usize>,
    pub rejected_aerial: Vec<usize>,
    /// Panorama observations unused in the final solve although not rejected (undetermined point, or
    /// weight 0 under weighting method 2).
    pub unused_pano: usize,
    /// Relative constraints whose σ was widened because the evidence contradicts their step
    /// ([`AdjustOptions::relative_release_threshold`]; 0 without).
    pub released_relative: usize,
    /// With relative yaw terms: each chain's common yaw correction from the tied solve and whether it kept
    /// its tie ([`yaw_support`]); empty without.
    pub yaw_chains: Vec<yaw_support::ChainYaw>,
}

/// Adjusts `block` with `options`.
pub fn adjust(block: &Block, options: &AdjustOptions) -> Result<Adjustment, AdjustError> {
    block.validate()?;
    options.validate()?;
    let mut state = State::initial(block).ok_or(AdjustError::NoRecordings)?;
    let origin = state.origin;
    let released_block;
    let mut released_relative = 0;
    let threshold = options
        .relative_release_threshold
        .filter(|_| !block.relative_constraints.is_empty());
    let block = match threshold.and_then(|t| release_contradicted(block, options, &state, t)) {
        Some((relaxed, released)) => {
            released_relative = released;
            released_block = relaxed;
            &released_block
        }
        None => block,
    };
    let initial = state.clone();
    let (mut prep, mut rejected, mut rounds) = solve_with_rejection(block, options, &mut state)?;
    let mut cov = recording_covariances(&prep, &state)?;
    let mut yaw_chains = Vec::new();
    let untied_block;
    let block = if yaw_support::applies(options) {
        let chains = yaw_support::yaw_chains(block.recordings.len(), &block.relative_constraints);
        let scale = cov.variance_factor.map_or(1.0, posterior_scale);
        yaw_chains =
            yaw_support::chain_yaws(&chains, &state.yaw_correction_rad, &cov.a_priori, scale);
        for chain in &mut yaw_chains {
            chain.tied = chain.is_significant(options.yaw_tie_significance);
        }
        let weak: Vec<&yaw_support::ChainYaw> = yaw_chains.iter().filter(|y| !y.tied).collect();
        match yaw_support::untied(&block.relative_constraints, &weak) {
            Some(relative_constraints) => {
                untied_block = Block {
                    relative_constraints,
                    ..block.clone()
                };
                state = initial;
                (prep, rejected, rounds) =
                    solve_with_rejection(&untied_block, options, &mut state)?;
                cov = recording_covariances(&prep, &state)?;
                &untied_block
            }
            None => block,
        }
    } else {
        block
    };
    let recordings = (0..block.recordings.len())
        .map(|c| {
            let m = &cov.a_priori[c];
            let sigma = Vector3::new(m[(0, 0)], m[(1, 1)], m[(2, 2)]).map(|v| v.max(0.0).sqrt());
            AdjustedRecording {
                position_world: origin.to_world(&state.centers_local[c]),
                yaw_correction_deg: state.yaw_correction_rad[c].to_degrees(),
                sigma_a_priori_m: sigma,
                sigma_a_posteriori_m: cov.variance_factor.map(|f| sigma * posterior_scale(f)),
                sigma_yaw_a_priori_deg: m[(3, 3)].max(0.0).sqrt().to_degrees(),
            }
        })
        .collect();
    let last = rounds.last().copied().expect("at least one round");
    let flagged = |v: &[bool]| -> Vec<usize> { (0..v.len()).filter(|&i| v[i]).collect() };
    let rejected_pano = flagged(&rejected.pano);
    let rejected_control = flagged(&rejected.control);
    let rejected_aerial = flagged(&rejected.aerial);
    let priors = (0..prep.recorded_local.len())
        .map(|c| {
            prep.prior_terms(c, &state)
                .iter()
                .filter(|t| t.2 > 0.0)
                .count()
        })
        .sum();
    Ok(Adjustment {
        recordings,
        points_world: state
            .points_local
            .iter()
            .map(|p| origin.to_world(p))
            .collect(),
        point_determined: prep.point_active.clone(),
        iterations: rounds.iter().map(|r| r.solve.iterations).sum(),
        final_cost: last.solve.final_cost,
        termination: last.solve.termination,
        variance_factor: cov.variance_factor,
        redundancy: cov.redundancy,
        observations: ObservationCounts {
            pano: block.pano_observations.len(),
            control: block.control_points.len(),
            aerial: block.aerial_observations.len(),
            priors,
            relative: block.relative_constraints.len(),
        },
        rejected: ObservationCounts {
            pano: rejected_pano.len(),
            control: rejected_control.len(),
            aerial: rejected_aerial.len(),
            priors: 0,
            relative: 0,
        },
        unused_pano: prep
            .pano
            .iter()
            .zip(&rejected.pano)
            .filter(|(o, &rej)| !o.active && !rej)
            .count(),
        rejected_pano,
        rejected_control,
        rejected_aerial,
        rounds,
        released_relative,
        yaw_chains,
    })
}

/// Solve with LM from `state`, reject the worst observation per tie point above the threshold, re-solve, until
/// nothing is rejected or the round limit is reached.
fn solve_with_rejection(
    block: &Block,
    options: &AdjustOptions,
    state: &mut State,
) -> Result<(Prepared, Rejected, Vec<RoundReport>), AdjustError> {
    let mut rejected = Rejected::none(block);
    let mut rounds = Vec::new();
    let max_rounds = if options.rejection_threshold.is_some() {
        options.max_rejection_rounds + 1
    } else {
        1
    };
    let mut prep;
    loop {
        prep = Prepared::new(block, options, state, &rejected)?;
        let report = solve(&prep, state, &options.lm)?;
        let mut round = RoundReport {
            solve: report,
            rejected_pano: 0,
            rejected_control: 0,
            rejected_aerial: 0,
        };
        if let Some(k) = options
            .rejection_threshold
            .filter(|_| rounds.len() + 1 < max_rounds)
        {
            // Per tie point, only its worst observation above k is rejected per round (one gross error at a
            // time, as in data snooping): a gross error also inflates the residuals of the other rays of
            // its point, which must not be rejected with it.
            let mut worst: Vec<Option<(f64, Candidate)>> = vec![None; prep.point_active.len()];
            let mut offer = |point: usize, value: f64, candidate: Candidate| {
                if value > k && worst[point].is_none_or(|(w, _)| value > w) {
                    worst[point] = Some((value, candidate));
                }
            };
            for (i, o) in prep.pano.iter().enumerate() {
                if o.active {
                    offer(
                        o.point,
                        pano_normalised(&prep, i, state),
                        Candidate::Pano(i),
                    );
                }
            }
            for (i, o) in prep.aerial.iter().enumerate() {
                if o.active {
                    let value = prep
                        .aerial_whitened(i, state)
                        .map_or(f64::INFINITY, |(r, _)| r.amax());
                    offer(o.point, value, Candidate::Aerial(i));
                }
            }
            for (i, c) in prep.control.iter().enumerate() {
                if c.active {
                    offer(
                        c.point,
                        prep.control_whitened(i, state).amax(),
                        Candidate::Control(i),
                    );
                }
            }
            for (_, candidate) in worst.into_iter().flatten() {
                match candidate {
                    Candidate::Pano(i) => {
                        rejected.pano[i] = true;
                        round.rejected_pano += 1;
                    }
                    Candidate::Control(i) => {
                        rejected.control[i] = true;
                        round.rejected_control += 1;
                    }
                    Candidate::Aerial(i) => {
                        rejected.aerial[i] = true;
                        round.rejected_aerial += 1;
                    }
                }
            }
        }
        let done = round.rejected_pano + round.rejected_control + round.rejected_aerial == 0;
        rounds.push(round);
        if done {
            break;
        }
    }
    Ok((prep, rejected, rounds))
}

/// [`super::relative_release`]: solves `block` without its relative constraints from `recorded`, and returns
/// the block with the constraints that solution contradicts widened and how many were; `None` when that solve
/// or its covariance fails (the adjustment then keeps the constraints as they are).
fn release_contradicted(
    block: &Block,
    options: &AdjustOptions,
    recorded: &State,
    threshold: f64,
) -> Option<(Block, usize)> {
    let mut free = Block {
        relative_constraints: Vec::new(),
        ..block.clone()
    };
    let mut state = recorded.clone();
    let (prep, _, _) = solve_with_rejection(&free, options, &mut state).ok()?;
    let pairs: Vec<(usize, usize)> = block
        .relative_constraints
        .iter()
        .map(|rc| (rc.from, rc.to))
        .collect();
    let (cov, cross) = recording_covariances_with_pairs(&prep, &state, &pairs).ok()?;
    let evidence = Evidence {
        state: &state,
        recorded,
        aerial: &aerial_evidence(&prep),
        covariance: &cov.a_priori,
        cross: &cross,
        variance_scale: cov.variance_factor.map_or(1.0, |f| f.max(1.0)),
    };
    let out = release(block, &evidence, threshold);
    free.relative_constraints = out.constraints;
    Some((free, out.released))
}

/// Whether each recording has aerial evidence of its own for the release
/// ([`relative_release::with_aerial_evidence`]) among the active observations of `prep`: the tie points with
/// an active control point or active aerial image observations that it observes.
fn aerial_evidence(prep: &Prepared) -> Vec<bool> {
    let mut anchored = vec![false; prep.point_active.len()];
    for c in prep.control.iter().filter(|c| c.active) {
        anchored[c.point] = true;
    }
    for o in prep.aerial.iter().filter(|o| o.active) {
        anchored[o.point] = true;
    }
    relative_release::with_aerial_evidence(
        prep.recorded_local.len(),
        prep.pano
            .iter()
            .filter(|o| o.active && anchored[o.point])
            .map(|o| (o.recording, o.point)),
    )
}

/// An observation that may be rejected.
#[derive(Clone, Copy, Debug)]
enum Candidate {
    Pano(usize),
    Control(usize),
    Aerial(usize),
}

/// Largest |component| of a panorama observation's residual in units of its σ_θ (no 5.7 factor).
fn pano_normalised(prep: &Prepared, i: usize, state: &State) -> f64 {
    let o = &prep.pano[i];
    pano_residual(
        o.observed_rad,
        &prep.rotations0[o.recording],
        state.yaw_correction_rad[o.recording],
        &state.centers_local[o.recording],
        &state.points_local[o.point],
    )
    .map_or(f64::INFINITY, |(r, _, _)| r.amax() * o.whitening)
}

/// The factor from a-priori to a-posteriori σ for the variance factor σ̂0²: `max(σ̂0, 1)`. A variance factor
/// above 1 says the observations scatter more than their a-priori σ, and the precision is scaled down with it;
/// one below 1 comes mostly from the robust loss and the rejection rounds, which leave only the residuals
/// that fit — it does not show that the recordings are better than the a-priori model, so σ is not shrunk.
pub fn posterior_scale(variance_factor: f64) -> f64 {
    variance_factor.max(1.0).sqrt()
}
