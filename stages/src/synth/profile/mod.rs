//! Error profiles of the synthetic campaign: named, documented, combinable models of what goes wrong in real
//! data, applied to an error-free rendered campaign. `thesis` is the thesis' experiment (3.5.1.2); the others
//! model a GNSS outage, inertial orientation errors, height errors, aerial orientation errors, aerial lens
//! distortion and the differences between the aerial and the mobile-mapping epoch.
//!
//! A profile is written as component names joined by `+` (`thesis+outage+ins`); `none` is no error at all and
//! `all` every component but `lens-unknown`. Errors of combined components add up. Most components change only
//! the tables (`mm/recordings.csv`, `aerial/*/cameras.csv`): they are applied by [`apply_profile_dir`] to a
//! folder rendered once, so campaigns that differ only in such components share their images. `lens`,
//! `lens-unknown` and `epoch` also change the images ([`Profile::render_options`]).
//!
//! All randomness is hashed from (seed, component, route or item id): the same seed gives the same errors, and a
//! component's errors do not depend on which others are combined with it.

pub mod aerial_eo;
pub mod apply_dir;
pub mod epoch;
pub mod ins;
pub mod lens;
pub mod outage;
pub mod position;
pub mod readme;
pub mod routes;
pub mod vertical;

pub use aerial_eo::AerialEoParams;
pub use apply_dir::apply_profile_dir;
pub use epoch::EpochParams;
pub use ins::InsParams;
pub use lens::LensParams;
pub use outage::{Outage, OutageParams};
pub use position::ThesisParams;
pub use routes::{Draw, Routes};
pub use vertical::VerticalParams;

use super::rng::Stream;
use super::SynthError;
use crate::campaign::{AerialImage, Recording};
use crate::params::{Params, Violation};
use serde::{Deserialize, Serialize};

/// One named error component.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash, Serialize, Deserialize)]
pub enum Component {
    Thesis,
    Outage,
    Ins,
    Vertical,
    Aerial,
    Lens,
    LensUnknown,
    Epoch,
}

/// Every component with its name and a one-line description (for help texts and errors).
pub const COMPONENTS: [(Component, &str, &str); 8] = [
    (
        Component::Thesis,
        "thesis",
        "0.80 m systematic horizontal offset + N(0, 0.10 m) per axis (thesis 3.5.1.2)",
    ),
    (
        Component::Outage,
        "outage",
        "GNSS outage: error rising to 1.5-2 m and back, growing in a direction that turns with the vehicle, random walk",
    ),
    (
        Component::Ins,
        "ins",
        "heading bias 0.1-0.5 deg + random walk, pitch/roll noise (yaw/pitch/roll/heading columns)",
    ),
    (
        Component::Vertical,
        "vertical",
        "height bias 0.1-0.3 m + noise, camera-height error 2-5 cm",
    ),
    (
        Component::Aerial,
        "aerial",
        "aerial orientation errors: a few cm, a few mdeg (true poses in truth/aerial_*.csv)",
    ),
    (
        Component::Lens,
        "lens",
        "nadir frames rendered with lens distortion, coefficients given in the tables",
    ),
    (
        Component::LensUnknown,
        "lens-unknown",
        "aerial lens distortion in the images, zero coefficients in the tables",
    ),
    (
        Component::Epoch,
        "epoch",
        "aerial vs MM epoch: moved cars, changed markings, roadworks, grown trees, low sun, exposure",
    ),
];

impl Component {
    /// The component's name as written in a profile.
    pub fn name(self) -> &'static str {
        COMPONENTS
            .iter()
            .find(|(c, _, _)| *c == self)
            .map_or("?", |(_, n, _)| n)
    }

    /// Whether the component changes the rendered images (not only the tables).
    pub fn changes_images(self) -> bool {
        matches!(
            self,
            Component::Lens | Component::LensUnknown | Component::Epoch
        )
    }
}

crate::params! {
    /// The parameters of every component (the `[synth.<component>]` tables); only those of the profile's
    /// components are used.
    pub struct ComponentParams {
        /// `[synth.thesis]`: constant offset + noise.
        thesis: ThesisParams = ThesisParams::default(), section;
        /// `[synth.outage]`: GNSS outage drift.
        outage: OutageParams = OutageParams::default(), section;
        /// `[synth.ins]`: inertial heading, pitch and roll errors.
        ins: InsParams = InsParams::default(), section;
        /// `[synth.vertical]`: height and camera-height errors.
        vertical: VerticalParams = VerticalParams::default(), section;
        /// `[synth.aerial]`: aerial orientation errors.
        aerial: AerialEoParams = AerialEoParams::default(), section;
        /// `[synth.lens]`: nadir lens distortion.
        lens: LensParams = LensParams::default(), section;
        /// `[synth.epoch]`: aerial vs mobile-mapping epoch differences.
        epoch: EpochParams = EpochParams::default(), section;
    }
}

/// A combination of components with their parameters.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Profile {
    /// Sorted, without repeats.
    pub components: Vec<Component>,
    pub params: ComponentParams,
}

/// What rendering needs to know of a profile (part of the rendered images' identity).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct RenderOptions {
    /// Radial displacement at the nadir frames' corners, pixels (0 = no nadir distortion).
    pub nadir_corner_distortion_px: f64,
    /// Epoch differences, if rendered.
    pub epoch: Option<EpochParams>,
}

/// The three tables a profile changes.
#[derive(Clone, Debug, PartialEq)]
pub struct Tables {
    pub recordings: Vec<Recording>,
    pub nadir: Vec<AerialImage>,
    pub oblique: Vec<AerialImage>,
}

/// The tables with a profile's errors and the README lines saying how they were made.
#[derive(Clone, Debug, PartialEq)]
pub struct Applied {
    pub tables: Tables,
    pub notes: Vec<String>,
    /// Whether the aerial tables differ from the true ones (then `truth/aerial_*.csv` are written).
    pub aerial_changed: bool,
}

impl Profile {
    /// The profile of these components with default parameters.
    pub fn of(components: &[Component]) -> Self {
        let mut c = components.to_vec();
        c.sort();
        c.dedup();
        Self {
            components: c,
            params: ComponentParams::default(),
        }
    }

    /// No errors at all.
    pub fn none() -> Self {
        Self::of(&[])
    }

    /// The thesis' deterioration (3.5.1.2).
    pub fn thesis() -> Self {
        Self::of(&[Component::Thesis])
    }

    /// Parse `name+name…` (`,` also separates; `none`, `all`), with default parameters.
    pub fn parse(spec: &str) -> Result<Self, SynthError> {
        let bad = |message: String| SynthError::InvalidOption {
            option: "profile".into(),
            message,
        };
        let mut components = Vec::new();
        for word in spec.split(['+', ',']).map(str::trim) {
            match word.to_ascii_lowercase().as_str() {
                "none" => {}
                "all" => components.extend(
                    COMPONENTS
                        .iter()
                        .map(|(c, _, _)| *c)
                        .filter(|c| *c != Component::LensUnknown),
                ),
                w => match COMPONENTS.iter().find(|(_, n, _)| *n == w) {
                    Some((c, _, _)) => components.push(*c),
                    None => {
                        return Err(bad(format!(
                            "unknown component '{word}' in '{spec}'; components: none, all, {} (join them \
                             with '+')",
                            COMPONENTS
                                .iter()
                                .map(|(_, n, _)| *n)
                                .collect::<Vec<_>>()
                                .join(", ")
                        )))
                    }
                },
            }
        }
        let p = Self::of(&components);
        if p.has(Component::Lens) && p.has(Component::LensUnknown) {
            return Err(bad(format!(
                "'{spec}' names both lens and lens-unknown; the tables either give the distortion or not"
            )));
        }
        Ok(p)
    }

    /// The canonical name: the components in their fixed order joined by `+`, or `none`.
    pub fn name(&self) -> String {
        if self.components.is_empty() {
            return "none".into();
        }
        self.components
            .iter()
            .map(|c| c.name())
            .collect::<Vec<_>>()
            .join("+")
    }

    /// Whether the profile has component `c`.
    pub fn has(&self, c: Component) -> bool {
        self.components.contains(&c)
    }

    /// Every invalid parameter (dotted field and problem); empty = valid.
    pub fn problems(&self) -> Vec<Violation> {
        self.params.violations()
    }

    /// A profile whose images are rendered as `r` says (only image-changing components; its tables are left
    /// true).
    pub fn rendering(r: &RenderOptions) -> Self {
        let mut p = Self::none();
        if r.nadir_corner_distortion_px > 0.0 {
            p.components.push(Component::Lens);
            p.params.lens.nadir_corner_px = r.nadir_corner_distortion_px;
        }
        if let Some(e) = &r.epoch {
            p.components.push(Component::Epoch);
            p.params.epoch = e.clone();
        }
        p
    }

    /// What the rendering of this profile's images needs.
    pub fn render_options(&self) -> RenderOptions {
        let lens = self.has(Component::Lens) || self.has(Component::LensUnknown);
        RenderOptions {
            nadir_corner_distortion_px: if lens {
                self.params.lens.nadir_corner_px
            } else {
                0.0
            },
            epoch: self
                .has(Component::Epoch)
                .then(|| self.params.epoch.clone()),
        }
    }

    /// The recorded tables made from the true ones (`truth`) for `seed`.
    pub fn apply(&self, seed: u64, truth: &Tables) -> Applied {
        let routes = Routes::of(&truth.recordings);
        let mut out = truth.clone();
        let mut notes = Vec::new();
        let p = &self.params;
        let on = Draw {
            seed,
            truth,
            routes: &routes,
        };
        for c in &self.components {
            notes.extend(match c {
                Component::Thesis => p.thesis.apply(seed, truth, &mut out),
                Component::Outage => p.outage.apply(&on, &mut out),
                Component::Ins => p.ins.apply(&on, &mut out),
                Component::Vertical => p.vertical.apply(&on, &mut out),
                Component::Aerial => p.aerial.apply(seed, truth, &mut out),
                Component::Lens => p.lens.given_note(),
                Component::LensUnknown => p.lens.hide(&mut out),
                Component::Epoch => p.epoch.note(),
            });
        }
        let aerial_changed = out.nadir != truth.nadir || out.oblique != truth.oblique;
        Applied {
            tables: out,
            notes,
            aerial_changed,
        }
    }
}

/// Push a violation unless the range `[low, high]` has low ≤ high (the bounds themselves are checked by the
/// declaration).
pub(crate) fn check_ordered(field: &str, r: [f64; 2], out: &mut Vec<Violation>) {
    if r[0] > r[1] {
        out.push(Violation::new(
            field,
            format!(
                "must be a range [low, high] with low ≤ high, got [{}, {}]",
                r[0], r[1]
            ),
        ));
    }
}

/// A size drawn uniformly from `range`, with a random sign.
pub(crate) fn signed_draw(s: &mut Stream, range: [f64; 2]) -> f64 {
    let size = s.range(range[0], range[1]);
    if s.uniform() < 0.5 {
        -size
    } else {
        size
    }
}

#[cfg(test)]
mod tests;
