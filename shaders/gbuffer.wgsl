// Rasterizes the scene into the (enlarged) G-buffer: UV, normal, material, UV derivatives and
// depth. Opaque geometry uses `gbuffer_opaque`; alpha-masked geometry `gbuffer_masked`,
// which discards and so loses early depth testing, is drawn after it.

#include "lib/common.wgsl"
#include "lib/scene.wgsl"
#include "lib/geometry.wgsl"

struct VertexOut {
    @builtin(position) clip: vec4<f32>,
    @location(0) normal: vec3<f32>,
    @location(1) uv: vec2<f32>,
    @location(2) @interpolate(flat) material: u32,
}

// 24 bytes per sample plus depth; see lib/gbuffer.wgsl for the layout.
struct GBuffer {
    @location(0) uv: vec2<f32>,
    @location(1) normal_material: vec4<f32>,
    @location(2) uv_grad: vec4<f32>,
}

@vertex
fn vertex(v: VertexIn) -> VertexOut {
    let world = vec4<f32>(v.position, 1.0);
    return VertexOut(frame.view_proj * world, v.normal, v.uv, v.material);
}

fn write_gbuffer(v: VertexOut, front_facing: bool) -> GBuffer {
    let uv_dx = dpdx(v.uv);
    let uv_dy = dpdy(v.uv);
    // The importer repairs zero normals, but interpolation can still cancel two: scale by an
    // inverse square root bounded away from zero, so a zero normal stays zero, not NaN.
    var n = v.normal * inverseSqrt(max(dot(v.normal, v.normal), 1e-20));
    // Back faces (of double-sided surfaces; others are culled) show their normal flipped.
    n = select(-n, n, front_facing);
    return GBuffer(v.uv, vec4<f32>(n, f32(v.material)), vec4<f32>(uv_dx, uv_dy));
}

@fragment
fn gbuffer_opaque(v: VertexOut, @builtin(front_facing) front_facing: bool) -> GBuffer {
    return write_gbuffer(v, front_facing);
}

@fragment
fn gbuffer_masked(v: VertexOut, @builtin(front_facing) front_facing: bool) -> GBuffer {
    if !passes_alpha_test(v.material, v.uv) {
        discard;
    }
    return write_gbuffer(v, front_facing);
}
