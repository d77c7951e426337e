//! Parameter validation of stage parameter types defined in `skytie-stages` (which does not know the engine's
//! [`StageParams`] trait): each implementation forwards to the type's own `validate`.

use crate::workflow::{ParamError, StageParams};
use skytie_stages::adjustment::verify::VerifyConfig;
use skytie_stages::adjustment::AdjustConfig;
use skytie_stages::nadir::baseline::BaselineParams;
use skytie_stages::nadir::control_points::ControlParams;
use skytie_stages::nadir::initial_transform::TransformParams;
use skytie_stages::nadir::mm_matching::MmMatchParams;
use skytie_stages::nadir::refine::RefineParams;
use skytie_stages::nadir::OrthoParams;
use skytie_stages::oblique::consensus::ConsensusParams;
use skytie_stages::oblique::facades::FacadeParams;
use skytie_stages::oblique::patch_registration::PatchParams;
use skytie_stages::oblique::sparse_cloud::SparseCloudParams;

fn convert(errs: Vec<(String, String)>) -> Vec<ParamError> {
    errs.into_iter()
        .map(|(field, message)| ParamError::new(field, message))
        .collect()
}

/// `impl StageParams for T` forwarding to `T::validate(&self) -> Result<(), Vec<(String, String)>>`.
macro_rules! forward_validate {
    ($($t:ty),+ $(,)?) => {$(
        impl StageParams for $t {
            fn validate(&self) -> Result<(), Vec<ParamError>> {
                <$t>::validate(self).map_err(convert)
            }
        }
    )+};
}

/// `impl StageParams for T` for parameter structs declared with `skytie_stages::params!`.
macro_rules! declared_params {
    ($($t:ty),+ $(,)?) => {$(
        impl StageParams for $t {
            fn validate(&self) -> Result<(), Vec<ParamError>> {
                skytie_stages::params::Params::validate(self).map_err(|v| {
                    v.into_iter().map(|v| ParamError::new(v.field, v.message)).collect()
                })
            }
        }
    )+};
}

declared_params!(OrthoParams);

forward_validate!(
    MmMatchParams,
    TransformParams,
    RefineParams,
    ControlParams,
    BaselineParams,
    AdjustConfig,
    VerifyConfig,
    SparseCloudParams,
    FacadeParams,
    PatchParams,
    ConsensusParams,
);
