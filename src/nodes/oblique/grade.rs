//! `grade_oblique`: evaluation only — grades the oblique pipeline's correspondences (before and after the
//! consensus, per street side) and its control points against a synthetic campaign's `truth/`
//! (`skytie_stages::oblique::grading`; the rule is stated there and in the README). Added by the pipeline only
//! when `truth/recordings.csv` exists; no processing stage reads `truth/`.

use crate::dag::{Handle, InputsOf, NodeCtx, RawFile, RunResult, Stage, StageError};
use crate::nodes::campaign::load::CampaignSnapshot;
use crate::nodes::campaign::summary::SummaryParams;
use crate::nodes::nadir::grade::load_truth;
use crate::nodes::oblique::consensus::ObliqueOutput;
use skytie_stages::oblique::grading::{grade_oblique, ObliqueGrade};
use skytie_stages::oblique::SparseCloud;
use skytie_stages::synth::scene_truth::SceneTruth;

crate::serde_artifact!(ObliqueGrade);

pub use crate::nodes::nadir::grade::TRUTH_RECORDINGS;
/// True oblique poses, when the campaign perturbed them (optional).
pub const TRUTH_AERIAL_OBLIQUE: &str = "truth/aerial_oblique.csv";

pub use skytie_stages::synth::scene_truth::SCENE_TRUTH_FILE;

/// The oblique grading node. Inputs: snapshot, truth files (`truth/recordings.csv` first, then optionally
/// `truth/aerial_oblique.csv`), `truth/scene.toml` when the campaign has one (zero or one file: the scene for
/// surface points and visibility), the panorama files in snapshot order (for their size), the sparse clouds
/// (for the tie points' true object points) and the consensus output.
pub struct GradeOblique;

impl GradeOblique {
    /// `oblique` metrics of a grade (merged with the consensus node's own `oblique` counts).
    pub fn metrics(g: &ObliqueGrade) -> serde_json::Value {
        g.metrics()
    }
}

impl Stage for GradeOblique {
    crate::nodes::stage_types!(skytie_stages::oblique::grading::STAGE, SummaryParams => ObliqueGrade,
        inputs: (Handle<CampaignSnapshot>, Vec<RawFile>, Vec<RawFile>, Vec<RawFile>, Vec<Handle<SparseCloud>>, Handle<ObliqueOutput>));

    fn run(&self, _: &SummaryParams, inputs: InputsOf<Self>, _: &NodeCtx) -> RunResult<Self> {
        let (snap, truth_files, scene_files, panos, clouds, result) = inputs;
        let truth = load_truth(
            &snap,
            &truth_files,
            &panos,
            &snap.campaign.oblique,
            "grade_oblique",
        )?;
        let scene = match scene_files.first() {
            Some(f) => {
                let text = std::fs::read_to_string(&f.path)
                    .map_err(|e| StageError::new(format!("{}: {e}", f.path.display())))?;
                let oracle = SceneTruth::parse(&text)
                    .and_then(|t| t.rebuild())
                    .map_err(|e| StageError::new(format!("{}: {e}", f.path.display())))?;
                Some(oracle)
            }
            None => None,
        };
        let clouds: Vec<SparseCloud> = clouds.iter().map(|c| (**c).clone()).collect();
        Ok(grade_oblique(
            &truth,
            scene.as_ref(),
            &clouds,
            &result.result,
        ))
    }
}
