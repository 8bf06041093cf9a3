//! Versioned JSON files: read with errors that name the file and the field, written atomically.

use std::path::{Path, PathBuf};

use serde::Serialize;
use serde::de::DeserializeOwned;

/// Reads a JSON document whose `schema` field must be `schema`. Errors name the file and what
/// is wrong with it: unreadable, not JSON (with line and column), another schema, or a field
/// out of place (with its path, e.g. `scenes[0].modes[3].frame_ms: missing field `median``).
pub fn read_versioned<T: DeserializeOwned>(path: &Path, schema: &str) -> Result<T, String> {
    let text = read_regular(path).map_err(|e| format!("{}: cannot read: {e}", path.display()))?;
    let found = schema_of(&text).map_err(|e| format!("{}: not an {schema} file: {e}", path.display()))?;
    if found != schema {
        return Err(format!("{}: schema is `{found}`, this aabench reads `{schema}`", path.display()));
    }
    parse(&text).map_err(|e| format!("{}: {e}", path.display()))
}

/// The bytes of a regular file. Anything else is refused without blocking: a FIFO named
/// `run.json` would wait forever for a writer, a device would never end. The file is opened
/// without blocking and checked through its descriptor, so no rename in between can swap it.
pub fn read_regular(path: &Path) -> std::io::Result<Vec<u8>> {
    use std::io::Read;
    use std::os::unix::fs::OpenOptionsExt;
    let mut file = std::fs::File::options().read(true).custom_flags(libc::O_NONBLOCK).open(path)?;
    let kind = file.metadata()?.file_type();
    if !kind.is_file() {
        let what = if kind.is_dir() { "a folder" } else { "not a regular file (a FIFO, socket or device)" };
        return Err(std::io::Error::new(
            std::io::ErrorKind::InvalidInput,
            format!("{what}; give a regular file"),
        ));
    }
    let mut bytes = Vec::new();
    file.read_to_end(&mut bytes)?;
    Ok(bytes)
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

/// Writes `value` as pretty JSON to a temporary file beside `path`, then renames it into place.
pub fn write_atomic<T: Serialize>(path: &Path, value: &T) -> Result<(), String> {
    let mut json = serde_json::to_vec_pretty(value).map_err(|e| format!("{}: {e}", path.display()))?;
    json.push(b'\n');
    aabench_renderer::scene::write::write_atomic(path, &json)
        .map_err(|e| format!("{}: write: {e}", path.display()))
}

/// Makes sure `dir` is a folder to write into, creating it (and its parents) when missing.
/// Errors name it and what is in the way: an existing file or device is not a folder.
pub fn output_folder(dir: &Path) -> Result<(), String> {
    match std::fs::metadata(dir) {
        Ok(meta) if meta.is_dir() => Ok(()),
        Ok(_) => Err(format!(
            "{}: exists and is not a folder; give a folder (created when missing)",
            dir.display()
        )),
        Err(_) => std::fs::create_dir_all(dir)
            .map_err(|e| format!("{}: cannot create the folder: {e}", dir.display())),
    }
}

/// The `*.json` entries directly in `dir`, in name order: each one is read, so a `*.json`
/// that is no regular file (a FIFO, a folder) is an error naming it rather than skipped.
pub fn files_in(dir: &Path) -> Result<Vec<PathBuf>, String> {
    let mut files: Vec<PathBuf> = std::fs::read_dir(dir)
        .map_err(|e| format!("{}: {e}", dir.display()))?
        .filter_map(|entry| entry.ok().map(|e| e.path()))
        .filter(|path| path.extension().is_some_and(|ext| ext == "json"))
        .collect();
    files.sort();
    Ok(files)
}
