// The scene's bindings: materials, lights and, in textured scenes, all textures in one 2D
// array with mipmaps. Bound by name from the scene's resources (scene/upload.rs).

struct Material {
    // Linear RGBA, multiplied with the texture.
    base_color: vec4<f32>,
    metallic: f32,
    roughness: f32,
    // Layer in `scene_textures`, or -1 for an untextured material.
    texture: i32,
    // MASK materials discard below this alpha; opaque ones carry 0.
    alpha_cutoff: f32,
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
@group(0) @binding(3) var scene_textures: texture_2d_array<f32>;
@group(0) @binding(4) var scene_sampler: sampler;
#endif
