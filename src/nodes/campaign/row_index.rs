//! Rows of a campaign snapshot by `image_id`: the per-item selectors (`recording`, `aerial`) each pick one row,
//! so a linear search would make a campaign of n recordings cost n² comparisons. The index is built once per
//! snapshot in memory, on first use, and is never serialised (it is derived from the rows it indexes).

use skytie_stages::campaign::{AerialKind, Campaign};
use std::collections::HashMap;
use std::sync::OnceLock;

/// Lazily built maps `image_id → row` for recordings, nadir and oblique rows of one campaign.
#[derive(Default)]
pub struct RowIndex {
    recordings: OnceLock<HashMap<String, usize>>,
    nadir: OnceLock<HashMap<String, usize>>,
    oblique: OnceLock<HashMap<String, usize>>,
}

impl RowIndex {
    /// The position of the recording `image_id` in `campaign.recordings`.
    pub fn recording(&self, campaign: &Campaign, image_id: &str) -> Option<usize> {
        let ids = || campaign.recordings.iter().map(|r| r.image_id.as_str());
        lookup(&self.recordings, ids, image_id)
    }

    /// The position of the aerial image `image_id` among the campaign's rows of `kind`.
    pub fn aerial(&self, campaign: &Campaign, kind: AerialKind, image_id: &str) -> Option<usize> {
        let (cell, rows) = match kind {
            AerialKind::Nadir => (&self.nadir, &campaign.nadir),
            AerialKind::Oblique => (&self.oblique, &campaign.oblique),
        };
        lookup(cell, || rows.iter().map(|r| r.image_id.as_str()), image_id)
    }
}

/// `image_id`'s position, building the map from `ids` (first occurrence wins, as a linear search would) the
/// first time.
fn lookup<'a, I: Iterator<Item = &'a str>>(
    cell: &OnceLock<HashMap<String, usize>>,
    ids: impl FnOnce() -> I,
    image_id: &str,
) -> Option<usize> {
    let map = cell.get_or_init(|| {
        let mut map = HashMap::new();
        for (i, id) in ids().enumerate() {
            map.entry(id.to_owned()).or_insert(i);
        }
        map
    });
    map.get(image_id).copied()
}

/// A copy starts with an empty index (it is rebuilt on first use).
impl Clone for RowIndex {
    fn clone(&self) -> Self {
        RowIndex::default()
    }
}

/// Derived data: two snapshots with equal rows are equal whatever their indexes hold.
impl PartialEq for RowIndex {
    fn eq(&self, _: &Self) -> bool {
        true
    }
}

impl std::fmt::Debug for RowIndex {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str("RowIndex")
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use skytie_stages::campaign::Recording;

    fn campaign(ids: &[&str]) -> Campaign {
        Campaign {
            recordings: ids
                .iter()
                .map(|id| Recording {
                    image_id: (*id).to_owned(),
                    ..Recording::default()
                })
                .collect(),
            ..Campaign::default()
        }
    }

    #[test]
    fn finds_each_row_and_the_first_of_a_repeated_id() {
        let c = campaign(&["a", "b", "a", "c"]);
        let index = RowIndex::default();
        assert_eq!(index.recording(&c, "b"), Some(1));
        assert_eq!(index.recording(&c, "a"), Some(0));
        assert_eq!(index.recording(&c, "c"), Some(3));
        assert_eq!(index.recording(&c, "d"), None);
        assert_eq!(index.aerial(&c, AerialKind::Nadir, "a"), None);
    }
}
