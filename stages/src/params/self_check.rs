//! A consistency check of a parameter struct declared with [`params!`](crate::params!), for tests: its `Default`
//! passes its own checks, round-trips through TOML, an empty table gives the default, unknown keys are rejected,
//! every field is documented, and the unit agrees with the name's suffix (`_m` ↔ `m`, `_px` ↔ `px`, `_deg` ↔
//! `deg`).

use crate::params::{describe, ParamSpec, Params};
use serde::de::DeserializeOwned;
use serde::Serialize;
use std::fmt::Debug;

/// The unit a parameter name's suffix promises (`_m` → `m`, `_px` → `px`, `_deg` → `deg`), if any.
fn unit_of_suffix(name: &str) -> Option<&'static str> {
    [("_m", "m"), ("_px", "px"), ("_deg", "deg")]
        .into_iter()
        .find(|(suffix, _)| name.ends_with(suffix))
        .map(|(_, unit)| unit)
}

/// Problems of `specs` and its sections: undocumented fields, unit and name suffix disagreeing.
fn spec_problems(type_name: &str, specs: &[ParamSpec], out: &mut Vec<String>) {
    for s in specs {
        if s.doc.trim().is_empty() {
            out.push(format!("{type_name}.{} has no doc comment", s.name));
        }
        if let Some(section) = s.section {
            spec_problems(type_name, &section(), out);
            continue;
        }
        let expected = unit_of_suffix(s.name).unwrap_or("");
        if s.unit != expected {
            out.push(format!(
                "{type_name}.{}: unit {:?}, but the name promises {expected:?}",
                s.name, s.unit
            ));
        }
    }
}

/// Every problem of `P`'s declaration (see the module documentation); empty when it is consistent.
pub fn declaration_problems<P>() -> Vec<String>
where
    P: Params + Serialize + DeserializeOwned + PartialEq + Debug,
{
    let name = std::any::type_name::<P>();
    let mut out = Vec::new();
    let p = P::default();
    if let Err(v) = p.validate() {
        out.push(format!(
            "{name}::default() violates its own checks: {}",
            describe(&v)
        ));
    }
    match toml::to_string(&p) {
        Ok(text) => match toml::from_str::<P>(&text) {
            Ok(back) if back == p => {}
            Ok(back) => out.push(format!("{name} does not round-trip through TOML: {back:?}")),
            Err(e) => out.push(format!("{name} cannot read its own TOML: {e}")),
        },
        Err(e) => out.push(format!("{name} cannot be written as TOML: {e}")),
    }
    if toml::from_str::<P>("").ok().as_ref() != Some(&p) {
        out.push(format!("{name}: an empty table does not give the default"));
    }
    if toml::from_str::<P>("no_such_parameter = 1").is_ok() {
        out.push(format!("{name} accepts an unknown key"));
    }
    spec_problems(name, &P::specs(), &mut out);
    out
}

/// Panics listing every problem of `P`'s declaration (see [`declaration_problems`]); for tests.
pub fn assert_declaration_sound<P>()
where
    P: Params + Serialize + DeserializeOwned + PartialEq + Debug,
{
    let problems = declaration_problems::<P>();
    assert!(problems.is_empty(), "{}", problems.join("\n"));
}
