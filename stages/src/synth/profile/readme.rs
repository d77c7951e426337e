//! The text of `truth/README.md`: which error profile made the recorded tables from the true ones, with every
//! drawn number, and what was left true.

use super::{Applied, Component, Profile};

/// `truth/README.md` of campaign `campaign_name` made with `profile` and `seed` (`applied` = its result).
pub fn readme(campaign_name: &str, seed: u64, profile: &Profile, applied: &Applied) -> String {
    let n = applied.tables.recordings.len();
    let mut t = format!(
        "# Truth of the synthetic campaign `{campaign_name}` (seed {seed})\n\n\
         `truth/recordings.csv` holds the true poses of the {n} panoramas (same columns as `mm/recordings.csv`). \
         The images were rendered with the true poses. Error profile: `{}`.\n\n",
        profile.name()
    );
    if applied.notes.is_empty() {
        t.push_str("- no errors: every table holds the true values.\n");
    } else {
        t.push_str(
            "The recorded tables were made from the true values as follows (errors of several components add \
             up):\n\n",
        );
        for note in &applied.notes {
            t.push_str(&format!("- {note}\n"));
        }
    }
    let mut untouched = Vec::new();
    if !profile.has(Component::Thesis) && !profile.has(Component::Outage) {
        untouched.push("horizontal positions (x, y)");
    }
    if !profile.has(Component::Vertical) {
        untouched.push("heights (z) and camera heights");
    }
    if !profile.has(Component::Ins) {
        untouched.push("headings and yaw/pitch/roll");
    }
    if !applied.aerial_changed {
        untouched.push("all aerial poses and lens parameters (no `truth/aerial_*.csv` is written)");
    }
    if !untouched.is_empty() {
        t.push_str(&format!(
            "\nTrue (not perturbed): {}.\n",
            untouched.join("; ")
        ));
    }
    t.push_str(
        "\nCheck points in `control/checkpoints.csv` are exact; their observations in `control/observations.csv` \
         are the true projections plus N(0, 0.5 px) per axis.\n\n\
         `truth/scene.toml` names the generator, preset and seed and a fingerprint of the scene, so that an \
         evaluator can rebuild the scene and ask what a camera sees (the oblique grading uses it for the true \
         surface point of a panorama observation and for `non_matchable`).\n",
    );
    t
}
