//! Parameter validation of stage parameter types defined in `skytie-stages` (which does not know the engine's
//! [`StageParams`] trait): each implementation forwards to the type's own `validate`.

use crate::workflow::{ParamError, StageParams};
use skytie_stages::nadir::OrthoParams;

fn convert(errs: Vec<(String, String)>) -> Vec<ParamError> {
    errs.into_iter()
        .map(|(field, message)| ParamError::new(field, message))
        .collect()
}

impl StageParams for OrthoParams {
    fn validate(&self) -> Result<(), Vec<ParamError>> {
        OrthoParams::validate(self).map_err(convert)
    }
}
