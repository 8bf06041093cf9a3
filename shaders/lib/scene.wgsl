// The scene's bindings: materials, lights and, in textured scenes, all textures in one 2D
// array with mipmaps. Bound by name from the scene's resources (scene/upload.rs).

// KHR_texture_transform of one texture slot, as rows of a 2×3 matrix: u′ = dot(u.xyz, (u, v, 1)),
// v′ = dot(v.xyz, (u, v, 1)). Read only by scenes that have a transform (`TEXTURE_TRANSFORM`).
struct UvTransform {
    u: vec4<f32>,
    v: vec4<f32>,
}

// Texture slots of a material, indexing `Material::transforms` (scene/upload.rs: SLOT_*).
const SLOT_BASE: u32 = 0u;
const SLOT_NORMAL: u32 = 1u;
const SLOT_EMISSIVE: u32 = 2u;
const SLOT_OCCLUSION: u32 = 3u;
const SLOT_METALLIC_ROUGHNESS: u32 = 4u;

// Texture fields hold a layer of the scene's texture array, or -1 for none.
struct Material {
    // Linear RGBA, multiplied with the texture.
    base_color: vec4<f32>,
    metallic: f32,
    roughness: f32,
    // The base-colour texture.
    texture: i32,
    // MASK materials discard below this alpha; opaque ones carry 0.
    alpha_cutoff: f32,
    // Emitted radiance, times the emissive texture.
    emissive: vec3<f32>,
    emissive_texture: i32,
    // A tangent-space normal map (read as data) and the scale of its X and Y.
    normal_texture: i32,
    normal_scale: f32,
    // Ambient occlusion in red (read as data): ambient × (1 + strength · (occlusion − 1)).
    occlusion_texture: i32,
    occlusion_strength: f32,
    // Roughness in green, metalness in blue (read as data), multiplying the factors.
    metallic_roughness_texture: i32,
    transforms: array<UvTransform, 5>,
}

// Light kinds (scene/upload.rs: LIGHT_*).
const LIGHT_POINT: u32 = 0u;
const LIGHT_SPOT: u32 = 1u;
const LIGHT_DIRECTIONAL: u32 = 2u;

struct Light {
    position: vec3<f32>,
    // Distance at which the contribution fades to zero.
    range: f32,
    // Colour times intensity.
    radiance: vec3<f32>,
    // The light's cube in `shadow_cubes`, or -1 for a light without shadows.
    shadow: i32,
    // World units a surface may lie behind the stored depth and count as lit.
    shadow_bias: f32,
    // PCF disk radius at the light; it grows with view distance (lib/shadows.wgsl).
    shadow_radius: f32,
    // Near plane of the light's cube; its far plane is `range`.
    shadow_near: f32,
    kind: u32,
    // Spot and directional lights: the unit direction the light shines in.
    direction: vec3<f32>,
    // Spot lights: the cone's fade is clamp(cos θ · spot_scale + spot_offset, 0, 1)².
    spot_scale: f32,
    spot_offset: f32,
}

// The number of lights is an override constant, not a uniform: lavapipe recompiles a shader
// for every new value of a uniform that steers a loop.
override LIGHT_COUNT: u32 = 0u;

// Capacity of the light table (scene.rs: MAX_LIGHTS).
const MAX_LIGHTS: u32 = 64u;

struct Lights {
    entries: array<Light, MAX_LIGHTS>,
}

@group(0) @binding(1) var<storage, read> materials: array<Material>;
// A uniform block, not a storage buffer: lavapipe loads a storage array element per SIMD lane;
// the uniform table makes 4×4 atrium shading 22% faster (1470 → 1150 ms, measured).
@group(0) @binding(2) var<uniform> lights: Lights;
#ifdef TEXTURED
// Colour textures (base colour, emission) through the sRGB view, data textures (normals,
// occlusion, metallic-roughness) through a linear view of the same array.
@group(0) @binding(3) var scene_textures: texture_2d_array<f32>;
@group(0) @binding(4) var scene_sampler: sampler;
@group(0) @binding(7) var scene_data_textures: texture_2d_array<f32>;

#ifdef TEXTURE_PAGES
// Scenes whose textures differ in size pack the smaller ones into layers as large as the
// largest (scene/textures.rs): per texture, its corner (xy) and side (z) in units of a layer's
// side, and its layer (w).
@group(0) @binding(8) var<storage, read> texture_places: array<vec4<f32>>;
#endif

// One trilinear lookup of `texture` (an index into the scene's textures) through `textures`, a
// view of the scene's array. Packed textures repeat by hand: the UV is wrapped into the
// texture's place and kept half a texel of the coarser level read from its edge, so the filter never
// reaches a neighbour (a repeat seam clamps instead of blending); footprints wider than the
// whole texture are shortened to it, so no level coarser than its own last is read.
fn texture_lookup(textures: texture_2d_array<f32>, texture: i32, uv: vec2<f32>, dx: vec2<f32>, dy: vec2<f32>) -> vec4<f32> {
#ifdef TEXTURE_PAGES
    let place = texture_places[texture];
    let side = f32(textureDimensions(textures).x) * place.z;
    let longest = max(length(dx), length(dy));
    let shorten = min(1.0, 1.0 / max(longest, 1e-20));
    // Trilinear filtering also reads the next coarser level, whose texels are up to twice
    // as large: the margin is half a texel of that one.
    let level = ceil(clamp(log2(longest * side), 0.0, log2(side)));
    let margin = vec2<f32>(min(0.5 * exp2(level) / side, 0.5));
    let local = clamp(fract(uv), margin, 1.0 - margin);
    let scale = place.z * shorten;
    return textureSampleGrad(textures, scene_sampler, place.xy + local * place.z, i32(place.w), dx * scale, dy * scale);
#else
    return textureSampleGrad(textures, scene_sampler, uv, texture, dx, dy);
#endif
}

// Where a texture slot is read: the UV and its derivatives per G-buffer texel.
struct TexCoords {
    uv: vec2<f32>,
    dx: vec2<f32>,
    dy: vec2<f32>,
}

// A surface's UV and derivatives through the UV transform of `slot` of a material.
fn slot_coords(material: i32, slot: u32, uv: vec2<f32>, dx: vec2<f32>, dy: vec2<f32>) -> TexCoords {
#ifdef TEXTURE_TRANSFORM
    let t = materials[material].transforms[slot];
    let linear = mat2x2<f32>(vec2<f32>(t.u.x, t.v.x), vec2<f32>(t.u.y, t.v.y));
    return TexCoords(linear * uv + vec2<f32>(t.u.z, t.v.z), linear * dx, linear * dy);
#else
    return TexCoords(uv, dx, dy);
#endif
}
#endif
