//! The bridge between the stages' declared parameters and the engine: every parameter struct declared with
//! `skytie_stages::params!` (which does not know the engine) is a workflow table the engine can read and check,
//! its range and cross-field violations being the engine's [`ParamError`]s (one type, shared through `skytie_util`).

use crate::workflow::{ParamError, StageParams};
use serde::de::DeserializeOwned;
use serde::Serialize;
use skytie_stages::params::Params;

impl<P: Params + Serialize + DeserializeOwned> StageParams for P {
    fn validate(&self) -> Result<(), Vec<ParamError>> {
        Params::validate(self)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::nodes::campaign::aerial::SelectAerialParams;
    use crate::nodes::campaign::load::{LoadCampaignParams, SelectRecordingParams};
    use crate::nodes::campaign::summary::SummaryParams;
    use crate::nodes::campaign::synth::SynthParams;
    use crate::nodes::nadir::options::NadirOptions;
    use crate::nodes::oblique::options::ObliqueOptions;
    use skytie_stages::params::self_check::assert_declaration_sound as check;

    #[test]
    fn every_node_parameter_struct() {
        check::<SynthParams>();
        check::<LoadCampaignParams>();
        check::<SelectRecordingParams>();
        check::<SelectAerialParams>();
        check::<SummaryParams>();
        check::<NadirOptions>();
        check::<ObliqueOptions>();
    }

    #[test]
    fn violations_reach_the_engine_with_their_dotted_field() {
        let mut o = ObliqueOptions::default();
        o.consensus.threshold_m = -1.0;
        o.plane_neighbours = 11;
        let errs = StageParams::validate(&o).unwrap_err();
        let fields: Vec<&str> = errs.iter().map(|e| e.field.as_str()).collect();
        assert_eq!(fields, ["plane_neighbours", "consensus.threshold_m"]);
        assert_eq!(errs[1].message, "must be in (0, 100] m, got -1");
    }
}
