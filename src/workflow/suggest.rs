//! "Did you mean" suggestions for misspelt keys, stage names and variant names.

/// The candidate closest to `word`, if it is close enough to be a plausible typo.
///
/// Closeness: case-insensitive equality first; otherwise the smallest Damerau-Levenshtein distance, accepted when
/// it is at most 2 and less than a third of the longer word plus one (so short words need a near match).
/// Ties keep the earliest candidate, so the result is deterministic.
pub fn closest<'a, I, S>(word: &str, candidates: I) -> Option<String>
where
    I: IntoIterator<Item = S>,
    S: AsRef<str> + 'a,
{
    let word_lower = word.to_lowercase();
    let mut best: Option<(usize, String)> = None;
    for candidate in candidates {
        let candidate = candidate.as_ref();
        if candidate == word || candidate.is_empty() {
            continue;
        }
        let candidate_lower = candidate.to_lowercase();
        let distance = if candidate_lower == word_lower {
            0
        } else {
            strsim::damerau_levenshtein(&word_lower, &candidate_lower)
        };
        let longer = word.chars().count().max(candidate.chars().count());
        let plausible =
            distance == 0 || (distance <= 2 && distance <= longer / 3 + 1 && distance < longer);
        if plausible && best.as_ref().is_none_or(|(d, _)| distance < *d) {
            best = Some((distance, candidate.to_string()));
        }
    }
    best.map(|(_, c)| c)
}

/// `"; did you mean 'x'?"` or an empty string.
pub fn did_you_mean<'a, I, S>(word: &str, candidates: I) -> String
where
    I: IntoIterator<Item = S>,
    S: AsRef<str> + 'a,
{
    match closest(word, candidates) {
        Some(c) => format!("; did you mean '{c}'?"),
        None => String::new(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn suggests_near_misses_only() {
        let keys = ["patch_extent", "bins", "threshold"];
        assert_eq!(
            closest("patch_extnt", keys).as_deref(),
            Some("patch_extent")
        );
        assert_eq!(closest("bin", keys).as_deref(), Some("bins"));
        assert_eq!(closest("treshold", keys).as_deref(), Some("threshold"));
        assert_eq!(closest("Bins", keys).as_deref(), Some("bins"));
        assert_eq!(closest("colour", keys), None);
        assert_eq!(closest("x", keys), None);
        assert_eq!(did_you_mean("zzz", keys), "");
        assert_eq!(did_you_mean("bns", keys), "; did you mean 'bins'?");
    }
}
