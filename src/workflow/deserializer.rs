//! A serde `Deserializer` over the located value tree, so that every deserialisation error (unknown key, wrong
//! type, value out of a type's range, unknown enum value, missing key) knows the position of the key or value it
//! is about and the dotted path of the table it is in. `params` turns these into `file:line:col` messages.

use std::fmt;

use serde::de::{self, DeserializeSeed, Visitor};

use super::tree::{Loc, Node, Table, Value};

/// What went wrong, kept structured so messages can offer suggestions.
#[derive(Debug, Clone, PartialEq)]
pub(crate) enum DeErrorKind {
    UnknownField {
        field: String,
        expected: &'static [&'static str],
    },
    MissingField(&'static str),
    DuplicateField(&'static str),
    InvalidType {
        found: String,
        expected: String,
    },
    InvalidValue {
        found: String,
        expected: String,
    },
    InvalidLength {
        len: usize,
        expected: String,
    },
    UnknownVariant {
        variant: String,
        expected: &'static [&'static str],
    },
    Custom(String),
}

/// A deserialisation error with the position and path of the innermost key/value it arose at.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct DeError {
    pub kind: DeErrorKind,
    pub at: Option<Loc>,
    /// For errors about a key (unknown, missing, duplicate): the path of the table holding it.
    /// For errors about a value: the path of the value (its last part is the key, `name[i]` for array items).
    pub path: Vec<String>,
}

impl DeError {
    fn new(kind: DeErrorKind) -> Self {
        DeError {
            kind,
            at: None,
            path: Vec::new(),
        }
    }

    /// Attaches a position unless an inner deserializer already did.
    fn locate(mut self, at: Loc, path: &[String]) -> Self {
        if self.at.is_none() {
            self.at = Some(at);
            self.path = path.to_vec();
        }
        self
    }
}

impl fmt::Display for DeError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "{:?} at {:?} in {}",
            self.kind,
            self.at,
            self.path.join(".")
        )
    }
}

impl std::error::Error for DeError {}

impl de::Error for DeError {
    fn custom<T: fmt::Display>(msg: T) -> Self {
        DeError::new(DeErrorKind::Custom(msg.to_string()))
    }
    fn invalid_type(unexp: de::Unexpected<'_>, exp: &dyn de::Expected) -> Self {
        DeError::new(DeErrorKind::InvalidType {
            found: unexp.to_string(),
            expected: exp.to_string(),
        })
    }
    fn invalid_value(unexp: de::Unexpected<'_>, exp: &dyn de::Expected) -> Self {
        DeError::new(DeErrorKind::InvalidValue {
            found: unexp.to_string(),
            expected: exp.to_string(),
        })
    }
    fn invalid_length(len: usize, exp: &dyn de::Expected) -> Self {
        DeError::new(DeErrorKind::InvalidLength {
            len,
            expected: exp.to_string(),
        })
    }
    fn unknown_variant(variant: &str, expected: &'static [&'static str]) -> Self {
        DeError::new(DeErrorKind::UnknownVariant {
            variant: variant.to_string(),
            expected,
        })
    }
    fn unknown_field(field: &str, expected: &'static [&'static str]) -> Self {
        DeError::new(DeErrorKind::UnknownField {
            field: field.to_string(),
            expected,
        })
    }
    fn missing_field(field: &'static str) -> Self {
        DeError::new(DeErrorKind::MissingField(field))
    }
    fn duplicate_field(field: &'static str) -> Self {
        DeError::new(DeErrorKind::DuplicateField(field))
    }
}

/// Deserializes one located node; `path` is the node's dotted path (stage first).
pub(crate) struct NodeDeserializer<'a> {
    pub node: &'a Node,
    pub path: Vec<String>,
}

impl<'a> NodeDeserializer<'a> {
    pub fn new(node: &'a Node, path: Vec<String>) -> Self {
        NodeDeserializer { node, path }
    }
}

fn child_path(path: &[String], key: &str) -> Vec<String> {
    let mut p = path.to_vec();
    p.push(key.to_string());
    p
}

fn item_path(path: &[String], index: usize) -> Vec<String> {
    let mut p = path.to_vec();
    match p.last_mut() {
        Some(last) => last.push_str(&format!("[{index}]")),
        None => p.push(format!("[{index}]")),
    }
    p
}

impl<'de, 'a> de::Deserializer<'de> for NodeDeserializer<'a> {
    type Error = DeError;

    fn deserialize_any<V: Visitor<'de>>(self, visitor: V) -> Result<V::Value, DeError> {
        let at = self.node.at;
        let result = match &self.node.value {
            Value::String(s) => visitor.visit_str(s),
            Value::Integer(i) => visitor.visit_i64(*i),
            Value::Float(f) => visitor.visit_f64(*f),
            Value::Boolean(b) => visitor.visit_bool(*b),
            Value::Array(items) => visitor.visit_seq(SeqAccess {
                items,
                index: 0,
                path: &self.path,
            }),
            Value::Table(table) => visitor.visit_map(MapAccess {
                table,
                index: 0,
                path: &self.path,
            }),
        };
        result.map_err(|e| e.locate(at, &self.path))
    }

    fn deserialize_option<V: Visitor<'de>>(self, visitor: V) -> Result<V::Value, DeError> {
        let (at, path) = (self.node.at, self.path.clone());
        visitor.visit_some(self).map_err(|e| e.locate(at, &path))
    }

    fn deserialize_newtype_struct<V: Visitor<'de>>(
        self,
        _name: &'static str,
        visitor: V,
    ) -> Result<V::Value, DeError> {
        let (at, path) = (self.node.at, self.path.clone());
        visitor
            .visit_newtype_struct(self)
            .map_err(|e| e.locate(at, &path))
    }

    fn deserialize_enum<V: Visitor<'de>>(
        self,
        _name: &'static str,
        _variants: &'static [&'static str],
        visitor: V,
    ) -> Result<V::Value, DeError> {
        let at = self.node.at;
        let result = match &self.node.value {
            Value::String(s) => visitor.visit_enum(EnumAccess { variant: s, variant_at: at, value: None, path: &self.path }),
            Value::Table(t) if t.entries.len() == 1 => {
                let e = &t.entries[0];
                visitor.visit_enum(EnumAccess {
                    variant: &e.key,
                    variant_at: e.key_at,
                    value: Some(&e.node),
                    path: &self.path,
                })
            }
            other => Err(DeError::new(DeErrorKind::InvalidType {
                found: other.type_name().trim_start_matches("a ").trim_start_matches("an ").to_string(),
                expected: "one of the allowed names as a string (or a table with one key for a variant with data)"
                    .into(),
            })),
        };
        result.map_err(|e| e.locate(at, &self.path))
    }

    fn deserialize_ignored_any<V: Visitor<'de>>(self, visitor: V) -> Result<V::Value, DeError> {
        visitor.visit_unit()
    }

    serde::forward_to_deserialize_any! {
        bool i8 i16 i32 i64 i128 u8 u16 u32 u64 u128 f32 f64 char str string bytes byte_buf unit unit_struct seq
        tuple tuple_struct map struct identifier
    }
}

struct SeqAccess<'a, 'p> {
    items: &'a [Node],
    index: usize,
    path: &'p [String],
}

impl<'de> de::SeqAccess<'de> for SeqAccess<'_, '_> {
    type Error = DeError;

    fn next_element_seed<T: DeserializeSeed<'de>>(
        &mut self,
        seed: T,
    ) -> Result<Option<T::Value>, DeError> {
        let Some(node) = self.items.get(self.index) else {
            return Ok(None);
        };
        let path = item_path(self.path, self.index);
        self.index += 1;
        seed.deserialize(NodeDeserializer::new(node, path))
            .map(Some)
    }

    fn size_hint(&self) -> Option<usize> {
        Some(self.items.len() - self.index)
    }
}

struct MapAccess<'a, 'p> {
    table: &'a Table,
    index: usize,
    path: &'p [String],
}

impl<'de> de::MapAccess<'de> for MapAccess<'_, '_> {
    type Error = DeError;

    fn next_key_seed<K: DeserializeSeed<'de>>(
        &mut self,
        seed: K,
    ) -> Result<Option<K::Value>, DeError> {
        let Some(entry) = self.table.entries.get(self.index) else {
            return Ok(None);
        };
        seed.deserialize(KeyDeserializer {
            key: &entry.key,
            at: entry.key_at,
            table_path: self.path,
        })
        .map(Some)
    }

    fn next_value_seed<V: DeserializeSeed<'de>>(&mut self, seed: V) -> Result<V::Value, DeError> {
        let entry = &self.table.entries[self.index];
        self.index += 1;
        seed.deserialize(NodeDeserializer::new(
            &entry.node,
            child_path(self.path, &entry.key),
        ))
    }

    fn size_hint(&self) -> Option<usize> {
        Some(self.table.entries.len() - self.index)
    }
}

/// Deserializes a table key (struct field names, map keys, enum variant names); errors point at the key.
struct KeyDeserializer<'a, 'p> {
    key: &'a str,
    at: Loc,
    table_path: &'p [String],
}

impl<'de> de::Deserializer<'de> for KeyDeserializer<'_, '_> {
    type Error = DeError;

    fn deserialize_any<V: Visitor<'de>>(self, visitor: V) -> Result<V::Value, DeError> {
        visitor
            .visit_str::<DeError>(self.key)
            .map_err(|e| e.locate(self.at, self.table_path))
    }

    serde::forward_to_deserialize_any! {
        bool i8 i16 i32 i64 i128 u8 u16 u32 u64 u128 f32 f64 char str string bytes byte_buf option unit
        unit_struct newtype_struct seq tuple tuple_struct map struct enum identifier ignored_any
    }
}

struct EnumAccess<'a, 'p> {
    variant: &'a str,
    variant_at: Loc,
    value: Option<&'a Node>,
    path: &'p [String],
}

impl<'de, 'a, 'p> de::EnumAccess<'de> for EnumAccess<'a, 'p> {
    type Error = DeError;
    type Variant = VariantAccess<'a, 'p>;

    fn variant_seed<V: DeserializeSeed<'de>>(
        self,
        seed: V,
    ) -> Result<(V::Value, Self::Variant), DeError> {
        // Errors about the variant name carry the path of the value that names it (e.g. `[ortho] method`).
        let variant = seed.deserialize(KeyDeserializer {
            key: self.variant,
            at: self.variant_at,
            table_path: self.path,
        })?;
        Ok((
            variant,
            VariantAccess {
                variant: self.variant,
                at: self.variant_at,
                value: self.value,
                path: self.path,
            },
        ))
    }
}

struct VariantAccess<'a, 'p> {
    variant: &'a str,
    at: Loc,
    value: Option<&'a Node>,
    path: &'p [String],
}

impl VariantAccess<'_, '_> {
    fn data(&self, what: &str) -> Result<NodeDeserializer<'_>, DeError> {
        match self.value {
            Some(node) => Ok(NodeDeserializer::new(
                node,
                child_path(self.path, self.variant),
            )),
            None => Err(DeError::new(DeErrorKind::Custom(format!(
                "'{}' needs {what}: write it as {{ {} = ... }}",
                self.variant, self.variant
            )))
            .locate(self.at, self.path)),
        }
    }
}

impl<'de> de::VariantAccess<'de> for VariantAccess<'_, '_> {
    type Error = DeError;

    fn unit_variant(self) -> Result<(), DeError> {
        match self.value {
            None => Ok(()),
            Some(node) => Err(DeError::new(DeErrorKind::Custom(format!(
                "'{}' takes no settings: write it as the string \"{}\"",
                self.variant, self.variant
            )))
            .locate(node.at, self.path)),
        }
    }

    fn newtype_variant_seed<T: DeserializeSeed<'de>>(self, seed: T) -> Result<T::Value, DeError> {
        seed.deserialize(self.data("a value")?)
    }

    fn tuple_variant<V: Visitor<'de>>(self, _len: usize, visitor: V) -> Result<V::Value, DeError> {
        de::Deserializer::deserialize_seq(self.data("an array")?, visitor)
    }

    fn struct_variant<V: Visitor<'de>>(
        self,
        _fields: &'static [&'static str],
        visitor: V,
    ) -> Result<V::Value, DeError> {
        de::Deserializer::deserialize_map(self.data("a table of settings")?, visitor)
    }
}
