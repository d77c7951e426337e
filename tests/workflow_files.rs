//! Workflow files end to end: loading, includes, sweeps, typed stage parameters, and the file:line:column of
//! every kind of error (known-answer tests: each input is written here with the position it must report).

use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};
use skytie::workflow::{CampaignSource, ParamError, StageParams, Workflow, WorkflowError};

// ---------------------------------------------------------------------------------------------------------------
// A stage parameter struct as stages define them.

#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
struct Patch {
    extent_m: f64,
    bins: u32,
}

impl Default for Patch {
    fn default() -> Self {
        Patch {
            extent_m: 10.0,
            bins: 16,
        }
    }
}

#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
enum Detector {
    Kaze,
    Harris,
}

#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
struct ObliqueParams {
    threshold: f64,
    detector: Detector,
    seed: u64,
    patch: Patch,
}

impl Default for ObliqueParams {
    fn default() -> Self {
        ObliqueParams {
            threshold: 0.5,
            detector: Detector::Kaze,
            seed: 0,
            patch: Patch::default(),
        }
    }
}

impl StageParams for ObliqueParams {
    fn validate(&self) -> Result<(), Vec<ParamError>> {
        let mut problems = Vec::new();
        if !(self.threshold > 0.0 && self.threshold <= 1.0) {
            problems.push(ParamError::new("threshold", "must be in (0, 1]"));
        }
        if self.patch.extent_m <= 0.0 {
            problems.push(ParamError::new("patch.extent_m", "must be > 0"));
        }
        if problems.is_empty() {
            Ok(())
        } else {
            Err(problems)
        }
    }
}

#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
struct OrthoParams {
    gsd_m: f64,
}

impl Default for OrthoParams {
    fn default() -> Self {
        OrthoParams { gsd_m: 0.03 }
    }
}

impl StageParams for OrthoParams {
    fn validate(&self) -> Result<(), Vec<ParamError>> {
        if self.gsd_m > 0.0 {
            Ok(())
        } else {
            Err(vec![ParamError::new("gsd_m", "must be > 0")])
        }
    }
}

// ---------------------------------------------------------------------------------------------------------------
// Helpers.

/// The base workflow used by most tests; the line numbers in the comments are what errors must report.
const BASE: &str = r#"name = "base"
campaign = "synth:demo"
seed = 7
stages = ["ortho", "oblique"]

[ortho]
gsd_m = 0.05

[oblique]
threshold = 0.8

[oblique.patch]
extent_m = 12.0
"#;

struct Dir {
    dir: tempfile::TempDir,
}

impl Dir {
    fn new() -> Self {
        Dir {
            dir: tempfile::tempdir().expect("temp dir"),
        }
    }
    fn write(&self, name: &str, text: &str) -> PathBuf {
        let path = self.dir.path().join(name);
        std::fs::write(&path, text).expect("write workflow");
        path
    }
}

fn parse(text: &str) -> Result<Workflow, WorkflowError> {
    Workflow::parse(text, Path::new("workflows/x.toml"))
}

/// Asserts an error's position and that its message contains `needle`; returns the Display text.
fn assert_error(e: &WorkflowError, line: usize, column: usize, needle: &str) -> String {
    let shown = e.to_string();
    assert_eq!(
        (e.line, e.column),
        (line, column),
        "wrong position in: {shown}"
    );
    assert!(
        e.message.contains(needle),
        "expected {needle:?} in: {shown}"
    );
    shown
}

// ---------------------------------------------------------------------------------------------------------------
// Loading and basic fields.

#[test]
fn loads_fields_and_stage_params() {
    let w = parse(BASE).unwrap();
    assert_eq!(w.name, "base");
    assert_eq!(w.pipeline, "skytie");
    assert_eq!(w.seed, 7);
    assert_eq!(w.stages, vec!["ortho", "oblique"]);
    assert_eq!(
        w.campaign,
        CampaignSource::Synth {
            preset: "demo".into(),
            seed: 7
        }
    );
    assert_eq!(w.variants(), vec!["default"]);
    assert!(!w.is_sweep());
    let ortho: OrthoParams = w.params("ortho", "default").unwrap();
    assert_eq!(ortho.gsd_m, 0.05);
    let oblique: ObliqueParams = w.params("oblique", "default").unwrap();
    assert_eq!(
        oblique,
        ObliqueParams {
            threshold: 0.8,
            detector: Detector::Kaze,
            seed: 7, // not set by the stage: the workflow seed
            patch: Patch {
                extent_m: 12.0,
                bins: 16
            },
        }
    );
}

#[test]
fn name_defaults_to_file_stem_and_pipeline_is_read() {
    let text = "campaign = \"synth:tiny\"\npipeline = \"toy\"\nstages = [\"a\"]\n";
    let w = Workflow::parse(text, Path::new("workflows/my_run.toml")).unwrap();
    assert_eq!(w.name, "my_run");
    assert_eq!(w.pipeline, "toy");
    assert_eq!(w.seed, 0);
    // A stage without table gets its defaults.
    let p: OrthoParams = w.params("a", "default").unwrap();
    assert_eq!(p, OrthoParams::default());
}

#[test]
fn campaign_sources() {
    let dir = Dir::new();
    let demo = dir.write(
        "demo.toml",
        "campaign = \"synth:demo\"\nseed = 3\nstages = [\"a\"]\n",
    );
    let w = Workflow::load(&demo).unwrap();
    assert_eq!(
        w.campaign,
        CampaignSource::Synth {
            preset: "demo".into(),
            seed: 3
        }
    );

    let paper = dir.write(
        "paper.toml",
        "campaign = \"synth:paper\"\nstages = [\"a\"]\n",
    );
    let w = Workflow::load(&paper).unwrap();
    assert_eq!(
        w.campaign,
        CampaignSource::Synth {
            preset: "paper".into(),
            seed: 0
        }
    );

    let real = dir.write(
        "real.toml",
        "campaign = \"../data/rotterdam\"\nstages = [\"a\"]\n",
    );
    let mut w = Workflow::load(&real).unwrap();
    assert_eq!(
        w.campaign,
        CampaignSource::Path(dir.dir.path().join("../data/rotterdam"))
    );
    w.override_campaign(PathBuf::from("elsewhere/c1"));
    assert_eq!(
        w.campaign,
        CampaignSource::Path(PathBuf::from("elsewhere/c1"))
    );

    let e = parse("campaign = \"synth:dmeo\"\nstages = [\"a\"]\n").unwrap_err();
    assert_error(&e, 1, 12, "did you mean 'demo'?");
}

#[test]
fn file_hash_follows_file_bytes() {
    let dir = Dir::new();
    let path = dir.write("w.toml", BASE);
    let first = Workflow::load(&path).unwrap();
    assert_eq!(first.file_hash, *blake3::hash(BASE.as_bytes()).as_bytes());
    assert_eq!(Workflow::load(&path).unwrap().file_hash, first.file_hash);
    dir.write("w.toml", &BASE.replace("gsd_m = 0.05", "gsd_m = 0.06"));
    assert_ne!(Workflow::load(&path).unwrap().file_hash, first.file_hash);

    // With includes, editing the included file changes the hash too.
    dir.write("base.toml", BASE);
    let sweep = dir.write("s.toml", "include = [\"base.toml\"]\n");
    let h1 = Workflow::load(&sweep).unwrap().file_hash;
    dir.write("base.toml", &BASE.replace("seed = 7", "seed = 8"));
    let h2 = Workflow::load(&sweep).unwrap().file_hash;
    assert_ne!(h1, h2);
}

// ---------------------------------------------------------------------------------------------------------------
// Error positions.

#[test]
fn toml_syntax_error_position() {
    let text = "campaign = \"synth:demo\"\nstages = [\"a\"]\nseed = = 3\n";
    let e = parse(text).unwrap_err();
    let shown = assert_error(&e, 3, 8, "TOML syntax error");
    assert!(shown.starts_with("workflows/x.toml:3:8: "), "{shown}");
}

#[test]
fn unknown_key_in_nested_stage_table_with_suggestion() {
    let w = parse(&BASE.replace("extent_m = 12.0", "extnt_m = 12.0")).unwrap();
    let e = w.params::<ObliqueParams>("oblique", "default").unwrap_err();
    let shown = assert_error(
        &e,
        13,
        1,
        "unknown key 'extnt_m' in [oblique.patch]; did you mean 'extent_m'?",
    );
    assert_eq!(
        shown,
        "workflows/x.toml:13:1: unknown key 'extnt_m' in [oblique.patch]; did you mean 'extent_m'?"
    );
}

#[test]
fn unknown_key_without_close_match_lists_valid_keys() {
    let w = parse(&BASE.replace("gsd_m = 0.05", "colour = 3")).unwrap();
    let e = w.params::<OrthoParams>("ortho", "default").unwrap_err();
    assert_error(
        &e,
        7,
        1,
        "unknown key 'colour' in [ortho] (valid keys: gsd_m)",
    );
}

#[test]
fn wrong_type_points_at_the_value() {
    let w = parse(&BASE.replace("threshold = 0.8", "threshold = \"high\"")).unwrap();
    let e = w.params::<ObliqueParams>("oblique", "default").unwrap_err();
    assert_error(
        &e,
        10,
        13,
        "[oblique] threshold: wrong type: expected f64, found string \"high\"",
    );

    let w = parse(&BASE.replace("extent_m = 12.0", "bins = -4")).unwrap();
    let e = w.params::<ObliqueParams>("oblique", "default").unwrap_err();
    assert_error(&e, 13, 8, "[oblique.patch] bins: invalid value");

    let w = parse(&BASE.replace("[oblique.patch]\nextent_m = 12.0", "patch = 3")).unwrap();
    let e = w.params::<ObliqueParams>("oblique", "default").unwrap_err();
    assert_error(&e, 12, 9, "[oblique] patch: wrong type");
}

#[test]
fn integers_are_accepted_for_floats() {
    let w = parse(&BASE.replace("gsd_m = 0.05", "gsd_m = 1")).unwrap();
    assert_eq!(
        w.params::<OrthoParams>("ortho", "default").unwrap().gsd_m,
        1.0
    );
}

#[test]
fn unknown_enum_value_with_suggestion() {
    let w = parse(&BASE.replace("threshold = 0.8", "detector = \"kaz\"")).unwrap();
    let e = w.params::<ObliqueParams>("oblique", "default").unwrap_err();
    assert_error(
        &e,
        10,
        12,
        "[oblique] detector: unknown value 'kaz' (allowed: kaze, harris); did you mean 'kaze'?",
    );
    let w = parse(&BASE.replace("threshold = 0.8", "detector = \"harris\"")).unwrap();
    assert_eq!(
        w.params::<ObliqueParams>("oblique", "default")
            .unwrap()
            .detector,
        Detector::Harris
    );
}

#[test]
fn out_of_range_value() {
    let w = parse(&BASE.replace("threshold = 0.8", "threshold = -1")).unwrap();
    let e = w.params::<ObliqueParams>("oblique", "default").unwrap_err();
    let shown = assert_error(&e, 10, 13, "[oblique] threshold = -1: must be in (0, 1]");
    assert_eq!(
        shown,
        "workflows/x.toml:10:13: [oblique] threshold = -1: must be in (0, 1]"
    );

    // Two problems at once: both reported, each with its own position.
    let text = BASE
        .replace("threshold = 0.8", "threshold = 2.0")
        .replace("extent_m = 12.0", "extent_m = -3.0");
    let e = parse(&text)
        .unwrap()
        .params::<ObliqueParams>("oblique", "default")
        .unwrap_err();
    assert_error(&e, 10, 13, "[oblique] threshold = 2.0: must be in (0, 1]");
    assert!(
        e.message
            .contains("\nworkflows/x.toml:13:12: [oblique.patch] extent_m = -3.0: must be > 0"),
        "{e}"
    );
}

#[test]
fn unknown_stage_table_and_unknown_top_level_key() {
    let e = parse(&format!("{BASE}\n[orthp]\ngsd_m = 1\n")).unwrap_err();
    assert_error(&e, 15, 2, "unknown stage 'orthp'");
    assert!(e.message.ends_with("did you mean 'ortho'?"), "{e}");

    let e = parse(&BASE.replace("seed = 7", "sed = 7")).unwrap_err();
    assert_error(
        &e,
        3,
        1,
        "unknown key 'sed' at the top level; did you mean 'seed'?",
    );

    let e = parse(&BASE.replace("campaign =", "campain =")).unwrap_err();
    assert_error(
        &e,
        2,
        1,
        "unknown key 'campain' at the top level; did you mean 'campaign'?",
    );
    assert!(
        e.message.contains("missing key 'campaign'"),
        "both problems are reported: {e}"
    );
}

#[test]
fn unknown_stage_for_a_pipeline() {
    let w = parse(
        &BASE
            .replace("[\"ortho\", \"oblique\"]", "[\"ortho\", \"obliqe\"]")
            .replace("[oblique", "[obliqe"),
    )
    .unwrap();
    let e = w
        .check_stage_names(&["ortho", "oblique", "adjust"])
        .unwrap_err();
    assert_error(&e, 4, 20, "unknown stage 'obliqe' for pipeline 'skytie'");
    assert!(e.message.ends_with("did you mean 'oblique'?"), "{e}");
    assert!(parse(BASE)
        .unwrap()
        .check_stage_names(&["ortho", "oblique"])
        .is_ok());
}

#[test]
fn duplicate_stage_and_stage_that_is_not_a_table() {
    let e = parse(&BASE.replace(
        "[\"ortho\", \"oblique\"]",
        "[\"ortho\", \"oblique\", \"ortho\"]",
    ))
    .unwrap_err();
    assert_error(&e, 4, 31, "stage 'ortho' is listed twice (first at line 4)");
    let e = parse("campaign = \"synth:demo\"\nstages = [\"ortho\"]\northo = 3\n").unwrap_err();
    assert_error(
        &e,
        3,
        9,
        "'ortho' is a stage: its parameters go in a table [ortho]",
    );
}

#[test]
fn dates_are_rejected_with_position() {
    let e = parse(&BASE.replace("gsd_m = 0.05", "gsd_m = 2020-01-01")).unwrap_err();
    assert_error(&e, 7, 9, "date/time values are not used in workflows");
}

// ---------------------------------------------------------------------------------------------------------------
// Sweeps.

/// BASE followed by SWEEP with `from` replaced by `to`.
fn sweep_with(from: &str, to: &str) -> String {
    format!("{BASE}{}", SWEEP.replace(from, to))
}

const SWEEP: &str = r#"
[sweep]
base = "base"

[[sweep.variant]]
name = "bins32"
"oblique.patch.bins" = 32

[[sweep.variant]]
name = "tight"
description = "lower threshold, larger patches"
"oblique.patch.extent_m" = 20.0
[sweep.variant.oblique]
threshold = 0.3
seed = 99
"#;

#[test]
fn variants_merge_over_stage_tables() {
    let w = parse(&format!("{BASE}{SWEEP}")).unwrap();
    assert!(w.is_sweep());
    assert_eq!(w.variants(), vec!["bins32", "tight"]);
    assert_eq!(w.sweep_base(), Some("base"));
    assert_eq!(
        w.variant_description("tight"),
        Some("lower threshold, larger patches")
    );

    // Override wins; untouched parameters keep the stage table's value; nested tables merge key by key.
    let a: ObliqueParams = w.params("oblique", "bins32").unwrap();
    assert_eq!(a.threshold, 0.8);
    assert_eq!(
        a.patch,
        Patch {
            extent_m: 12.0,
            bins: 32
        }
    );
    assert_eq!(a.seed, 7);
    let b: ObliqueParams = w.params("oblique", "tight").unwrap();
    assert_eq!(b.threshold, 0.3);
    assert_eq!(
        b.patch,
        Patch {
            extent_m: 20.0,
            bins: 16
        }
    ); // bins: struct default
    assert_eq!(b.seed, 99); // the variant sets the stage's own seed
                            // A stage the variants do not touch is the same in every variant.
    for v in w.variants() {
        assert_eq!(w.params::<OrthoParams>("ortho", &v).unwrap().gsd_m, 0.05);
    }
    assert_eq!(
        w.variant_overrides("tight").unwrap(),
        vec![
            ("oblique.patch.extent_m".to_string(), "20.0".to_string()),
            ("oblique.threshold".to_string(), "0.3".to_string()),
            ("oblique.seed".to_string(), "99".to_string()),
        ]
    );
    let table = w.stage_table("oblique", "tight").unwrap();
    assert_eq!(table["threshold"].as_float(), Some(0.3));
    assert_eq!(table["patch"]["extent_m"].as_float(), Some(20.0));

    // "default" is the workflow without overrides, also in a sweep.
    let base: ObliqueParams = w.params("oblique", "default").unwrap();
    assert_eq!((base.threshold, base.patch.bins, base.seed), (0.8, 16, 7));

    let e = w.params::<ObliqueParams>("oblique", "tigth").unwrap_err();
    assert_error(
        &e,
        15,
        2,
        "unknown variant 'tigth' (variants: bins32, tight); did you mean 'tight'?",
    );
}

#[test]
fn errors_in_variant_overrides_point_at_the_override() {
    // BASE has 13 lines; SWEEP starts on line 14 with an empty line, so `"oblique.patch.bins" = 32` is line 20.
    let w = parse(&sweep_with(
        "\"oblique.patch.bins\" = 32",
        "\"oblique.patch.bns\" = 32",
    ))
    .unwrap();
    let e = w.params::<ObliqueParams>("oblique", "bins32").unwrap_err();
    assert_error(
        &e,
        20,
        1,
        "unknown key 'bns' in [oblique.patch]; did you mean 'bins'? (set by variant 'bins32')",
    );
    // The other variant is fine.
    assert!(w.params::<ObliqueParams>("oblique", "tight").is_ok());

    let w = parse(&sweep_with("threshold = 0.3", "threshold = 1.3")).unwrap();
    let e = w.params::<ObliqueParams>("oblique", "tight").unwrap_err();
    assert_error(
        &e,
        27,
        13,
        "[oblique] threshold = 1.3: must be in (0, 1] (set by variant 'tight')",
    );
}

#[test]
fn structural_errors_in_sweeps_point_at_the_line() {
    // (replace in SWEEP, by, line, column, message)
    let cases = [
        (
            "\"oblique.patch.bins\"",
            "\"obliqeu.patch.bins\"",
            20,
            1,
            "unknown stage 'obliqeu' in override of variant 'bins32'",
        ),
        // The table form reports at the stage key of the table header.
        (
            "[sweep.variant.oblique]",
            "[sweep.variant.oblque]",
            26,
            16,
            "unknown stage 'oblque' in override of variant 'tight'",
        ),
        // An override must name a parameter, and cannot go through a scalar.
        (
            "\"oblique.patch.bins\" = 32",
            "ortho = 32",
            20,
            1,
            "override 'ortho' in variant 'bins32' must name a parameter",
        ),
        (
            "\"oblique.patch.bins\" = 32",
            "\"oblique.threshold.x\" = 32",
            20,
            1,
            "goes through 'threshold', which is a float in [oblique], not a table",
        ),
        (
            "name = \"tight\"",
            "name = \"bins32\"",
            23,
            8,
            "duplicate variant name 'bins32' (first declared at line 19)",
        ),
    ];
    for (from, to, line, column, message) in cases {
        let e = parse(&sweep_with(from, to)).unwrap_err();
        assert_error(&e, line, column, message);
    }
    let e = parse(&sweep_with(cases[0].0, cases[0].1)).unwrap_err();
    assert!(e.message.ends_with("did you mean 'oblique'?"), "{e}");
}

#[test]
fn variant_without_name_and_unknown_sweep_key() {
    let text = format!(
        "{BASE}{}",
        SWEEP
            .replace("name = \"tight\"\n", "")
            .replace("base = ", "bsae = ")
    );
    let e = parse(&text).unwrap_err();
    assert_error(
        &e,
        16,
        1,
        "unknown key 'bsae' in [sweep]; did you mean 'base'?",
    );
    assert!(
        e.message.contains(":22:1: sweep variant #2 has no name"),
        "{e}"
    );
}

// ---------------------------------------------------------------------------------------------------------------
// Includes.

#[test]
fn include_builds_on_a_base_workflow() {
    let dir = Dir::new();
    dir.write("base.toml", BASE);
    let sweep = dir.write(
        "oblique_sweep.toml",
        "include = [\"base.toml\"]\n\n[oblique]\nthreshold = 0.6\n\n[[sweep.variant]]\nname = \"v1\"\northo.gsd_m = 0.1\n",
    );
    let w = Workflow::load(&sweep).unwrap();
    assert_eq!(
        w.name, "oblique_sweep",
        "the name is not inherited from the included file"
    );
    assert_eq!(w.stages, vec!["ortho", "oblique"]);
    assert_eq!(
        w.sources,
        vec![sweep.clone(), dir.dir.path().join("base.toml")]
    );
    let o: ObliqueParams = w.params("oblique", "v1").unwrap();
    assert_eq!((o.threshold, o.patch.extent_m), (0.6, 12.0));
    assert_eq!(w.params::<OrthoParams>("ortho", "v1").unwrap().gsd_m, 0.1);

    // Variants accumulate across includes.
    let more = dir.write("more.toml", "include = \"oblique_sweep.toml\"\n[[sweep.variant]]\nname = \"v2\"\n\"oblique.threshold\" = 0.2\n");
    let w = Workflow::load(&more).unwrap();
    assert_eq!(w.variants(), vec!["v1", "v2"]);
    assert_eq!(
        w.params::<ObliqueParams>("oblique", "v2")
            .unwrap()
            .threshold,
        0.2
    );
    assert_eq!(
        w.params::<ObliqueParams>("oblique", "v1")
            .unwrap()
            .threshold,
        0.6
    );
}

#[test]
fn diamond_includes_merge_the_shared_file_once() {
    let dir = Dir::new();
    dir.write("base.toml", &format!("{BASE}{SWEEP}"));
    dir.write(
        "left.toml",
        "include = \"base.toml\"\n[ortho]\ngsd_m = 0.07\n",
    );
    dir.write(
        "right.toml",
        "include = \"base.toml\"\n[oblique]\nthreshold = 0.9\n",
    );
    let top = dir.write("top.toml", "include = [\"left.toml\", \"right.toml\"]\n");
    let w = Workflow::load(&top).unwrap();
    assert_eq!(
        w.variants(),
        vec!["bins32", "tight"],
        "variants of the shared file are not duplicated"
    );
    assert_eq!(w.sources.len(), 4);
    assert_eq!(
        w.params::<OrthoParams>("ortho", "default").unwrap().gsd_m,
        0.07
    );
    assert_eq!(
        w.params::<ObliqueParams>("oblique", "bins32")
            .unwrap()
            .threshold,
        0.9
    );
}

#[test]
fn errors_in_included_files_carry_their_path() {
    let dir = Dir::new();
    let base = dir.write(
        "base.toml",
        &BASE.replace("extent_m = 12.0", "extent = 12.0"),
    );
    let sweep = dir.write("s.toml", "include = [\"base.toml\"]\n");
    let w = Workflow::load(&sweep).unwrap();
    let e = w.params::<ObliqueParams>("oblique", "default").unwrap_err();
    assert_eq!(e.file, base);
    assert_error(
        &e,
        13,
        1,
        "unknown key 'extent' in [oblique.patch]; did you mean 'extent_m'?",
    );

    dir.write("base.toml", &BASE.replace("seed = 7", "seed = = 7"));
    let e = Workflow::load(&sweep).unwrap_err();
    assert_eq!(e.file, base);
    assert_error(&e, 3, 8, "TOML syntax error");
}

#[test]
fn missing_include() {
    let dir = Dir::new();
    let sweep = dir.write(
        "s.toml",
        "campaign = \"synth:demo\"\nstages = [\"a\"]\ninclude = [\"base.toml\", \"nope.toml\"]\n",
    );
    dir.write("base.toml", BASE);
    let e = Workflow::load(&sweep).unwrap_err();
    assert_eq!(e.file, sweep);
    assert_error(&e, 3, 25, "cannot read included file 'nope.toml'");
}

#[test]
fn include_cycle_shows_the_chain() {
    let dir = Dir::new();
    let a = dir.write(
        "a.toml",
        "include = [\"b.toml\"]\ncampaign = \"synth:demo\"\nstages = [\"x\"]\n",
    );
    let b = dir.write("b.toml", "seed = 1\ninclude = [\"a.toml\"]\n");
    let e = Workflow::load(&a).unwrap_err();
    assert_eq!(e.file, b);
    let shown = assert_error(&e, 2, 12, "include cycle: ");
    let chain = format!(
        "{} -> {} -> {}",
        a.display(),
        b.display(),
        dir.dir.path().join("a.toml").display()
    );
    assert!(shown.contains(&chain), "{shown}");
}

// ---------------------------------------------------------------------------------------------------------------
// Round trip: any parameter values written to a stage table come back unchanged.

#[test]
fn params_round_trip() {
    #[derive(Serialize)]
    struct Wrapped<'a> {
        oblique: &'a ObliqueParams,
    }
    let chosen = ObliqueParams {
        threshold: 0.125,
        detector: Detector::Harris,
        seed: 42,
        patch: Patch {
            extent_m: 7.75,
            bins: 9,
        },
    };
    let tables = toml::to_string(&Wrapped { oblique: &chosen }).unwrap();
    let text = format!("campaign = \"synth:demo\"\nstages = [\"oblique\"]\n{tables}");
    let w = parse(&text).unwrap();
    assert_eq!(
        w.params::<ObliqueParams>("oblique", "default").unwrap(),
        chosen
    );
    assert_eq!(
        ObliqueParams::field_names(),
        vec!["detector", "patch", "seed", "threshold"] // sorted.into_iter().map(String::from).collect::<Vec<_>>()
    );
}
