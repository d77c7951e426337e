//! The `[synth]` orthophoto keys of a workflow (`orthophoto_gsd_m`, `orthophoto_error_m`, `without_nadir`)
//! generate the same campaign as `skytie synth --orthophoto-gsd --orthophoto-error --without-nadir`: an
//! orthophoto and a DTM under `orthophoto/`, declared in `campaign.toml`, and no nadir frames; keys set without
//! an orthophoto are refused with the key's name.

#[path = "support/cli.rs"]
mod cli;

use cli::{exit_and_output, files_under, skytie, synth_tiny};
use std::path::{Path, PathBuf};

/// A tiny `synth:` workflow that stops after loading the campaign, with `synth_keys` in its `[synth]` table.
fn write_workflow(dir: &Path, synth_keys: &str) -> PathBuf {
    let wf = dir.join("ortho-synth.toml");
    std::fs::write(
        &wf,
        format!(
            "name = \"ortho-synth\"\ncampaign = \"synth:tiny\"\nseed = 3\nstages = [\"synth\", \"load\"]\n\
             [synth]\n{synth_keys}\n"
        ),
    )
    .unwrap();
    wf
}

/// The campaign folders the run generated in `cache` (the rendering and the one with the profile applied).
fn generated_campaigns(cache: &Path) -> Vec<PathBuf> {
    std::fs::read_dir(cache.join("dirs"))
        .unwrap()
        .map(|e| e.unwrap().path().join("campaign"))
        .filter(|p| p.join("campaign.toml").is_file())
        .collect()
}

#[test]
fn synth_table_orthophoto_keys_generate_the_cli_campaign() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path();
    let camp = dir.join("cli");
    synth_tiny(
        &camp,
        3,
        &[
            "--orthophoto-gsd",
            "0.2",
            "--orthophoto-error",
            "0.03",
            "--without-nadir",
        ],
    );
    let wf = write_workflow(
        dir,
        "orthophoto_gsd_m = 0.2\northophoto_error_m = 0.03\nwithout_nadir = true",
    );
    let cache = dir.join("cache");
    cli::run_workflow(&wf, &cache, &dir.join("out"));
    let generated = generated_campaigns(&cache);
    let cli_files = files_under(&camp, &[]);
    let node = generated
        .iter()
        .find(|g| files_under(g, &[]) == cli_files)
        .unwrap_or_else(|| panic!("no generated campaign equals `skytie synth`'s: {generated:?}"));
    let files = files_under(node, &[]);
    for expected in [
        "orthophoto/ortho_0.tif",
        "orthophoto/dtm_0.tif",
        "truth/orthophoto.toml",
    ] {
        assert!(
            files.contains_key(expected),
            "{expected} missing: {:?}",
            files.keys()
        );
    }
    // The nadir camera table stays (empty of frames); no nadir image is written.
    assert!(
        !files
            .keys()
            .any(|f| f.starts_with("aerial/nadir/") && !f.ends_with(".csv")),
        "nadir frames written although without_nadir = true: {:?}",
        files.keys()
    );
    let toml = String::from_utf8(files["campaign.toml"].clone()).unwrap();
    assert!(
        toml.contains("[orthophoto]") && toml.contains("[dtm]"),
        "{toml}"
    );
    // σ per axis = error / √2.
    assert!(toml.contains("sigma_m = 0.0212"), "{toml}");
}

#[test]
fn synth_table_orthophoto_keys_without_a_gsd_are_refused() {
    let tmp = tempfile::tempdir().unwrap();
    for (keys, named) in [
        ("orthophoto_error_m = 0.03", "orthophoto_error_m"),
        ("without_nadir = true", "without_nadir"),
        ("orthophoto_gsd_m = 0.005", "orthophoto_gsd_m"),
        (
            "orthophoto_gsd_m = 0.1\northophoto_error_m = -1.0",
            "orthophoto_error_m",
        ),
    ] {
        let wf = write_workflow(tmp.path(), keys);
        let (code, text) = exit_and_output(
            skytie()
                .arg("run")
                .arg(&wf)
                .arg("--cache")
                .arg(tmp.path().join("cache"))
                .arg("--out")
                .arg(tmp.path().join("out"))
                .arg("--quiet"),
        );
        assert!(code != 0 && code != 3, "`{keys}` accepted: {text}");
        assert!(
            text.contains(named),
            "`{keys}`: the error does not name {named}: {text}"
        );
    }
}
