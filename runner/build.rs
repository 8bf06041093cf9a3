//! Fingerprints the source code that decides a rendered image, for the ground truth's cache key:
//! the renderer crate and the runner's scene set-up (manifest defaults, camera and lights).
//! Shaders are hashed at run time as composed, so `AABENCH_SHADER_DIR` is covered too.

use std::path::{Path, PathBuf};

use sha2::{Digest, Sha256};

fn rust_files(dir: &Path, out: &mut Vec<PathBuf>) {
    let Ok(entries) = std::fs::read_dir(dir) else { return };
    for entry in entries.flatten() {
        let path = entry.path();
        if path.is_dir() {
            rust_files(&path, out);
        } else if path.extension().is_some_and(|ext| ext == "rs") {
            out.push(path);
        }
    }
}

fn main() {
    let mut files = Vec::new();
    rust_files(Path::new("../renderer/src"), &mut files);
    rust_files(Path::new("src/manifest"), &mut files);
    files.push(PathBuf::from("src/scenes.rs"));
    files.sort();
    let mut hasher = Sha256::new();
    for file in &files {
        let bytes = std::fs::read(file).unwrap_or_default();
        hasher.update(file.to_string_lossy().as_bytes());
        hasher.update((bytes.len() as u64).to_le_bytes());
        hasher.update(&bytes);
    }
    // A folder is scanned whole, so added files count too.
    for watched in ["../renderer/src", "src/scenes.rs", "src/manifest"] {
        println!("cargo::rerun-if-changed={watched}");
    }
    let digest: String = hasher.finalize().iter().map(|b| format!("{b:02x}")).collect();
    println!("cargo::rustc-env=AABENCH_RENDER_SOURCE_SHA256={digest}");
}
