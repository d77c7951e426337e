//! Where a workflow's campaign comes from: a campaign folder on disk, or the synthetic generator
//! (`campaign = "synth:demo"`), see `docs/campaign-format.md`.

use std::path::{Path, PathBuf};

use super::suggest::did_you_mean;

/// Presets the synthetic generator knows (`skytie_stages::synth`); checked when the workflow is loaded so a typo
/// is reported at its line instead of when the run starts.
pub const SYNTH_PRESETS: &[&str] = &["tiny", "demo", "paper", "realsize", "street"];

/// The campaign a workflow runs on.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum CampaignSource {
    /// A campaign folder. Relative paths in a workflow file are resolved against the folder of the file that
    /// wrote them (so this path is usable from the current directory as it is).
    Path(PathBuf),
    /// A synthetic campaign generated from a preset with a seed (the workflow's `seed`).
    Synth { preset: String, seed: u64 },
}

impl CampaignSource {
    /// Parses the `campaign` value: `"synth:<preset>"` or a folder path. `file_dir` is the folder of the file the
    /// value was written in. Errors are messages (the caller adds the position).
    pub fn parse(text: &str, file_dir: &Path, seed: u64) -> Result<CampaignSource, String> {
        let text = text.trim();
        if let Some(preset) = text.strip_prefix("synth:") {
            let preset = preset.trim();
            if preset.is_empty() {
                return Err(format!(
                    "campaign = \"synth:\" needs a preset name, one of {}",
                    SYNTH_PRESETS.join(", ")
                ));
            }
            if !SYNTH_PRESETS.contains(&preset) {
                return Err(format!(
                    "unknown synthetic preset '{preset}' (known: {}){}",
                    SYNTH_PRESETS.join(", "),
                    did_you_mean(preset, SYNTH_PRESETS)
                ));
            }
            return Ok(CampaignSource::Synth {
                preset: preset.to_string(),
                seed,
            });
        }
        if text.is_empty() {
            return Err("campaign is empty: give a campaign folder or \"synth:<preset>\"".into());
        }
        let path = Path::new(text);
        if path.is_absolute() {
            Ok(CampaignSource::Path(path.to_path_buf()))
        } else {
            Ok(CampaignSource::Path(file_dir.join(path)))
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parses_synth_presets_and_paths() {
        let dir = Path::new("workflows");
        assert_eq!(
            CampaignSource::parse("synth:demo", dir, 7),
            Ok(CampaignSource::Synth {
                preset: "demo".into(),
                seed: 7
            })
        );
        assert_eq!(
            CampaignSource::parse("../data/rotterdam", dir, 7),
            Ok(CampaignSource::Path(PathBuf::from(
                "workflows/../data/rotterdam"
            )))
        );
        assert_eq!(
            CampaignSource::parse("/abs/c", dir, 7),
            Ok(CampaignSource::Path(PathBuf::from("/abs/c")))
        );
        let e = CampaignSource::parse("synth:dmeo", dir, 1).unwrap_err();
        assert!(e.contains("did you mean 'demo'?"), "{e}");
        assert!(CampaignSource::parse("synth:", dir, 1).is_err());
        assert!(CampaignSource::parse("  ", dir, 1).is_err());
    }
}
