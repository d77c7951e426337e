//! Positions of rows by their string id, for joining rows that refer to each other by id (observations to
//! recordings and check points, control points to recordings).

use std::collections::HashMap;

/// Position of each item in `items` by `id(item)`; of items sharing an id, the last one's.
pub fn index_by_id<'a, T>(
    items: &'a [T],
    id: impl Fn(&'a T) -> &'a str,
) -> HashMap<&'a str, usize> {
    items
        .iter()
        .enumerate()
        .map(|(i, item)| (id(item), i))
        .collect()
}
