//! Shared by the renderer's integration tests: one device, generated scenes, one-call renders.

#![allow(dead_code)]

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::sync::{Arc, Mutex, MutexGuard, OnceLock};

use aabench_renderer::scene::animation::Track;
use aabench_renderer::scene::generate::Generator;
use aabench_renderer::scene::{Camera, Light, LightKind, Lighting, Scene, load_gltf};
use aabench_renderer::{
    AdaptiveSettings, ColorSettings, FrameImages, Gpu, Mode, RenderSettings, SceneRenderer,
};
use glam::{DVec2, DVec3, DVec4, Vec3};
use serde_json::{Value, json};

/// One device for the whole test binary, and a lock so that tests render one at a time:
/// lavapipe already uses every core.
pub fn gpu() -> (Arc<Gpu>, MutexGuard<'static, ()>) {
    static GPU: OnceLock<Arc<Gpu>> = OnceLock::new();
    static LOCK: Mutex<()> = Mutex::new(());
    let guard = LOCK.lock().unwrap_or_else(|poisoned| poisoned.into_inner());
    let gpu = GPU.get_or_init(|| Arc::new(Gpu::new().expect("a Vulkan adapter (lavapipe)")));
    (Arc::clone(gpu), guard)
}

/// Generates a scene, writes it as GLB into a temporary folder, imports it through glTF and
/// removes the folder. Each generator runs once per test binary; later calls get a copy.
pub fn generated(generator: Generator) -> (Scene, Camera) {
    static SCENES: Mutex<BTreeMap<String, (Scene, Camera)>> = Mutex::new(BTreeMap::new());
    let mut scenes = SCENES.lock().unwrap_or_else(|poisoned| poisoned.into_inner());
    let entry = scenes.entry(generator.to_string()).or_insert_with(|| {
        let dir =
            std::env::temp_dir().join(format!("aabench-renderer-tests-{}-{generator}", std::process::id()));
        let path: PathBuf = dir.join(format!("{generator}.glb"));
        generator.write(1, &path).expect("write generated scene");
        let scene = load_gltf(&path).expect("import generated scene");
        let _ = std::fs::remove_dir_all(&dir);
        let mut camera = scene.camera.expect("generated scenes carry a camera");
        if !camera.far.is_finite() {
            camera.far = 500.0;
        }
        (scene, camera)
    });
    entry.clone()
}

/// The `crossing` scene with its animation playing, a renderer of it under [`lit`] at `width` ×
/// `height`, the crate's translation track, and the material indices (as the G-buffer stores
/// them) of the crate and its bars, which that track moves.
pub fn crossing_playing(
    width: u32,
    height: u32,
) -> (SceneRenderer, Camera, Track, Vec<f32>, MutexGuard<'static, ()>) {
    let (gpu, guard) = gpu();
    let (mut scene, camera) = generated(Generator::Crossing);
    let index = scene.animations.iter().position(|a| a.name.as_deref() == Some("crossing")).unwrap();
    scene.play(&[index]).unwrap();
    let track = scene.animations[index].tracks.as_ref().unwrap()[0].clone();
    let moving: Vec<f32> = (scene.materials.iter().enumerate())
        .filter(|(_, m)| m.name == "crate" || m.name == "bars")
        .map(|(i, _)| i as f32)
        .collect();
    assert_eq!(moving.len(), 2, "the crate's two materials");
    let renderer = SceneRenderer::new(gpu, &scene, &camera, &lit(), settings(width, height)).unwrap();
    (renderer, camera, track, moving, guard)
}

/// Ambient light only: every surface shows exactly ambient × albedo.
pub fn ambient_only() -> Lighting {
    Lighting { lights: Vec::new(), ambient: Vec3::ONE, background: Vec3::new(0.2, 0.3, 0.5), exposure: 1.0 }
}

/// A few point lights around the camera.
pub fn lit() -> Lighting {
    let light = |position: Vec3, color: Vec3| Light {
        kind: LightKind::Point,
        position,
        color,
        intensity: 12.0,
        range: 30.0,
        shadow: None,
    };
    Lighting {
        lights: vec![
            light(Vec3::new(2.0, 3.0, 3.0), Vec3::new(1.0, 0.9, 0.8)),
            light(Vec3::new(-3.0, 2.0, 1.0), Vec3::new(0.4, 0.6, 1.0)),
        ],
        ambient: Vec3::splat(0.05),
        background: Vec3::new(0.2, 0.3, 0.5),
        exposure: 1.0,
    }
}

pub fn settings(width: u32, height: u32) -> RenderSettings {
    // Exposure, clamp and sRGB without dither: colours that tests can predict exactly. The
    // colour pipeline's own tests (colour.rs) set theirs.
    RenderSettings {
        width,
        height,
        stall_iterations: 64,
        adaptive: AdaptiveSettings::default(),
        color: ColorSettings::plain(),
    }
}

pub fn renderer(
    generator: Generator,
    lighting: &Lighting,
    settings: RenderSettings,
) -> (SceneRenderer, MutexGuard<'static, ()>) {
    let (gpu, guard) = gpu();
    let (scene, camera) = generated(generator);
    let renderer = SceneRenderer::new(gpu, &scene, &camera, lighting, settings).expect("scene upload");
    (renderer, guard)
}

pub fn render(renderer: &mut SceneRenderer, mode: &str) -> FrameImages {
    let mode: Mode = mode.parse().expect("mode id");
    let prepared = renderer.prepare(mode).expect("prepare mode");
    prepared.render().expect("render frame");
    prepared.read_images().expect("read images")
}

/// Distinct display colours (RGB) of an image.
pub fn colours(image: &FrameImages) -> std::collections::BTreeSet<[u8; 3]> {
    image.display.bytes().chunks_exact(4).map(|p| [p[0], p[1], p[2]]).collect()
}

/// Largest per-channel difference between two display images, in code steps.
pub fn max_step(a: &FrameImages, b: &FrameImages) -> u16 {
    a.display.rgba.iter().zip(&b.display.rgba).map(|(x, y)| x.abs_diff(*y)).max().unwrap_or(0)
}

/// Where a world point lands through `camera` in a `size` frame, in pixels (y down), and its
/// linear view depth: the CPU twin of the shaders' projection, in f64.
pub fn project(camera: &Camera, size: DVec2, point: DVec3) -> (DVec2, f64) {
    let clip = camera.projection(size.x / size.y) * camera.view() * point.extend(1.0);
    let ndc = DVec2::new(clip.x, clip.y) / clip.w;
    (DVec2::new((ndc.x + 1.0) / 2.0 * size.x, (1.0 - ndc.y) / 2.0 * size.y), clip.w)
}

/// The world point seen at `pixel` (a frame position in pixels) at linear view depth `depth`.
pub fn unproject(camera: &Camera, size: DVec2, pixel: DVec2, depth: f64) -> DVec3 {
    let ndc = DVec2::new(pixel.x / size.x * 2.0 - 1.0, 1.0 - pixel.y / size.y * 2.0);
    let tan_y = (camera.fov_y * 0.5).tan();
    let ray = DVec3::new(ndc.x * tan_y * size.x / size.y, ndc.y * tan_y, -1.0);
    (camera.view().inverse() * DVec4::from((ray * depth, 1.0))).truncate()
}

/// The `thin` scene under [`lit`] at `width` × `height`, with its camera.
pub fn thin_renderer(width: u32, height: u32) -> (SceneRenderer, Camera, MutexGuard<'static, ()>) {
    let (gpu, guard) = gpu();
    let (scene, camera) = generated(Generator::Thin);
    let renderer =
        SceneRenderer::new(gpu, &scene, &camera, &lit(), settings(width, height)).expect("scene upload");
    (renderer, camera, guard)
}

/// A folder with one triangle's positions in `tri.bin` (36 bytes) and glTF files written into it.
#[derive(Debug)]
pub struct Folder {
    pub dir: PathBuf,
}

impl Folder {
    pub fn new(name: &str) -> Folder {
        let dir = std::env::temp_dir().join(format!("aabench-import-{name}-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).unwrap();
        let positions: [f32; 9] = [0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0];
        std::fs::write(dir.join("tri.bin"), bytemuck::cast_slice(&positions)).unwrap();
        Folder { dir }
    }

    /// A document of one triangle mesh and `nodes`, with `edit` applied; returns its path.
    pub fn gltf(&self, name: &str, nodes: Value, edit: impl Fn(&mut Value)) -> PathBuf {
        let mut document = json!({
            "asset": { "version": "2.0" },
            "buffers": [{ "uri": "tri.bin", "byteLength": 36 }],
            "bufferViews": [{ "buffer": 0, "byteLength": 36 }],
            "accessors": [{
                "bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3",
                "min": [0, 0, 0], "max": [1, 1, 0]
            }],
            "meshes": [{ "primitives": [{ "attributes": { "POSITION": 0 } }] }],
            "nodes": nodes,
            "scenes": [{ "nodes": [0] }],
            "scene": 0
        });
        edit(&mut document);
        let path = self.dir.join(name);
        std::fs::write(&path, serde_json::to_vec(&document).unwrap()).unwrap();
        path
    }

    pub fn one_node(&self, name: &str, edit: impl Fn(&mut Value)) -> PathBuf {
        self.gltf(name, json!([{ "mesh": 0 }]), edit)
    }
}

impl Drop for Folder {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.dir);
    }
}

pub fn error(path: &Path) -> String {
    let message = load_gltf(path).expect_err("the file is broken").to_string();
    assert!(message.contains(&path.display().to_string()), "the error names the file: {message}");
    message
}
