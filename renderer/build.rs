//! Embeds every file under `shaders/` into `shaders::SOURCES`: a new shader is a new file and
//! nothing more.

use std::path::{Path, PathBuf};

/// The `.wgsl` files under `dir`, as paths relative to `root` with `/` between folders.
fn wgsl_files(root: &Path, dir: &Path, out: &mut Vec<String>) {
    let entries = std::fs::read_dir(dir).unwrap_or_else(|e| panic!("{}: {e}", dir.display()));
    for entry in entries {
        let path = entry.unwrap_or_else(|e| panic!("{}: {e}", dir.display())).path();
        if path.is_dir() {
            wgsl_files(root, &path, out);
        } else if path.extension().is_some_and(|ext| ext == "wgsl") {
            let relative = path.strip_prefix(root).expect("under the root");
            let parts: Vec<String> =
                relative.components().map(|c| c.as_os_str().to_string_lossy().into_owned()).collect();
            out.push(parts.join("/"));
        }
    }
}

fn main() {
    let root = PathBuf::from(std::env::var("CARGO_MANIFEST_DIR").expect("cargo sets it")).join("../shaders");
    let mut files = Vec::new();
    wgsl_files(&root, &root, &mut files);
    files.sort();
    let entries: String = files
        .iter()
        .map(|name| format!("    ({name:?}, include_str!({:?})),\n", root.join(name).display().to_string()))
        .collect();
    let out = PathBuf::from(std::env::var("OUT_DIR").expect("cargo sets it")).join("shaders.rs");
    std::fs::write(&out, format!("&[\n{entries}]\n")).unwrap_or_else(|e| panic!("{}: {e}", out.display()));
    // A folder is scanned whole, so added files count too.
    println!("cargo::rerun-if-changed=../shaders");
}
