//! The CPU scene: what a glTF file holds once imported, plus the lights and camera that a
//! manifest adds. Generated scenes are written as glTF and read back through the same importer,
//! so there is one path for generated scenes and users' own files.

pub mod animation;
mod camera;
pub mod generate;
mod import;
pub mod playing;
pub mod pose;
pub mod shadow;
pub mod skin;
pub mod textures;
mod upload;
pub mod write;

pub use camera::{Camera, CameraError, FrameUniforms, MAX_COORDINATE, Tile, number};
pub use import::{
    MAX_TEXTURE_SIDE, is_data_uri, load_gltf, percent_decode, read_generator, regular_file, shown,
};
pub use shadow::{MAX_SHADOW_LIGHTS, Shadow, ShadowCubes};
pub use upload::{
    GpuScene, LIGHT_DIRECTIONAL, LIGHT_POINT, LIGHT_SPOT, MAX_LIGHTS, MAX_MATERIALS, SLOT_BASE,
    SLOT_EMISSIVE, SLOT_METALLIC_ROUGHNESS, SLOT_NORMAL, SLOT_OCCLUSION,
};

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
    /// The base-colour texture (sRGB).
    pub texture: Option<TextureRef>,
    pub alpha: AlphaMode,
    /// Without it, back faces are culled.
    pub double_sided: bool,
    /// A tangent-space normal map (linear; glTF's +X right, +Y up), whose X and Y are scaled
    /// by `normal_scale`. Its vertices carry tangents ([`Scene::tangents`]).
    pub normal_texture: Option<TextureRef>,
    pub normal_scale: f32,
    /// Emitted radiance: `emissiveFactor` times `KHR_materials_emissive_strength`, in the
    /// renderer's units (those of a light's colour × intensity), times the texture (sRGB).
    pub emissive: [f32; 3],
    pub emissive_texture: Option<TextureRef>,
    /// Ambient occlusion in the texture's red channel (linear): ambient light is scaled by
    /// `1 + occlusion_strength · (occlusion − 1)`.
    pub occlusion_texture: Option<TextureRef>,
    pub occlusion_strength: f32,
    /// Roughness in green and metalness in blue (linear), multiplying the factors.
    pub metallic_roughness_texture: Option<TextureRef>,
}

impl Default for Material {
    /// glTF's defaults: white, fully metallic and rough, opaque, no textures.
    fn default() -> Material {
        Material {
            name: String::new(),
            base_color: [1.0; 4],
            metallic: 1.0,
            roughness: 1.0,
            texture: None,
            alpha: AlphaMode::Opaque,
            double_sided: false,
            normal_texture: None,
            normal_scale: 1.0,
            emissive: [0.0; 3],
            emissive_texture: None,
            occlusion_texture: None,
            occlusion_strength: 1.0,
            metallic_roughness_texture: None,
        }
    }
}

/// A texture as one material slot uses it: which texture, through which UV transform.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TextureRef {
    /// Index into [`Scene::textures`].
    pub texture: usize,
    pub transform: UvTransform,
}

/// `KHR_texture_transform`: uv′ = offset + R(−rotation) · (scale ⊙ uv), stored as the two rows
/// of a 2×3 affine matrix (u′ = row₀ · (u, v, 1), v′ = row₁ · (u, v, 1)).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct UvTransform {
    pub rows: [[f32; 3]; 2],
}

impl UvTransform {
    pub const IDENTITY: UvTransform = UvTransform { rows: [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0]] };

    /// The extension's translation · rotation · scale: u′ = cos r · sx·u + sin r · sy·v + ox,
    /// v′ = −sin r · sx·u + cos r · sy·v + oy. The extension's GLSL sketch, read with GLSL's
    /// column-major constructors, turns the other way; Khronos' TextureTransformTest sample
    /// (its green markers) and the viewers agree on this one (`docs/own-scene.md`).
    pub fn new(offset: [f32; 2], rotation: f32, scale: [f32; 2]) -> UvTransform {
        let (sin, cos) = rotation.sin_cos();
        UvTransform {
            rows: [[cos * scale[0], sin * scale[1], offset[0]], [-sin * scale[0], cos * scale[1], offset[1]]],
        }
    }

    pub fn apply(&self, uv: [f32; 2]) -> [f32; 2] {
        self.rows.map(|row| row[0] * uv[0] + row[1] * uv[1] + row[2])
    }

    pub fn is_identity(&self) -> bool {
        *self == UvTransform::IDENTITY
    }
}

impl Material {
    /// The textures the material samples, each with its UV transform.
    pub fn textures(&self) -> impl Iterator<Item = &TextureRef> {
        [
            &self.texture,
            &self.normal_texture,
            &self.emissive_texture,
            &self.occlusion_texture,
            &self.metallic_roughness_texture,
        ]
        .into_iter()
        .flatten()
    }

    pub fn draw_class(&self) -> DrawClass {
        DrawClass { masked: matches!(self.alpha, AlphaMode::Mask { .. }), double_sided: self.double_sided }
    }
}

/// An RGBA8 image, as decoded from the file.
#[derive(Debug, Clone, PartialEq)]
pub struct Texture {
    pub width: u32,
    pub height: u32,
    pub rgba: Vec<u8>,
    pub encoding: Encoding,
}

/// What a texture's values mean, which decides how its mipmaps average them.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Encoding {
    /// Colour (base colour, emission): sRGB-encoded, averaged in linear light.
    Srgb,
    /// Data (normals, occlusion, metallic-roughness): linear values, averaged as they are.
    Linear,
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
    /// One tangent per vertex (xyz unit, w = ±1: the bitangent is w · normal × tangent) when
    /// a material has a normal map, else empty. Zero for vertices that need none.
    pub tangents: Vec<[f32; 4]>,
    /// The first camera found in the node hierarchy, if any (relative to `origin`).
    pub camera: Option<Camera>,
    /// The glTF node that holds `camera`, which an animation can move.
    pub camera_node: Option<usize>,
    /// The `aspectRatio` that `camera` declares, with its index in `cameras`: aabench renders at
    /// the manifest's resolution and keeps the vertical field of view.
    pub camera_aspect: Option<(usize, f64)>,
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
    /// The file's animations, each playable or with the reason it is not.
    pub animations: Vec<animation::Animation>,
    /// The node trees the animations move, with the vertices each node's meshes gave.
    pub rig: animation::Rig,
    /// The animations that frames play ([`Scene::play`]); none leaves every node at rest.
    pub playing: Option<playing::Playing>,
}

impl Scene {
    /// The tracks of the animations that play, if any do.
    pub fn playing_tracks(&self) -> Option<&[animation::Track]> {
        self.playing.as_ref().map(|playing| playing.tracks.as_slice())
    }

    /// Whether any material samples a texture.
    pub fn is_textured(&self) -> bool {
        !self.textures.is_empty() && self.materials.iter().any(|m| m.textures().next().is_some())
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
