//! What determines a scene's images, as SHA-256 content hashes: the manifest file, and the glTF
//! file together with the external buffers and images it names. Baselines record them, and the
//! ground-truth cache is keyed by them.

use std::path::{Path, PathBuf};

use crate::files::percent_decode;
use anyhow::Context;
use serde::{Deserialize, Serialize};
use sha2::{Digest, Sha256};

use crate::manifest::Manifest;

/// Content hashes of a scene's input files, hex-encoded.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct SceneInputs {
    pub manifest_sha256: String,
    /// The glTF file, then each external buffer and image in the order the file lists them.
    pub gltf_sha256: String,
}

impl SceneInputs {
    /// Hashes the manifest's file and its glTF file (which must exist: generate it first).
    pub fn of(manifest: &Manifest) -> anyhow::Result<SceneInputs> {
        let manifest_bytes = std::fs::read(&manifest.path)
            .with_context(|| format!("{}: cannot read", manifest.path.display()))?;
        Ok(SceneInputs {
            manifest_sha256: hex(&Sha256::digest(&manifest_bytes)),
            gltf_sha256: gltf_sha256(&manifest.gltf_path())?,
        })
    }
}

/// SHA-256 over the glTF file and its external resources. Each part enters as its length and
/// bytes, so moving bytes from one file to the next changes the hash.
pub fn gltf_sha256(path: &Path) -> anyhow::Result<String> {
    let bytes = std::fs::read(path).with_context(|| format!("{}: cannot read", path.display()))?;
    let mut hasher = Sha256::new();
    let mut add = |bytes: &[u8]| {
        hasher.update((bytes.len() as u64).to_le_bytes());
        hasher.update(bytes);
    };
    add(&bytes);
    for resource in external_resources(path, &bytes)? {
        let part = std::fs::read(&resource)
            .with_context(|| format!("{}: cannot read {}", path.display(), resource.display()))?;
        add(&part);
    }
    Ok(hex(&hasher.finalize()))
}

/// The files that a JSON glTF names in `buffers[].uri` and `images[].uri` (data URIs are part
/// of the file itself). A binary GLB may still name external files in its JSON chunk.
fn external_resources(path: &Path, bytes: &[u8]) -> anyhow::Result<Vec<PathBuf>> {
    let json = if bytes.starts_with(b"glTF") { glb_json_chunk(bytes) } else { Some(bytes) };
    let Some(json) = json else { return Ok(Vec::new()) };
    let Ok(document) = serde_json::from_slice::<serde_json::Value>(json) else {
        // Not JSON: the importer reports that with its own words.
        return Ok(Vec::new());
    };
    let folder = path.parent().unwrap_or(Path::new("."));
    let uris = ["buffers", "images"].into_iter().flat_map(|list| {
        document[list].as_array().into_iter().flatten().filter_map(|item| item["uri"].as_str())
    });
    uris.filter(|uri| !aabench_renderer::scene::is_data_uri(uri))
        .map(|uri| percent_decode(uri).map(|relative| folder.join(relative)))
        .collect::<Result<_, _>>()
        .map_err(|e| anyhow::anyhow!("{}: {e}", path.display()))
}

/// The JSON chunk of a GLB: a 12-byte header, then chunks of (length, type, data).
fn glb_json_chunk(bytes: &[u8]) -> Option<&[u8]> {
    let length = u32::from_le_bytes(bytes.get(12..16)?.try_into().ok()?) as usize;
    (bytes.get(16..20)? == b"JSON").then(|| bytes.get(20..20 + length)).flatten()
}

/// Lowercase hexadecimal.
pub fn hex(bytes: &[u8]) -> String {
    bytes.iter().map(|b| format!("{b:02x}")).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn external_buffers_and_images_are_part_of_the_hash() {
        let dir = std::env::temp_dir().join(format!("aabench-inputs-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let gltf = dir.join("scene.gltf");
        std::fs::write(
            &gltf,
            r#"{"buffers":[{"uri":"geo%20metry.bin","byteLength":4}],
                "images":[{"uri":"data:image/png;base64,AAAA"},{"uri":"albedo.png"}]}"#,
        )
        .unwrap();
        std::fs::write(dir.join("geo metry.bin"), [1, 2, 3, 4]).unwrap();
        std::fs::write(dir.join("albedo.png"), [9]).unwrap();
        let first = gltf_sha256(&gltf).unwrap();
        assert_eq!(first.len(), 64);
        std::fs::write(dir.join("albedo.png"), [8]).unwrap();
        let second = gltf_sha256(&gltf).unwrap();
        assert_ne!(first, second, "a changed image must change the hash");
        std::fs::remove_file(dir.join("geo metry.bin")).unwrap();
        let error = gltf_sha256(&gltf).unwrap_err().to_string();
        assert!(error.contains("geo metry.bin"), "{error}");
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
