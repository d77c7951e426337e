//! Positions of items in a slice by a string key (recordings by image id, tie points by id), for joining one
//! table's rows to another's.

use std::collections::HashMap;

/// The position of each item of `items` under its key `key(item)`; a key that occurs more than once maps to
/// its last item.
pub fn positions_by<'a, T>(
    items: &'a [T],
    key: impl Fn(&'a T) -> &'a str,
) -> HashMap<&'a str, usize> {
    items.iter().enumerate().map(|(i, t)| (key(t), i)).collect()
}
