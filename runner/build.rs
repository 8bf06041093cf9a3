//! Fingerprints the source code that decides a rendered image, for the ground truth's cache key:
//! the renderer crate and the runner's scene set-up (manifest defaults, camera and lights).
//! Shaders are hashed at run time as composed, so `AABENCH_SHADER_DIR` is covered too. And the
//! build's identity, which runs record: all of the source (ColorVideoVDP's with its tables
//! included), the shaders and the lock file.

use std::path::{Path, PathBuf};

use sha2::{Digest, Sha256};

/// Every file under `dir` (recursively) that `keep` accepts.
fn files_under(dir: &Path, keep: fn(&Path) -> bool, out: &mut Vec<PathBuf>) {
    let Ok(entries) = std::fs::read_dir(dir) else { return };
    for entry in entries.flatten() {
        let path = entry.path();
        if path.is_dir() {
            files_under(&path, keep, out);
        } else if keep(&path) {
            out.push(path);
        }
    }
}

fn rust(path: &Path) -> bool {
    path.extension().is_some_and(|ext| ext == "rs")
}

/// SHA-256 over the files' names, lengths and bytes, in name order, as hex.
fn digest(mut files: Vec<PathBuf>) -> String {
    files.sort();
    let mut hasher = Sha256::new();
    for file in &files {
        let bytes = std::fs::read(file).unwrap_or_default();
        hasher.update(file.to_string_lossy().as_bytes());
        hasher.update((bytes.len() as u64).to_le_bytes());
        hasher.update(&bytes);
    }
    hasher.finalize().iter().map(|b| format!("{b:02x}")).collect()
}

fn main() {
    let mut render = Vec::new();
    files_under(Path::new("../renderer/src"), rust, &mut render);
    files_under(Path::new("src/manifest"), rust, &mut render);
    render.push(PathBuf::from("src/run/scenes.rs"));
    // The build's identity, recorded in every run: everything that renders and measures (the
    // crates' source, ColorVideoVDP's tables, the shaders, the lock file). Runs of one build
    // pool; runs of two do not.
    let mut build = Vec::new();
    files_under(Path::new("../renderer/src"), rust, &mut build);
    files_under(Path::new("src"), rust, &mut build);
    files_under(Path::new("../cvvdp/src"), rust, &mut build);
    files_under(Path::new("../cvvdp/data"), |_| true, &mut build);
    files_under(Path::new("../shaders"), |_| true, &mut build);
    build.push(PathBuf::from("../Cargo.lock"));
    // A folder is scanned whole, so added files count too.
    for watched in ["../renderer/src", "src", "../cvvdp/src", "../cvvdp/data", "../shaders", "../Cargo.lock"]
    {
        println!("cargo::rerun-if-changed={watched}");
    }
    println!("cargo::rustc-env=AABENCH_RENDER_SOURCE_SHA256={}", digest(render));
    println!("cargo::rustc-env=AABENCH_BUILD_SHA256={}", digest(build));
}
