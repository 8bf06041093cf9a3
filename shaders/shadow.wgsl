// The shadow pass: the scene's depth from each shadow-casting light into the faces of its cube
// (scene/shadow.rs builds the face matrices). Opaque geometry needs no fragment shader; MASK
// materials discard as in the G-buffer pass.

#include "lib/common.wgsl"
#include "lib/scene.wgsl"
#include "lib/geometry.wgsl"

// Faces of all shadow cubes: 6 × MAX_SHADOW_LIGHTS (scene/shadow.rs).
const MAX_SHADOW_FACES: u32 = 48u;

// World to clip space of each face, 6 per shadow light; the instance index picks one.
struct ShadowFaces {
    matrices: array<mat4x4<f32>, MAX_SHADOW_FACES>,
}

@group(0) @binding(5) var<uniform> shadow_faces: ShadowFaces;

struct ShadowVertex {
    @builtin(position) clip: vec4<f32>,
    @location(0) uv: vec2<f32>,
    @location(1) @interpolate(flat) material: u32,
}

@vertex
fn shadow_vertex(v: VertexIn, @builtin(instance_index) face: u32) -> ShadowVertex {
    return ShadowVertex(shadow_faces.matrices[face] * vec4<f32>(v.position, 1.0), v.uv, v.material);
}

@fragment
fn shadow_masked(v: ShadowVertex) {
    if !passes_alpha_test(v.material, v.uv) {
        discard;
    }
}
