//! Every parameter struct of the stages passes [`declaration_problems`].

use crate::params::self_check::declaration_problems;
use crate::params::Params;
use serde::de::DeserializeOwned;
use serde::Serialize;
use std::fmt::Debug;

fn check<P: Params + Serialize + DeserializeOwned + PartialEq + Debug>() {
    let problems = declaration_problems::<P>();
    assert!(problems.is_empty(), "{}", problems.join("\n"));
}

#[test]
fn every_declared_stage_parameter_struct() {
    use crate::adjustment::config::AdjustConfig;
    use crate::adjustment::verify::VerifyConfig;
    use crate::estimators::mlesac::PlaneFitParams;
    use crate::estimators::one_plus_one::OnePlusOneParams;
    use crate::estimators::RansacParams;
    use crate::features::agast::AgastParams;
    use crate::features::daisy::DaisyParams;
    use crate::imaging::wallis::WallisParams;
    use crate::nadir::baseline::BaselineParams;
    use crate::nadir::control_points::ControlParams;
    use crate::nadir::initial_transform::TransformParams;
    use crate::nadir::mm_matching::MmMatchParams;
    use crate::nadir::refine::RefineParams;
    use crate::nadir::vehicle_mask::VehicleMask;
    use crate::nadir::OrthoParams;
    use crate::oblique::consensus::ConsensusParams;
    use crate::oblique::facades::FacadeParams;
    use crate::oblique::patch_registration::PatchParams;
    use crate::oblique::sparse_cloud::SparseCloudParams;

    check::<OrthoParams>();
    check::<VehicleMask>();
    check::<MmMatchParams>();
    check::<TransformParams>();
    check::<RefineParams>();
    check::<BaselineParams>();
    check::<ControlParams>();
    check::<SparseCloudParams>();
    check::<AgastParams>();
    check::<DaisyParams>();
    check::<FacadeParams>();
    check::<PatchParams>();
    check::<ConsensusParams>();
    check::<AdjustConfig>();
    check::<VerifyConfig>();
    check::<RansacParams>();
    check::<PlaneFitParams>();
    check::<OnePlusOneParams>();
    check::<WallisParams>();
}
