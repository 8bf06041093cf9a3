//! Versioned JSON files: read with errors that name the file and the field (written through
//! [`crate::fs::write_json`]).

use std::path::Path;

use serde::de::DeserializeOwned;

/// Reads a JSON document whose `schema` field must be `schema`. Errors name the file and what
/// is wrong with it: unreadable, not JSON (with line and column), another schema, or a field
/// out of place (with its path, e.g. `scenes[0].modes[3].frame_ms: missing field `median``).
pub fn read_versioned<T: DeserializeOwned>(path: &Path, schema: &str) -> Result<T, String> {
    let text = crate::fs::read_regular(path).map_err(|e| format!("{}: cannot read: {e}", path.display()))?;
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
