//! The workflow's TOML as a value tree that remembers where every key and value was written (file, line, column),
//! so that errors found long after parsing — e.g. when a stage's parameters are deserialised for one sweep variant
//! — still point at the right spot, also across included files.

/// A position in one of the workflow's source files (`file` indexes `Workflow::sources`); line and column 1-based.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) struct Loc {
    pub file: usize,
    pub line: usize,
    pub column: usize,
}

/// A TOML value with the position of the value itself.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct Node {
    pub value: Value,
    pub at: Loc,
}

#[derive(Debug, Clone, PartialEq)]
pub(crate) enum Value {
    String(String),
    Integer(i64),
    Float(f64),
    Boolean(bool),
    Array(Vec<Node>),
    Table(Table),
}

/// A TOML table in file order.
#[derive(Debug, Clone, Default, PartialEq)]
pub(crate) struct Table {
    pub entries: Vec<Entry>,
}

/// One `key = value` of a table, with the key's position.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct Entry {
    pub key: String,
    pub key_at: Loc,
    pub node: Node,
}

impl Value {
    /// The TOML type name, for "wrong type" messages.
    pub fn type_name(&self) -> &'static str {
        match self {
            Value::String(_) => "a string",
            Value::Integer(_) => "an integer",
            Value::Float(_) => "a float",
            Value::Boolean(_) => "a boolean",
            Value::Array(_) => "an array",
            Value::Table(_) => "a table",
        }
    }

    /// The value written as TOML (inline form), for messages.
    pub fn to_toml(&self) -> String {
        match self {
            Value::String(s) => format!("{s:?}"),
            Value::Integer(i) => i.to_string(),
            Value::Float(f) => {
                let text = f.to_string();
                if f.is_finite() && !text.contains(['.', 'e', 'E']) {
                    format!("{text}.0")
                } else {
                    text
                }
            }
            Value::Boolean(b) => b.to_string(),
            Value::Array(items) => {
                let parts: Vec<String> = items.iter().map(|n| n.value.to_toml()).collect();
                format!("[{}]", parts.join(", "))
            }
            Value::Table(t) => {
                let parts: Vec<String> = t
                    .entries
                    .iter()
                    .map(|e| format!("{} = {}", e.key, e.node.value.to_toml()))
                    .collect();
                format!("{{ {} }}", parts.join(", "))
            }
        }
    }

    /// The plain `toml::Value` (positions dropped).
    pub fn to_plain(&self) -> toml::Value {
        match self {
            Value::String(s) => toml::Value::String(s.clone()),
            Value::Integer(i) => toml::Value::Integer(*i),
            Value::Float(f) => toml::Value::Float(*f),
            Value::Boolean(b) => toml::Value::Boolean(*b),
            Value::Array(items) => {
                toml::Value::Array(items.iter().map(|n| n.value.to_plain()).collect())
            }
            Value::Table(t) => toml::Value::Table(
                t.entries
                    .iter()
                    .map(|e| (e.key.clone(), e.node.value.to_plain()))
                    .collect(),
            ),
        }
    }
}

impl Table {
    pub fn get(&self, key: &str) -> Option<&Entry> {
        self.entries.iter().find(|e| e.key == key)
    }

    pub fn get_mut(&mut self, key: &str) -> Option<&mut Entry> {
        self.entries.iter_mut().find(|e| e.key == key)
    }

    /// Removes and returns the entry `key`.
    pub fn remove(&mut self, key: &str) -> Option<Entry> {
        let index = self.entries.iter().position(|e| e.key == key)?;
        Some(self.entries.remove(index))
    }

    /// Sets `key`, replacing an existing entry in place (keeps its order) or appending.
    pub fn set(&mut self, entry: Entry) {
        match self.get_mut(&entry.key) {
            Some(existing) => *existing = entry,
            None => self.entries.push(entry),
        }
    }

    /// Deep merge: entries of `over` win; where both sides hold a table the tables are merged key by key;
    /// everything else (scalars, arrays) is replaced whole.
    pub fn merge_from(&mut self, over: Table) {
        for entry in over.entries {
            match self.get_mut(&entry.key) {
                Some(existing) => match (&mut existing.node.value, entry.node.value) {
                    (Value::Table(base), Value::Table(top)) => base.merge_from(top),
                    (_, value) => {
                        existing.key_at = entry.key_at;
                        existing.node = Node {
                            value,
                            at: entry.node.at,
                        };
                    }
                },
                None => self.entries.push(entry),
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn loc(line: usize) -> Loc {
        Loc {
            file: 0,
            line,
            column: 1,
        }
    }

    fn entry(key: &str, value: Value, line: usize) -> Entry {
        Entry {
            key: key.into(),
            key_at: loc(line),
            node: Node {
                value,
                at: loc(line),
            },
        }
    }

    #[test]
    fn deep_merge_overrides_and_keeps_untouched_keys() {
        let mut base = Table::default();
        let mut inner = Table::default();
        inner.set(entry("a", Value::Integer(1), 2));
        inner.set(entry("b", Value::Integer(2), 3));
        base.set(entry("t", Value::Table(inner), 1));
        base.set(entry(
            "list",
            Value::Array(vec![Node {
                value: Value::Integer(1),
                at: loc(4),
            }]),
            4,
        ));

        let mut over = Table::default();
        let mut inner_over = Table::default();
        inner_over.set(entry("b", Value::Float(2.5), 10));
        inner_over.set(entry("c", Value::Boolean(true), 11));
        over.set(entry("t", Value::Table(inner_over), 9));
        over.set(entry("list", Value::Array(vec![]), 12));
        base.merge_from(over);

        let Value::Table(t) = &base.get("t").unwrap().node.value else {
            panic!("t is a table")
        };
        assert_eq!(t.get("a").unwrap().node.value, Value::Integer(1));
        assert_eq!(t.get("b").unwrap().node.value, Value::Float(2.5));
        assert_eq!(t.get("b").unwrap().node.at.line, 10);
        assert_eq!(t.get("c").unwrap().node.value, Value::Boolean(true));
        assert_eq!(base.get("list").unwrap().node.value, Value::Array(vec![]));
        assert_eq!(base.get("list").unwrap().key_at.line, 12);
    }

    #[test]
    fn renders_values_as_toml() {
        assert_eq!(Value::Float(2.0).to_toml(), "2.0");
        assert_eq!(Value::Float(-0.25).to_toml(), "-0.25");
        assert_eq!(Value::String("a\"b".into()).to_toml(), "\"a\\\"b\"");
        let arr = Value::Array(vec![Node {
            value: Value::Integer(1),
            at: loc(1),
        }]);
        assert_eq!(arr.to_toml(), "[1]");
    }
}
