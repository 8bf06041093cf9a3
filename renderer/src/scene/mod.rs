//! The CPU scene: what a glTF file holds once imported, plus the lights and camera that a
//! manifest adds. Generated scenes are written as glTF and read back through the same importer,
//! so there is one path for generated scenes and users' own files.

mod camera;
pub mod generate;
mod import;
pub mod shadow;
mod upload;
pub mod write;

pub use camera::{Camera, CameraError, FrameUniforms, MAX_COORDINATE, Tile};
pub use import::{MAX_TEXTURE_SIDE, escapes, load_gltf, percent_decode, read_generator, regular_file};
pub use shadow::{MAX_SHADOW_LIGHTS, Shadow, ShadowCubes};
pub use upload::{GpuScene, LIGHT_DIRECTIONAL, LIGHT_POINT, LIGHT_SPOT, MAX_LIGHTS};

use glam::Vec3;

/// One vertex as the G-buffer pass reads it: world space, baked node transforms.
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct Vertex {
    pub position: [f32; 3],
    pub normal: [f32; 3],
    pub uv: [f32; 2],
    pub material: u32,
}

/// How a material treats alpha. BLEND is rendered as opaque: a deferred renderer has no
/// place for it, and none of the scenes this tool measures rely on it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum AlphaMode {
    Opaque,
    /// Fragments whose alpha is below the cutoff are discarded in the G-buffer pass.
    Mask {
        cutoff: f32,
    },
}

/// How the G-buffer pass draws a triangle: alpha-tested or not, back faces culled or not.
/// Each class has its own pipeline; the importer sorts triangles by class.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct DrawClass {
    pub masked: bool,
    pub double_sided: bool,
}

impl DrawClass {
    /// Every class, in drawing order: opaque before masked (masked fragments discard and so
    /// lose early depth testing; opaque depth in place first rejects more of them).
    pub const ALL: [DrawClass; 4] = [
        DrawClass { masked: false, double_sided: false },
        DrawClass { masked: false, double_sided: true },
        DrawClass { masked: true, double_sided: false },
        DrawClass { masked: true, double_sided: true },
    ];
}

#[derive(Debug, Clone, PartialEq)]
pub struct Material {
    pub name: String,
    /// Linear RGBA factor, multiplied with the texture.
    pub base_color: [f32; 4],
    pub metallic: f32,
    pub roughness: f32,
    /// Index into [`Scene::textures`] of the base-colour texture.
    pub texture: Option<usize>,
    pub alpha: AlphaMode,
    /// Without it, back faces are culled.
    pub double_sided: bool,
}

impl Material {
    pub fn draw_class(&self) -> DrawClass {
        DrawClass { masked: matches!(self.alpha, AlphaMode::Mask { .. }), double_sided: self.double_sided }
    }
}

/// An sRGB-encoded RGBA8 image, as decoded from the file.
#[derive(Debug, Clone, PartialEq)]
pub struct Texture {
    pub width: u32,
    pub height: u32,
    pub rgba: Vec<u8>,
}

/// A light, from the manifest or from the file's `KHR_lights_punctual`. Intensities are in
/// the extension's photometric units: candela for point and spot lights (the illuminance at
/// distance d is intensity / d²), lux for directional ones.
#[derive(Debug, Clone, PartialEq)]
pub struct Light {
    pub kind: LightKind,
    /// Unused by directional lights.
    pub position: Vec3,
    pub color: Vec3,
    pub intensity: f32,
    /// Distance at which the light's contribution fades to zero; also the far plane of its
    /// shadow cube. Unused by directional lights.
    pub range: f32,
    /// An omnidirectional shadow, when the light casts one (point lights only).
    pub shadow: Option<Shadow>,
}

impl Light {
    /// The light's shadow cube settings: only point lights cast (omnidirectional) shadows.
    pub fn cube(&self) -> Option<&Shadow> {
        self.shadow.as_ref().filter(|_| self.kind == LightKind::Point)
    }
}

/// Checks a light's values the same way whichever file they come from (a manifest, a glTF
/// file's `KHR_lights_punctual`): a finite position within ±[`MAX_COORDINATE`], a colour and
/// an intensity finite and ≥ 0, a range finite and > 0 (`None`: a glTF light that reaches
/// everywhere). On failure, the field and why.
pub fn check_light(
    position: glam::DVec3,
    color: [f32; 3],
    intensity: f32,
    range: Option<f32>,
) -> Result<(), (&'static str, String)> {
    if !(position.is_finite() && position.abs().max_element() <= MAX_COORDINATE) {
        return Err((
            "position",
            format!("{} must be finite and within ±{MAX_COORDINATE:e}", camera::vector(position)),
        ));
    }
    if !color.iter().all(|c| c.is_finite() && *c >= 0.0) {
        return Err(("color", "components must be finite and ≥ 0".into()));
    }
    if !(intensity.is_finite() && intensity >= 0.0) {
        return Err(("intensity", format!("{intensity} must be finite and ≥ 0")));
    }
    match range {
        Some(range) if !(range.is_finite() && range > 0.0) => {
            Err(("range", format!("{range} must be finite and > 0")))
        }
        _ => Ok(()),
    }
}

/// How a light spreads.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum LightKind {
    /// Equally in every direction from its position.
    Point,
    /// In a cone along `direction` (unit, pointing away from the light): full strength within
    /// `inner` radians of the axis, fading (smoothly, as KHR_lights_punctual defines) to zero at
    /// `outer`.
    Spot { direction: Vec3, inner: f32, outer: f32 },
    /// Parallel rays along `direction` (unit), as from the sun: no position, no falloff.
    Directional { direction: Vec3 },
}

/// Lighting and display settings that a manifest gives a scene.
#[derive(Debug, Clone, PartialEq)]
pub struct Lighting {
    pub lights: Vec<Light>,
    pub ambient: Vec3,
    /// Radiance where no geometry covers a sample.
    pub background: Vec3,
    /// Linear scale applied before display encoding.
    pub exposure: f32,
}

/// Geometry, materials and textures of an imported scene.
#[derive(Debug, Clone, Default)]
pub struct Scene {
    pub vertices: Vec<Vertex>,
    /// Triangle list, sorted by draw class.
    pub indices: Vec<u32>,
    /// The index range of each draw class present, in [`DrawClass::ALL`] order.
    pub draws: Vec<(DrawClass, std::ops::Range<u32>)>,
    pub materials: Vec<Material>,
    pub textures: Vec<Texture>,
    /// The first camera found in the node hierarchy, if any (relative to `origin`).
    pub camera: Option<Camera>,
    /// Where the scene's coordinates start, in the file's world space: vertices, bounds and
    /// the camera are relative to it, so geometry far from the file's origin keeps f32
    /// precision. Manifest cameras and lights are moved by it before rendering.
    pub origin: glam::DVec3,
    /// The `asset.generator` string of the file, used to tell stale generated files.
    pub generator: Option<String>,
    /// The file's `KHR_lights_punctual` lights, relative to `origin`.
    pub lights: Vec<Light>,
    /// What the file uses that aabench ignores (optional extensions), one line each.
    pub warnings: Vec<String>,
}

impl Scene {
    /// Whether any material samples a texture.
    pub fn is_textured(&self) -> bool {
        !self.textures.is_empty() && self.materials.iter().any(|m| m.texture.is_some())
    }

    pub fn triangle_count(&self) -> usize {
        self.indices.len() / 3
    }

    /// Axis-aligned bounds of all vertices; a zero box for an empty scene.
    pub fn bounds(&self) -> (Vec3, Vec3) {
        let mut positions = self.vertices.iter().map(|v| Vec3::from(v.position));
        let Some(first) = positions.next() else {
            return (Vec3::ZERO, Vec3::ZERO);
        };
        positions.fold((first, first), |(lo, hi), p| (lo.min(p), hi.max(p)))
    }
}
