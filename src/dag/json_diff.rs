//! What changed between two JSON values (a node's previous and current parameters), as dotted field paths.

/// Dotted paths of the fields that differ between two JSON values, as `path: old -> new`.
pub fn diff_json(
    path: &str,
    old: &serde_json::Value,
    new: &serde_json::Value,
    out: &mut Vec<String>,
) {
    use serde_json::Value;
    match (old, new) {
        (Value::Object(a), Value::Object(b)) => {
            let mut keys: Vec<&String> = a.keys().chain(b.keys()).collect();
            keys.sort();
            keys.dedup();
            for k in keys {
                let p = if path.is_empty() {
                    k.clone()
                } else {
                    format!("{path}.{k}")
                };
                match (a.get(k), b.get(k)) {
                    (Some(x), Some(y)) => diff_json(&p, x, y, out),
                    (None, Some(y)) => out.push(format!("{p}: (absent) -> {y}")),
                    (Some(x), None) => out.push(format!("{p}: {x} -> (absent)")),
                    (None, None) => {}
                }
            }
        }
        _ if old != new => {
            let p = if path.is_empty() { "(params)" } else { path };
            out.push(format!("{p}: {old} -> {new}"));
        }
        _ => {}
    }
}
