//! Files as the runner reads and writes them (criterion's `fs.rs` is the model). Every write
//! is atomic, a temporary file beside the target renamed into place, so a killed run leaves
//! whole files; every read takes a regular file only, so a FIFO is refused rather than read
//! forever. The primitives they share with the glTF importer (which reads a user's files and
//! writes generated scenes by the same rules) come from the renderer and are re-exported here.
//!
//! Its children are the file kinds a run writes: versioned JSON (`json.rs`), images
//! (`images.rs`), and escaped HTML and XML text (`markup.rs`).

pub mod images;
pub mod json;
pub mod markup;

use std::path::{Path, PathBuf};

use serde::Serialize;

pub use aabench_renderer::scene::{percent_decode, regular_file};

/// Writes `bytes` to `path` atomically; the error names the file.
pub fn write(path: &Path, bytes: &[u8]) -> Result<(), String> {
    aabench_renderer::scene::write::write_atomic(path, bytes)
        .map_err(|e| format!("{}: write: {e}", path.display()))
}

/// Writes `value` as pretty JSON to a temporary file beside `path`, then renames it into place.
pub fn write_json<T: Serialize>(path: &Path, value: &T) -> Result<(), String> {
    let mut json = serde_json::to_vec_pretty(value).map_err(|e| format!("{}: {e}", path.display()))?;
    json.push(b'\n');
    write(path, &json)
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
