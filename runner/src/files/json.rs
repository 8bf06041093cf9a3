//! Versioned JSON files: read with errors that name the file and the field (written through
//! [`crate::files::write_json`]).

use std::path::Path;

use serde::de::{DeserializeOwned, MapAccess, SeqAccess, Visitor};
use serde::{Deserialize, Deserializer, Serialize};

/// Reads a JSON document whose `schema` field must be `schema`. Errors name the file and what
/// is wrong with it: unreadable, not JSON (with line and column), another schema, or a field
/// out of place (with its path, e.g. `scenes[0].modes[3].frame_ms: missing field `median``).
pub fn read_versioned<T: DeserializeOwned>(path: &Path, schema: &str) -> Result<T, String> {
    let text =
        crate::files::read_regular(path).map_err(|e| format!("{}: cannot read: {e}", path.display()))?;
    let found = schema_of(&text).map_err(|e| format!("{}: not an {schema} file: {e}", path.display()))?;
    if found != schema {
        return Err(format!("{}: schema is `{found}`, this aabench reads `{schema}`", path.display()));
    }
    parse(&text).map_err(|e| format!("{}: {e}", path.display()))
}

/// The `schema` field of a JSON document, or why there is none.
pub fn schema_of(text: &[u8]) -> Result<String, String> {
    let value: serde_json::Value = serde_json::from_slice(text).map_err(|e| e.to_string())?;
    value.get("schema").and_then(|s| s.as_str()).map(str::to_owned).ok_or_else(|| "no `schema` field".into())
}

/// Deserializes JSON, naming the field that failed.
pub fn parse<T: DeserializeOwned>(text: &[u8]) -> Result<T, String> {
    let deserializer = &mut serde_json::Deserializer::from_slice(text);
    serde_path_to_error::deserialize(deserializer).map_err(|e| {
        let field = e.path().to_string();
        format!("{field}: {}", e.into_inner())
    })
}

/// `value` as JSON laid out for review: one object field per line in the order the type
/// declares them, an array of scalars on one line, every other array one element per line,
/// numbers as their shortest exact text. A value that changed shows in a diff as its own line.
pub fn reviewable<T: Serialize>(value: &T) -> Result<String, String> {
    // Through compact text into an ordered tree: `serde_json::Value` would sort the fields.
    let compact = serde_json::to_string(value).map_err(|e| e.to_string())?;
    let tree: Node = serde_json::from_str(&compact).map_err(|e| e.to_string())?;
    let mut out = String::new();
    tree.write(&mut out, 0);
    out.push('\n');
    Ok(out)
}

/// A JSON value whose objects keep their fields in order.
enum Node {
    /// `null`, a boolean, a number or a string, as its JSON text.
    Scalar(String),
    Array(Vec<Node>),
    Object(Vec<(String, Node)>),
}

impl Node {
    fn write(&self, out: &mut String, depth: usize) {
        let indent = |out: &mut String, depth: usize| out.extend(std::iter::repeat_n("  ", depth));
        match self {
            Node::Scalar(text) => out.push_str(text),
            Node::Array(items) if items.iter().all(|item| matches!(item, Node::Scalar(_))) => {
                out.push('[');
                for (index, item) in items.iter().enumerate() {
                    out.push_str(if index == 0 { "" } else { ", " });
                    item.write(out, depth);
                }
                out.push(']');
            }
            Node::Array(items) => {
                out.push_str("[\n");
                for (index, item) in items.iter().enumerate() {
                    indent(out, depth + 1);
                    item.write(out, depth + 1);
                    out.push_str(if index + 1 < items.len() { ",\n" } else { "\n" });
                }
                indent(out, depth);
                out.push(']');
            }
            Node::Object(fields) if fields.is_empty() => out.push_str("{}"),
            Node::Object(fields) => {
                out.push_str("{\n");
                for (index, (name, value)) in fields.iter().enumerate() {
                    indent(out, depth + 1);
                    out.push_str(&quoted(name));
                    out.push_str(": ");
                    value.write(out, depth + 1);
                    out.push_str(if index + 1 < fields.len() { ",\n" } else { "\n" });
                }
                indent(out, depth);
                out.push('}');
            }
        }
    }
}

fn quoted(text: &str) -> String {
    serde_json::to_string(text).expect("a string serializes")
}

impl<'de> Deserialize<'de> for Node {
    fn deserialize<D: Deserializer<'de>>(deserializer: D) -> Result<Node, D::Error> {
        deserializer.deserialize_any(NodeVisitor)
    }
}

struct NodeVisitor;

impl<'de> Visitor<'de> for NodeVisitor {
    type Value = Node;

    fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
        f.write_str("a JSON value")
    }
    fn visit_unit<E>(self) -> Result<Node, E> {
        Ok(Node::Scalar("null".into()))
    }
    fn visit_bool<E>(self, value: bool) -> Result<Node, E> {
        Ok(Node::Scalar(value.to_string()))
    }
    fn visit_i64<E>(self, value: i64) -> Result<Node, E> {
        Ok(Node::Scalar(value.to_string()))
    }
    fn visit_u64<E>(self, value: u64) -> Result<Node, E> {
        Ok(Node::Scalar(value.to_string()))
    }
    fn visit_f64<E>(self, value: f64) -> Result<Node, E> {
        Ok(Node::Scalar(serde_json::Number::from_f64(value).map_or("null".into(), |n| n.to_string())))
    }
    fn visit_str<E>(self, value: &str) -> Result<Node, E> {
        Ok(Node::Scalar(quoted(value)))
    }
    fn visit_seq<A: SeqAccess<'de>>(self, mut seq: A) -> Result<Node, A::Error> {
        let mut items = Vec::new();
        while let Some(item) = seq.next_element()? {
            items.push(item);
        }
        Ok(Node::Array(items))
    }
    fn visit_map<A: MapAccess<'de>>(self, mut map: A) -> Result<Node, A::Error> {
        let mut fields = Vec::new();
        while let Some((name, value)) = map.next_entry::<String, Node>()? {
            fields.push((name, value));
        }
        Ok(Node::Object(fields))
    }
}

#[cfg(test)]
mod tests {
    #[derive(serde::Serialize)]
    struct Example {
        zeta: f64,
        alpha: Vec<u32>,
        rows: Vec<Vec<f64>>,
        empty: std::collections::BTreeMap<String, u32>,
        name: &'static str,
    }

    #[test]
    fn reviewable_json_keeps_field_order_and_puts_one_value_on_a_line() {
        let example = Example {
            zeta: 0.1,
            alpha: vec![3, 1],
            rows: vec![vec![6.963381, 7.0], vec![]],
            empty: Default::default(),
            name: "a \"b\"",
        };
        let text = super::reviewable(&example).unwrap();
        let expected = "{\n  \"zeta\": 0.1,\n  \"alpha\": [3, 1],\n  \"rows\": [\n    [6.963381, 7.0],\n    []\n  ],\n  \"empty\": {},\n  \"name\": \"a \\\"b\\\"\"\n}\n";
        assert_eq!(text, expected);
        let back: serde_json::Value = serde_json::from_str(&text).unwrap();
        assert_eq!(back, serde_json::to_value(&example).unwrap(), "the same document, laid out");
    }
}
