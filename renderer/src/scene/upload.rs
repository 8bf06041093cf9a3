//! Uploading a scene: geometry buffers (tangents in a second vertex buffer), material and
//! light tables, the textures (scene/textures.rs), the shadow cubes' face matrices, and the
//! named resources that shaders bind from the scene.

use std::ops::Range;

use bytemuck::Zeroable;
use wgpu::util::DeviceExt;

use super::shadow::{self, MAX_SHADOW_LIGHTS, ShadowCubes};
use super::textures;
use super::{AlphaMode, DrawClass, FrameUniforms, Light, LightKind, Lighting, Scene, TextureRef};
use crate::bindings::Bound;

/// Lights a scene may have: the size of the shaders' uniform light table.
pub const MAX_LIGHTS: usize = 64;

/// Materials a scene may have: the G-buffer stores the material index in the w of an f16
/// normal target, where integers are exact up to 2048.
pub const MAX_MATERIALS: usize = 2048;

/// `Material` in `shaders/lib/scene.wgsl`.
#[repr(C)]
#[derive(Debug, Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct GpuMaterial {
    base_color: [f32; 4],
    metallic: f32,
    roughness: f32,
    texture: i32,
    alpha_cutoff: f32,
    emissive: [f32; 3],
    emissive_texture: i32,
    normal_texture: i32,
    normal_scale: f32,
    occlusion_texture: i32,
    occlusion_strength: f32,
    metallic_roughness_texture: i32,
    padding: [i32; 3],
    /// The rows of each slot's UV transform ([`SLOT_BASE`] …), padded to 16 bytes.
    transforms: [[[f32; 4]; 2]; SLOTS],
}

// The storage array's stride in `shaders/lib/scene.wgsl`.
const _: () = assert!(std::mem::size_of::<GpuMaterial>() == 240);

/// `SLOT_*` in `shaders/lib/scene.wgsl`: a material's texture slots.
pub const SLOT_BASE: usize = 0;
pub const SLOT_NORMAL: usize = 1;
pub const SLOT_EMISSIVE: usize = 2;
pub const SLOT_OCCLUSION: usize = 3;
pub const SLOT_METALLIC_ROUGHNESS: usize = 4;
const SLOTS: usize = 5;

/// `Light` in `shaders/lib/scene.wgsl`.
#[repr(C)]
#[derive(Debug, Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct GpuLight {
    position: [f32; 3],
    range: f32,
    radiance: [f32; 3],
    /// The light's cube in the shadow cube array, or −1.
    shadow: i32,
    shadow_bias: f32,
    shadow_radius: f32,
    shadow_near: f32,
    /// [`LIGHT_POINT`], [`LIGHT_SPOT`] or [`LIGHT_DIRECTIONAL`].
    kind: u32,
    /// Spot and directional lights: the unit direction the light shines in.
    direction: [f32; 3],
    /// Spot lights: the cone's fade, `clamp(cos θ · scale + offset, 0, 1)²`.
    spot_scale: f32,
    spot_offset: f32,
    padding: [f32; 3],
}

// The uniform table's stride in `shaders/lib/scene.wgsl` (std140: 16-byte multiples).
const _: () = assert!(std::mem::size_of::<GpuLight>() == 80);

/// `LIGHT_*` in `shaders/lib/scene.wgsl`.
pub const LIGHT_POINT: u32 = 0;
pub const LIGHT_SPOT: u32 = 1;
pub const LIGHT_DIRECTIONAL: u32 = 2;

/// A light's kind, direction and cone as the shader reads them. The cone fade is
/// KHR_lights_punctual's: scale = 1 / max(0.001, cos inner − cos outer), offset = −cos outer ·
/// scale.
fn light_shape(kind: LightKind) -> (u32, [f32; 3], f32, f32) {
    match kind {
        LightKind::Point => (LIGHT_POINT, [0.0; 3], 0.0, 1.0),
        LightKind::Spot { direction, inner, outer } => {
            let scale = 1.0 / (inner.cos() - outer.cos()).max(0.001);
            (LIGHT_SPOT, direction.normalize_or_zero().to_array(), scale, -outer.cos() * scale)
        }
        LightKind::Directional { direction } => {
            (LIGHT_DIRECTIONAL, direction.normalize_or_zero().to_array(), 0.0, 1.0)
        }
    }
}

/// A scene on the device. Cheap to clone: wgpu handles are reference counted.
#[derive(Debug, Clone)]
pub struct GpuScene {
    pub(crate) vertices: wgpu::Buffer,
    /// One tangent per vertex, when a material has a normal map.
    tangents: Option<wgpu::Buffer>,
    /// Where each vertex lay in the frame before, when an animation plays (`MOVING`).
    previous: Option<wgpu::Buffer>,
    pub(crate) indices: wgpu::Buffer,
    pub(crate) draws: Vec<(DrawClass, Range<u32>)>,
    pub(crate) light_count: u32,
    /// The `Frame` uniform block.
    pub(crate) frame: wgpu::Buffer,
    materials: wgpu::Buffer,
    lights: wgpu::Buffer,
    /// The texture array and its sampler; none for an untextured scene.
    textures: Option<(wgpu::Texture, wgpu::Sampler)>,
    /// Each texture's layer and place in it, when textures share layers.
    texture_places: Option<wgpu::Buffer>,
    /// Face matrices of the shadow cubes and the sampler that reads them.
    shadow_faces: Option<(wgpu::Buffer, wgpu::Sampler)>,
    /// Bytes of the texture array, all mips included.
    pub texture_bytes: u64,
}

impl GpuScene {
    pub fn new(
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        scene: &Scene,
        lighting: &Lighting,
        frame: &FrameUniforms,
    ) -> GpuScene {
        let buffer = |label: &str, contents: &[u8], usage: wgpu::BufferUsages| {
            // Zero-sized bindings are invalid; an empty table still gets one zeroed entry.
            let padded;
            let contents = if contents.is_empty() {
                padded = vec![0u8; 32];
                &padded[..]
            } else {
                contents
            };
            device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some(label),
                contents,
                usage,
            })
        };
        let materials: Vec<GpuMaterial> = scene.materials.iter().map(gpu_material).collect();
        let lights = &lighting.lights[..lighting.lights.len().min(MAX_LIGHTS)];
        let shadows = ShadowCubes::of(lights);
        let (mut table, mut faces) = light_table(lights);
        // A fixed-size uniform array: unused entries stay zero.
        table.resize(MAX_LIGHTS, GpuLight::zeroed());
        let storage = wgpu::BufferUsages::STORAGE;
        let uniform = wgpu::BufferUsages::UNIFORM;
        // The shaders' table has room for every face of MAX_SHADOW_LIGHTS cubes.
        faces.resize(6 * MAX_SHADOW_LIGHTS, [[0.0; 4]; 4]);
        let shadow_faces = shadows.map(|_| {
            let sampler = device.create_sampler(&wgpu::SamplerDescriptor {
                label: Some("shadow cubes"),
                ..Default::default()
            });
            (buffer("shadow faces", bytemuck::cast_slice(&faces), uniform), sampler)
        });
        let layout = textures::Layout::of(&scene.textures);
        let textures = scene.is_textured().then(|| textures::upload(device, queue, &scene.textures, &layout));
        // Where each texture lies, for scenes whose textures share layers (`TEXTURE_PAGES`).
        let texture_places = (textures.is_some() && layout.is_packed())
            .then(|| buffer("texture places", bytemuck::cast_slice(&layout.gpu_places()), storage));
        // A playing animation rewrites the vertices of the nodes it moves every frame.
        let moving = scene.playing_tracks().is_some();
        let vertex = if moving {
            wgpu::BufferUsages::VERTEX | wgpu::BufferUsages::COPY_DST
        } else {
            wgpu::BufferUsages::VERTEX
        };
        let positions: Vec<[f32; 3]> = scene.vertices.iter().map(|v| v.position).collect();
        GpuScene {
            vertices: buffer("vertices", bytemuck::cast_slice(&scene.vertices), vertex),
            tangents: (!scene.tangents.is_empty())
                .then(|| buffer("tangents", bytemuck::cast_slice(&scene.tangents), vertex)),
            previous: moving.then(|| buffer("previous positions", bytemuck::cast_slice(&positions), vertex)),
            indices: buffer("indices", bytemuck::cast_slice(&scene.indices), wgpu::BufferUsages::INDEX),
            draws: scene.draws.clone(),
            light_count: lights.len() as u32,
            // Rewritten when the ground truth renders tile by tile.
            frame: buffer("frame", bytemuck::bytes_of(frame), uniform | wgpu::BufferUsages::COPY_DST),
            materials: buffer("materials", bytemuck::cast_slice(&materials), storage),
            lights: buffer("lights", bytemuck::cast_slice(&table), uniform),
            texture_bytes: if textures.is_some() { layout.bytes() } else { 0 },
            textures: textures.map(|array| (array, textures::sampler(device))),
            texture_places,
            shadow_faces,
        }
    }

    /// The same scene with its `Frame` uniforms in `frame`: a temporal mode's own.
    pub(crate) fn with_frame(&self, frame: wgpu::Buffer) -> GpuScene {
        GpuScene { frame, ..self.clone() }
    }

    /// The scene resource that shaders bind under `name`, if the scene has it.
    pub(crate) fn binding(&self, name: &str) -> Option<Bound> {
        let buffer = |b: &wgpu::Buffer| Some(Bound::Buffer(b.clone()));
        match name {
            "frame" => buffer(&self.frame),
            "materials" => buffer(&self.materials),
            "lights" => buffer(&self.lights),
            "scene_textures" => self.textures.as_ref().map(|(t, _)| Bound::Texture {
                texture: t.clone(),
                filterable: true,
                view_format: None,
            }),
            // The same array read as data: normal, occlusion and metallic-roughness textures are not sRGB.
            "scene_data_textures" => self.textures.as_ref().map(|(t, _)| Bound::Texture {
                texture: t.clone(),
                filterable: true,
                view_format: Some(wgpu::TextureFormat::Rgba8Unorm),
            }),
            "scene_sampler" => {
                self.textures.as_ref().map(|(_, s)| Bound::Sampler { sampler: s.clone(), filtering: true })
            }
            "texture_places" => self.texture_places.as_ref().and_then(buffer),
            "shadow_faces" => self.shadow_faces.as_ref().and_then(|(b, _)| buffer(b)),
            // Depth is read texel by texel: a filtering sampler would blend depths.
            "shadow_sampler" => self
                .shadow_faces
                .as_ref()
                .map(|(_, s)| Bound::Sampler { sampler: s.clone(), filtering: false }),
            _ => None,
        }
    }

    /// Moves the vertices of the nodes that `poser`'s animation moves to where they lie at
    /// `now` seconds, and their positions of the frame before to where they lay at `then`.
    pub(crate) fn write_pose(&self, queue: &wgpu::Queue, poser: &super::pose::Poser, now: f64, then: f64) {
        const VERTEX: u64 = size_of::<super::Vertex>() as u64;
        for moved in poser.vertices_at(now) {
            queue.write_buffer(
                &self.vertices,
                moved.first as u64 * VERTEX,
                bytemuck::cast_slice(&moved.vertices),
            );
            if let Some(tangents) = self.tangents.as_ref().filter(|_| !moved.tangents.is_empty()) {
                queue.write_buffer(tangents, moved.first as u64 * 16, bytemuck::cast_slice(&moved.tangents));
            }
        }
        if let Some(previous) = &self.previous {
            for (first, positions) in poser.positions_at(then) {
                queue.write_buffer(previous, first as u64 * 12, bytemuck::cast_slice(&positions));
            }
        }
    }

    /// Whether an animation plays: the vertices have their positions of the frame before (the
    /// last vertex buffer).
    pub(crate) fn is_moving(&self) -> bool {
        self.previous.is_some()
    }

    /// Whether the vertices have tangents (a second vertex buffer), for normal maps.
    pub(crate) fn has_tangents(&self) -> bool {
        self.tangents.is_some()
    }

    /// The draw classes the scene has, in drawing order.
    pub fn draw_classes(&self) -> impl Iterator<Item = DrawClass> + '_ {
        self.draws.iter().map(|(class, _)| *class)
    }

    /// Draws every triangle, each class with the pipeline and bind groups (by group index)
    /// that `pick` gives it, instances `instances`. Passes decide how the scene is drawn; the
    /// scene draws itself.
    pub(crate) fn draw<'a>(
        &self,
        pass: &mut wgpu::RenderPass<'_>,
        pick: impl Fn(DrawClass) -> (&'a wgpu::RenderPipeline, &'a [(u32, wgpu::BindGroup)]),
        instances: Range<u32>,
    ) {
        pass.set_vertex_buffer(0, self.vertices.slice(..));
        if let Some(tangents) = &self.tangents {
            pass.set_vertex_buffer(1, tangents.slice(..));
        }
        // After the tangents, where the scene has them (`scene_pipeline` lays them out so).
        if let Some(previous) = &self.previous {
            pass.set_vertex_buffer(1 + u32::from(self.tangents.is_some()), previous.slice(..));
        }
        pass.set_index_buffer(self.indices.slice(..), wgpu::IndexFormat::Uint32);
        for (class, range) in &self.draws {
            let (pipeline, groups) = pick(*class);
            pass.set_pipeline(pipeline);
            for (index, group) in groups {
                pass.set_bind_group(*index, group, &[]);
            }
            pass.draw_indexed(range.clone(), 0, instances.clone());
        }
    }
}

/// The lights' table as the shaders read it, and the view-projection of every face of the
/// shadow cubes of the lights that cast shadows (at most [`MAX_SHADOW_LIGHTS`]; a light past
/// them shines without shadow).
fn light_table(lights: &[Light]) -> (Vec<GpuLight>, Vec<[[f32; 4]; 4]>) {
    let mut table = Vec::with_capacity(MAX_LIGHTS);
    let mut faces = Vec::new();
    for light in lights {
        let near = f64::from(light.range) * shadow::NEAR_FRACTION;
        let cube = match light.cube() {
            Some(_) if faces.len() < 6 * MAX_SHADOW_LIGHTS => {
                faces.extend(shadow::face_matrices(light.position, near, f64::from(light.range)));
                (faces.len() / 6 - 1) as i32
            }
            _ => -1,
        };
        let settings = light.shadow.unwrap_or_default();
        let (kind, direction, spot_scale, spot_offset) = light_shape(light.kind);
        table.push(GpuLight {
            position: light.position.to_array(),
            range: light.range,
            radiance: (light.color * light.intensity).to_array(),
            shadow: cube,
            shadow_bias: settings.bias,
            shadow_radius: settings.radius,
            shadow_near: near as f32,
            kind,
            direction,
            spot_scale,
            spot_offset,
            padding: [0.0; 3],
        });
    }
    (table, faces)
}

fn gpu_material(material: &super::Material) -> GpuMaterial {
    let layer = |slot: &Option<TextureRef>| slot.map_or(-1, |t| t.texture as i32);
    let mut transforms = [[[1.0, 0.0, 0.0, 0.0], [0.0, 1.0, 0.0, 0.0]]; SLOTS];
    for (slot, texture) in [
        (SLOT_BASE, material.texture),
        (SLOT_NORMAL, material.normal_texture),
        (SLOT_EMISSIVE, material.emissive_texture),
        (SLOT_OCCLUSION, material.occlusion_texture),
        (SLOT_METALLIC_ROUGHNESS, material.metallic_roughness_texture),
    ] {
        if let Some(texture) = texture {
            transforms[slot] = texture.transform.rows.map(|[a, b, c]| [a, b, c, 0.0]);
        }
    }
    GpuMaterial {
        base_color: material.base_color,
        metallic: material.metallic,
        roughness: material.roughness,
        texture: layer(&material.texture),
        alpha_cutoff: match material.alpha {
            AlphaMode::Opaque => 0.0,
            AlphaMode::Mask { cutoff } => cutoff,
        },
        emissive: material.emissive,
        emissive_texture: layer(&material.emissive_texture),
        normal_texture: layer(&material.normal_texture),
        normal_scale: material.normal_scale,
        occlusion_texture: layer(&material.occlusion_texture),
        occlusion_strength: material.occlusion_strength,
        metallic_roughness_texture: layer(&material.metallic_roughness_texture),
        padding: [0; 3],
        transforms,
    }
}
