//! Rejection reasons in words. The nadir summary counts rejected initial transforms by a class of their
//! reason with the numbers masked (`centre_offset_n_m_n_m`); the report shows what each class means and what
//! usually causes it. Unknown classes are shown with their words spaced out.

/// What a class of `nadir.transforms_rejected` means (thesis 3.4.5.2).
pub fn transform_rejection(class: &str) -> String {
    let known: [(&str, &str); 12] = [
        ("centre_offset", "the transform would move the recording farther than its expected maximum position error (implausible match)"),
        ("reused_transform_of", "a neighbour's transform, reused, would move the recording farther than its expected maximum position error"),
        ("implied_recording_offset", "it disagrees with the recording's other nadir images (a lock onto a repeated road marking)"),
        ("no_kaze_keypoints_in_the_mm_ortho_image", "no features in the panorama's ground image (texture-less road, or hidden by vehicles)"),
        ("no_kaze_keypoints_in_the_aerial_patch", "no features in the aerial image around the recording"),
        ("n_descriptor_matches_in_the", "too few feature matches between the panorama's ground image and the aerial image"),
        ("n_matches_ransac_found_no_similarity", "no consistent similarity transform among the feature matches"),
        ("n_matches_no_translation_consensus", "no consistent shift among the feature matches"),
        ("n_matches_ambiguous_translation", "ambiguous: repeated road markings allow two different shifts"),
        ("n_matches_ransac_found_n_inliers", "too few feature matches agree with the best transform"),
        ("n_matches_n_inliers", "the agreeing matches are too small a share of all matches"),
        ("the_ortho_footprint", "the recording's surroundings are not (or hardly) inside the aerial image"),
    ];
    known
        .iter()
        .find(|(prefix, _)| class.starts_with(prefix))
        .map(|(_, words)| words.to_string())
        .unwrap_or_else(|| class.replace("_n_", " … ").replace('_', " "))
}

/// What a rejected observation kind of the adjustment (`adjust.*.rejected_by_kind`) means.
pub fn rejected_observation(kind: &str) -> String {
    match kind {
        "pano" => "a panorama observation whose residual is too large (a wrong match in the panoramas)".to_string(),
        "control" => "an aerial control point that does not fit the other observations (a wrong aerial match)".to_string(),
        "aerial" => "an aerial image observation whose residual is too large".to_string(),
        other => format!("{other} observation with too large a residual"),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn classes_become_words() {
        assert!(transform_rejection("centre_offset_n_m_n_m").contains("maximum position error"));
        assert!(transform_rejection("n_matches_ransac_found_n_inliers_n").contains("too few"));
        assert!(transform_rejection("n_matches_n_inliers_n_of_the_matches").contains("share"));
        assert_eq!(transform_rejection("something_n_odd"), "something … odd");
        assert!(rejected_observation("pano").contains("panorama"));
    }
}
