//! The ground truth every mode is measured against: the brute-force reference at 8×8 samples
//! per pixel, more than any mode takes, with reference-MxM's shaders and texture-footprint rule.
//! It is rendered untimed, tile by tile, and cached on disk under a key of everything that
//! determines it, so a nightly run pays for it once per change of scene.

use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Duration;

use aabench_renderer::scene::Camera;
use aabench_renderer::{DisplayImage, PlatformInfo, Truth, shaders};
use sha2::{Digest, Sha256};

use crate::files::images;
use crate::plan::inputs::{SceneInputs, hex};
use crate::run::worker::Worker;

/// Samples per pixel side of the truth.
pub const TRUTH_M: u32 = 8;
/// The truth's name wherever a mode id would stand (`vs_ground_truth.against`, file names).
pub const TRUTH_ID: &str = "truth-8x8";
/// The most bytes of render targets one truth tile may take: 1024×768 at 8×8 needs 1.8 GB of
/// targets in one piece, 14 bands of 130 MB in tiles. A signal waits for the tile under way
/// (the shadowed room's take 1.7 s each at 1024×768 on 2 cores, about twice that beside
/// another job); the quick tier's 256×192 is one piece.
pub const TILE_BYTES: u64 = 128 << 20;

/// SHA-256 over what determines the truth image: the aabench version and the source code that
/// renders (the renderer crate and the runner's scene set-up, fingerprinted by build.rs), the
/// truth's sample count, the resolution, the scene's input files, the shaders as compiled
/// (`AABENCH_SHADER_DIR` included), and the driver and build profile that render it (lavapipe
/// gives the same bits on every machine with the same Mesa, so the CPU model is left out).
pub fn cache_key(
    inputs: &SceneInputs,
    resolution: [u32; 2],
    platform: &PlatformInfo,
) -> anyhow::Result<String> {
    let mut hasher = Sha256::new();
    let mut add = |part: &str| {
        hasher.update((part.len() as u64).to_le_bytes());
        hasher.update(part.as_bytes());
    };
    add("aabench.truth/1");
    add(env!("CARGO_PKG_VERSION"));
    add(env!("AABENCH_RENDER_SOURCE_SHA256"));
    add(&format!("{TRUTH_M} {}x{}", resolution[0], resolution[1]));
    // Tiles differ from one piece by flipped samples; a truth in one piece keeps its old key.
    if !aabench_renderer::truth_in_one_piece(resolution[0], resolution[1], TRUTH_M, TILE_BYTES) {
        add(&format!("tiles within {TILE_BYTES} bytes"));
    }
    add(&inputs.manifest_sha256);
    add(&inputs.gltf_sha256);
    for file in shaders::pass_files() {
        for features in shaders::Features::combinations() {
            add(&shaders::compose(file, features)?);
        }
    }
    add(&platform.adapter);
    add(&platform.driver_info);
    add(&platform.build_profile);
    Ok(hex(&hasher.finalize()))
}

/// The key of the truth at one frame of a camera path: the still truth's key (everything but
/// the camera and the pose; the manifest, which picks the animation, among it) with the frame's
/// camera and, where an animation plays, its time added.
pub fn frame_key(still_key: &str, camera: &Camera, animation_time: Option<f64>) -> String {
    let mut hasher = Sha256::new();
    hasher.update(b"aabench.truth-frame/1");
    hasher.update(still_key.as_bytes());
    let vectors = [camera.position, camera.forward, camera.up];
    for value in vectors.iter().flat_map(|v| v.to_array()).chain([camera.fov_y, camera.near, camera.far]) {
        hasher.update(value.to_le_bytes());
    }
    // Absent adds nothing, so that the keys of paths without an animation stay as they were.
    if let Some(time) = animation_time {
        hasher.update(b"animation time");
        hasher.update(time.to_le_bytes());
    }
    hex(&hasher.finalize())
}

/// `<dir>/<scene>-<w>x<h>-<first 16 hex digits of the key>.png`
pub fn cache_file(dir: &Path, scene: &str, resolution: [u32; 2], key: &str) -> PathBuf {
    dir.join(format!("{scene}-{}x{}-{}.png", resolution[0], resolution[1], &key[..16]))
}

/// The cached display image, or `None` when it is missing, unreadable, of another size or of
/// another bit depth: then it is rendered again.
pub fn load_cached(path: &Path, resolution: [u32; 2], bits: u32) -> Option<DisplayImage> {
    let (width, height, image) = images::read_display_png(path, bits)?;
    ([width, height] == resolution).then_some(image)
}

/// Writes the display image to the cache (atomically).
/// Renders the truth at the worker's current camera, stopping between tiles once `cancel` is
/// set, and caches its display image in `cache`. Returns the truth and, where the cache could
/// not be written, why (a warning: the run goes on).
pub async fn render_and_store(
    worker: &mut Worker,
    timeout: Duration,
    cache: &Path,
    resolution: [u32; 2],
    cancel: Arc<AtomicBool>,
) -> Result<(Truth, Option<String>), String> {
    let truth = worker
        .call(timeout, move |state| {
            let stop = || cancel.load(Ordering::SeqCst);
            let renderer = state.renderer.as_mut().expect("an uploaded scene");
            renderer.render_truth_until(TRUTH_M, TILE_BYTES, &stop)
        })
        .await
        .map_err(|e| e.to_string())?
        .map_err(|e| e.to_string())?;
    let not_cached = store(cache, resolution, &truth.images.display).err().map(|e| format!("{e:#}"));
    Ok((truth, not_cached))
}

pub fn store(path: &Path, resolution: [u32; 2], image: &DisplayImage) -> anyhow::Result<()> {
    if let Some(dir) = path.parent() {
        std::fs::create_dir_all(dir).map_err(|e| anyhow::anyhow!("{}: {e}", dir.display()))?;
    }
    images::write_display_png(path, resolution[0], resolution[1], image)
}

/// The process's peak resident set, which Linux lets a process reset: reset it before a
/// render, read it after, and the peak is the render's (with what was resident before it).
pub mod peak_memory {
    /// Resets the peak to the current resident set. Returns false where that is unsupported.
    pub fn reset() -> bool {
        std::fs::write("/proc/self/clear_refs", "5").is_ok()
    }

    /// `VmHWM` of /proc/self/status, in bytes.
    pub fn read() -> Option<u64> {
        let status = std::fs::read_to_string("/proc/self/status").ok()?;
        let line = status.lines().find(|line| line.starts_with("VmHWM:"))?;
        let kib: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
        Some(kib * 1024)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn platform() -> PlatformInfo {
        PlatformInfo {
            adapter: "llvmpipe".into(),
            driver: "llvmpipe".into(),
            driver_info: "Mesa 22.3.6".into(),
            backend: "vulkan".into(),
            device_type: "cpu".into(),
            lp_num_threads: None,
            cpu_model: "AMD EPYC".into(),
            cpu_cores: 2,
            cpu_fma: Some(true),
            build_profile: "release".into(),
        }
    }

    #[test]
    fn the_key_follows_inputs_resolution_and_driver_but_not_the_cpu() {
        let inputs = SceneInputs { manifest_sha256: "a".into(), gltf_sha256: "b".into() };
        let key = |inputs: &SceneInputs, resolution, platform: &PlatformInfo| {
            cache_key(inputs, resolution, platform).unwrap()
        };
        let base = key(&inputs, [64, 48], &platform());
        assert_eq!(base, key(&inputs, [64, 48], &platform()), "deterministic");
        assert_ne!(base, key(&inputs, [64, 49], &platform()));
        let edited = SceneInputs { gltf_sha256: "c".into(), ..inputs.clone() };
        assert_ne!(base, key(&edited, [64, 48], &platform()));
        let other_mesa = PlatformInfo { driver_info: "Mesa 24.0".into(), ..platform() };
        assert_ne!(base, key(&inputs, [64, 48], &other_mesa));
        let other_cpu = PlatformInfo { cpu_model: "Intel Xeon".into(), cpu_cores: 8, ..platform() };
        assert_eq!(base, key(&inputs, [64, 48], &other_cpu));
    }

    #[test]
    fn a_corrupt_or_resized_cache_file_is_a_miss() {
        let dir = std::env::temp_dir().join(format!("aabench-truth-{}", std::process::id()));
        let path = cache_file(&dir, "edge", [2, 1], "0123456789abcdef0123");
        assert!(path.ends_with("edge-2x1-0123456789abcdef.png"));
        assert_eq!(load_cached(&path, [2, 1], 8), None, "missing");
        let image = DisplayImage::from_rgba8(&[1, 2, 3, 255, 4, 5, 6, 255]);
        store(&path, [2, 1], &image).unwrap();
        assert_eq!(load_cached(&path, [2, 1], 8), Some(image));
        assert_eq!(load_cached(&path, [1, 2], 8), None, "another size");
        assert_eq!(load_cached(&path, [2, 1], 10), None, "another bit depth");
        std::fs::write(&path, b"\x89PNG truncated").unwrap();
        assert_eq!(load_cached(&path, [2, 1], 8), None, "corrupt");
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn peak_memory_is_read_and_reset() {
        // A 256 MiB peak, touched and freed: far above what the tests running beside this one
        // allocate between the calls below.
        let big = vec![1u8; 256 << 20];
        assert_eq!(std::hint::black_box(&big)[12345], 1);
        drop(big);
        let peak = peak_memory::read().expect("Linux reports VmHWM");
        assert!(peak > 256 << 20, "{peak}");
        if peak_memory::reset() {
            assert!(peak_memory::read().unwrap() < peak - (128 << 20), "the reset forgets the old peak");
        }
    }
}
