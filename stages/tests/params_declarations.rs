//! Every parameter struct of the stages passes `declaration_problems`.

use skytie_stages::params::self_check::assert_declaration_sound as check;

#[test]
fn every_declared_stage_parameter_struct() {
    use skytie_stages::adjustment::config::AdjustConfig;
    use skytie_stages::adjustment::verify::VerifyConfig;
    use skytie_stages::estimators::mlesac::PlaneFitParams;
    use skytie_stages::estimators::one_plus_one::OnePlusOneParams;
    use skytie_stages::estimators::RansacParams;
    use skytie_stages::features::agast::AgastParams;
    use skytie_stages::features::daisy::DaisyParams;
    use skytie_stages::imaging::wallis::WallisParams;
    use skytie_stages::nadir::baseline::BaselineParams;
    use skytie_stages::nadir::control_points::ControlParams;
    use skytie_stages::nadir::initial_transform::TransformParams;
    use skytie_stages::nadir::mm_matching::MmMatchParams;
    use skytie_stages::nadir::refine::RefineParams;
    use skytie_stages::nadir::vehicle_detect::VehicleDetectParams;
    use skytie_stages::nadir::vehicle_mask::VehicleMask;
    use skytie_stages::nadir::OrthoParams;
    use skytie_stages::oblique::consensus::ConsensusParams;
    use skytie_stages::oblique::facades::FacadeParams;
    use skytie_stages::oblique::patch_registration::PatchParams;
    use skytie_stages::oblique::sparse_cloud::SparseCloudParams;
    use skytie_stages::synth::profile::ComponentParams;

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
    check::<VehicleDetectParams>();
    check::<ComponentParams>();
}
