//! A parameter value outside its allowed range, as the photogrammetry crate's parameter checks
//! (`skytie_stages::params::Violation`) and the engine's workflow validation (`skytie::workflow::ParamError`)
//! both report it.

use std::fmt;

/// A parameter value outside its allowed range: the dotted field path (`"threshold"`, `"patch.extent_m"`) and a
/// message stating the range (`"must be in (0, 1]"`).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Violation {
    pub field: String,
    pub message: String,
}

impl Violation {
    pub fn new(field: impl Into<String>, message: impl Into<String>) -> Violation {
        Violation {
            field: field.into(),
            message: message.into(),
        }
    }
}

/// `field: message`, e.g. `min_peak: must be in [0, 1), got 1.5`.
impl fmt::Display for Violation {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}: {}", self.field, self.message)
    }
}
