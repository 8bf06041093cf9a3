//! Uploading a scene: geometry buffers, material and light tables, every texture as one layer
//! of a single mipmapped 2D array (lavapipe has no binding arrays), the shadow cubes' face
//! matrices, and the named resources that shaders bind from the scene.

use std::ops::Range;

use bytemuck::Zeroable;
use wgpu::util::DeviceExt;

use super::shadow::{self, MAX_SHADOW_LIGHTS, ShadowCubes};
use super::{AlphaMode, DrawClass, FrameUniforms, LightKind, Lighting, Scene, Texture};
use crate::bindings::Bound;

/// Lights a scene may have: the size of the shaders' uniform light table.
pub const MAX_LIGHTS: usize = 64;

/// Textures larger than this are scaled down to it; all layers share one size.
pub const MAX_TEXTURE_SIZE: u32 = 1024;

/// `Material` in `shaders/lib/scene.wgsl`.
#[repr(C)]
#[derive(Debug, Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct GpuMaterial {
    base_color: [f32; 4],
    metallic: f32,
    roughness: f32,
    texture: i32,
    alpha_cutoff: f32,
}

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
    pub(crate) indices: wgpu::Buffer,
    pub(crate) draws: Vec<(DrawClass, Range<u32>)>,
    pub(crate) light_count: u32,
    /// The `Frame` uniform block.
    pub(crate) frame: wgpu::Buffer,
    materials: wgpu::Buffer,
    lights: wgpu::Buffer,
    /// The texture array and its sampler; none for an untextured scene.
    textures: Option<(wgpu::Texture, wgpu::Sampler)>,
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
        let textures = scene.is_textured().then(|| upload_texture_array(device, queue, &scene.textures));
        GpuScene {
            vertices: buffer("vertices", bytemuck::cast_slice(&scene.vertices), wgpu::BufferUsages::VERTEX),
            indices: buffer("indices", bytemuck::cast_slice(&scene.indices), wgpu::BufferUsages::INDEX),
            draws: scene.draws.clone(),
            light_count: lights.len() as u32,
            // Rewritten when the ground truth renders tile by tile.
            frame: buffer("frame", bytemuck::bytes_of(frame), uniform | wgpu::BufferUsages::COPY_DST),
            materials: buffer("materials", bytemuck::cast_slice(&materials), storage),
            lights: buffer("lights", bytemuck::cast_slice(&table), uniform),
            texture_bytes: textures.as_ref().map_or(0, |(_, bytes)| *bytes),
            textures: textures.map(|(array, _)| (array, texture_sampler(device))),
            shadow_faces,
        }
    }

    /// The scene resource that shaders bind under `name`, if the scene has it.
    pub(crate) fn binding(&self, name: &str) -> Option<Bound> {
        let buffer = |b: &wgpu::Buffer| Some(Bound::Buffer(b.clone()));
        match name {
            "frame" => buffer(&self.frame),
            "materials" => buffer(&self.materials),
            "lights" => buffer(&self.lights),
            "scene_textures" => {
                self.textures.as_ref().map(|(t, _)| Bound::Texture { texture: t.clone(), filterable: true })
            }
            "scene_sampler" => {
                self.textures.as_ref().map(|(_, s)| Bound::Sampler { sampler: s.clone(), filtering: true })
            }
            "shadow_faces" => self.shadow_faces.as_ref().and_then(|(b, _)| buffer(b)),
            // Depth is read texel by texel: a filtering sampler would blend depths.
            "shadow_sampler" => self
                .shadow_faces
                .as_ref()
                .map(|(_, s)| Bound::Sampler { sampler: s.clone(), filtering: false }),
            _ => None,
        }
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

/// Trilinear; the shaders add anisotropy with taps of their own (`sample_albedo`).
fn texture_sampler(device: &wgpu::Device) -> wgpu::Sampler {
    device.create_sampler(&wgpu::SamplerDescriptor {
        label: Some("scene textures"),
        address_mode_u: wgpu::AddressMode::Repeat,
        address_mode_v: wgpu::AddressMode::Repeat,
        mag_filter: wgpu::FilterMode::Linear,
        min_filter: wgpu::FilterMode::Linear,
        mipmap_filter: wgpu::MipmapFilterMode::Linear,
        ..Default::default()
    })
}

fn gpu_material(material: &super::Material) -> GpuMaterial {
    GpuMaterial {
        base_color: material.base_color,
        metallic: material.metallic,
        roughness: material.roughness,
        texture: material.texture.map_or(-1, |t| t as i32),
        alpha_cutoff: match material.alpha {
            AlphaMode::Opaque => 0.0,
            AlphaMode::Mask { cutoff } => cutoff,
        },
    }
}

/// Uploads all textures (at least one) as layers of one sRGB array.
fn upload_texture_array(
    device: &wgpu::Device,
    queue: &wgpu::Queue,
    textures: &[Texture],
) -> (wgpu::Texture, u64) {
    let size = textures
        .iter()
        .map(|t| t.width.max(t.height))
        .max()
        .unwrap_or(1)
        .next_power_of_two()
        .min(MAX_TEXTURE_SIZE);
    let layers = mip_chains(textures, size);
    let levels = layers[0].len() as u32;
    let array = device.create_texture(&wgpu::TextureDescriptor {
        label: Some("scene textures"),
        size: wgpu::Extent3d { width: size, height: size, depth_or_array_layers: layers.len() as u32 },
        mip_level_count: levels,
        sample_count: 1,
        dimension: wgpu::TextureDimension::D2,
        format: wgpu::TextureFormat::Rgba8UnormSrgb,
        usage: wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::COPY_DST,
        view_formats: &[],
    });
    let mut bytes = 0;
    for (layer, chain) in layers.iter().enumerate() {
        for (level, pixels) in chain.iter().enumerate() {
            let side = (size >> level).max(1);
            queue.write_texture(
                wgpu::TexelCopyTextureInfo {
                    texture: &array,
                    mip_level: level as u32,
                    origin: wgpu::Origin3d { x: 0, y: 0, z: layer as u32 },
                    aspect: wgpu::TextureAspect::All,
                },
                pixels,
                wgpu::TexelCopyBufferLayout {
                    offset: 0,
                    bytes_per_row: Some(4 * side),
                    rows_per_image: Some(side),
                },
                wgpu::Extent3d { width: side, height: side, depth_or_array_layers: 1 },
            );
            bytes += pixels.len() as u64;
        }
    }
    (array, bytes)
}

/// Every texture scaled to `size`² and its full mip chain, textures spread over the cores.
fn mip_chains(textures: &[Texture], size: u32) -> Vec<Vec<Vec<u8>>> {
    let threads = std::thread::available_parallelism().map_or(1, |n| n.get());
    let chunk = textures.len().div_ceil(threads).max(1);
    std::thread::scope(|scope| {
        let workers: Vec<_> = textures
            .chunks(chunk)
            .map(|part| scope.spawn(move || part.iter().map(|t| mip_chain(t, size)).collect::<Vec<_>>()))
            .collect();
        workers.into_iter().flat_map(|worker| worker.join().expect("mip generation panicked")).collect()
    })
}

fn mip_chain(texture: &Texture, size: u32) -> Vec<Vec<u8>> {
    let base = if texture.width == size && texture.height == size {
        texture.rgba.clone()
    } else {
        let image = image::RgbaImage::from_raw(texture.width, texture.height, texture.rgba.clone())
            .expect("texture size matches its pixels");
        image::imageops::resize(&image, size, size, image::imageops::FilterType::Triangle).into_raw()
    };
    let mut chain = vec![base];
    let mut side = size;
    while side > 1 {
        let next = downsample(chain.last().expect("level 0"), side);
        side /= 2;
        chain.push(next);
    }
    chain
}

/// Halves a square sRGB RGBA8 image with a 2×2 box filter in linear light (alpha is linear).
fn downsample(pixels: &[u8], side: u32) -> Vec<u8> {
    let half = (side / 2) as usize;
    let side = side as usize;
    let linear = srgb_to_linear_table();
    let mut out = vec![0u8; half * half * 4];
    for y in 0..half {
        for x in 0..half {
            for c in 0..4 {
                let texel = |dx: usize, dy: usize| pixels[((2 * y + dy) * side + 2 * x + dx) * 4 + c];
                let quad = [texel(0, 0), texel(1, 0), texel(0, 1), texel(1, 1)];
                out[(y * half + x) * 4 + c] = if c == 3 {
                    (quad.iter().map(|&v| u32::from(v)).sum::<u32>() as f32 / 4.0).round() as u8
                } else {
                    linear_to_srgb(quad.iter().map(|&v| linear[v as usize]).sum::<f32>() / 4.0)
                };
            }
        }
    }
    out
}

fn srgb_to_linear_table() -> [f32; 256] {
    std::array::from_fn(|i| {
        let v = i as f32 / 255.0;
        if v <= 0.04045 { v / 12.92 } else { ((v + 0.055) / 1.055).powf(2.4) }
    })
}

fn linear_to_srgb(v: f32) -> u8 {
    let encoded = if v <= 0.0031308 { v * 12.92 } else { 1.055 * v.powf(1.0 / 2.4) - 0.055 };
    (encoded.clamp(0.0, 1.0) * 255.0).round() as u8
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn downsampling_averages_in_linear_light() {
        // Black and white average to linear 0.5, which sRGB encodes as 188, not 128.
        let pixels = [0, 0, 0, 255, 255, 255, 255, 255, 0, 0, 0, 255, 255, 255, 255, 255];
        assert_eq!(downsample(&pixels, 2), vec![188, 188, 188, 255]);
    }

    #[test]
    fn mip_chain_reaches_one_texel() {
        let texture = Texture { width: 8, height: 4, rgba: vec![128; 8 * 4 * 4] };
        let chain = mip_chain(&texture, 8);
        let sides: Vec<usize> = chain.iter().map(|level| level.len() / 4).collect();
        assert_eq!(sides, vec![64, 16, 4, 1]);
        assert!(chain.iter().all(|level| level.iter().all(|&v| v == 128)));
    }
}
