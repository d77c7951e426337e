//! Feature detection: Förstner interest points (and, from the "kaze" engineer, KAZE features).

pub mod agast;
pub mod daisy;
pub mod forstner;
pub mod kaze;
