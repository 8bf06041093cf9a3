// Rasterizes the scene into the (enlarged) G-buffer: UV, normal (the normal map's, where a
// material has one), material, UV derivatives and depth. Opaque geometry uses `gbuffer_opaque`; alpha-masked geometry `gbuffer_masked` (under 4× MSAA `gbuffer_masked_samples`),
// which discards and so loses early depth testing, is drawn after it.

#include "lib/common.wgsl"
#include "lib/scene.wgsl"
#include "lib/geometry.wgsl"

struct VertexOut {
    @builtin(position) clip: vec4<f32>,
    @location(0) normal: vec3<f32>,
    @location(1) uv: vec2<f32>,
    @location(2) @interpolate(flat) material: u32,
#ifdef NORMAL_MAPS
    @location(3) tangent: vec4<f32>,
#endif
#ifdef MOVING
    // The point's clip position now (as `clip`, which the fragment stage reads as pixels) and
    // where it lay in the frame before, in that frame's unjittered clip space.
    @location(4) now: vec4<f32>,
    @location(5) then: vec4<f32>,
#endif
}

// 24 bytes per sample plus depth; see lib/gbuffer.wgsl for the layout.
struct GBuffer {
    @location(0) uv: vec2<f32>,
    @location(1) normal_material: vec4<f32>,
    @location(2) uv_grad: vec4<f32>,
}

#ifdef NORMAL_MAPS
// Tangents come from a second vertex buffer (scene::Scene::tangents).
struct TangentIn {
    @location(4) tangent: vec4<f32>,
}

// The normal map's normal in world space, or `n` where the material has no normal map or the
// vertex no tangent. The interpolated tangent is made perpendicular to `n` first.
fn mapped_normal(n: vec3<f32>, tangent: vec4<f32>, material_index: u32, uv: vec2<f32>, uv_dx: vec2<f32>, uv_dy: vec2<f32>) -> vec3<f32> {
    let material = materials[material_index];
    let along = tangent.xyz - n * dot(n, tangent.xyz);
    let along2 = dot(along, along);
    if material.normal_texture < 0 || along2 < 1e-12 {
        return n;
    }
    let t = along * inverseSqrt(along2);
    let b = cross(n, t) * select(1.0, -1.0, tangent.w < 0.0);
    let c = slot_coords(i32(material_index), SLOT_NORMAL, uv, uv_dx, uv_dy);
    let texel = texture_lookup(scene_data_textures, material.normal_texture, c.uv, c.dx, c.dy).xyz;
    let local = (texel * 2.0 - 1.0) * vec3<f32>(material.normal_scale, material.normal_scale, 1.0);
    let mapped = t * local.x + b * local.y + n * local.z;
    // A map that cancels the normal keeps the surface's own.
    let length2 = dot(mapped, mapped);
    return select(n, mapped * inverseSqrt(length2), length2 > 1e-12);
}
#endif

#ifdef MOVING
// Each vertex's position in the frame before, from the last vertex buffer (scene/pose.rs).
struct PreviousIn {
    @location(5) position: vec3<f32>,
}
#endif

@vertex
fn vertex(
    v: VertexIn,
#ifdef NORMAL_MAPS
    t: TangentIn,
#endif
#ifdef MOVING
    previous: PreviousIn,
#endif
) -> VertexOut {
    var out: VertexOut;
    out.clip = frame.view_proj * vec4<f32>(v.position, 1.0);
    out.normal = v.normal;
    out.uv = v.uv;
    out.material = v.material;
#ifdef NORMAL_MAPS
    out.tangent = t.tangent;
#endif
#ifdef MOVING
    // The reprojection takes this frame's clip space to the frame before's: a point's place
    // then through this frame's camera, taken back, is where the frame before saw it.
    out.now = out.clip;
    out.then = frame.reprojection * (frame.view_proj * vec4<f32>(previous.position, 1.0));
#endif
    return out;
}

fn write_gbuffer(v: VertexOut, front_facing: bool) -> GBuffer {
    let uv_dx = dpdx(v.uv);
    let uv_dy = dpdy(v.uv);
    // The importer repairs zero normals, but interpolation can still cancel two: scale by an
    // inverse square root bounded away from zero, so a zero normal stays zero, not NaN.
    var n = v.normal * inverseSqrt(max(dot(v.normal, v.normal), 1e-20));
#ifdef NORMAL_MAPS
    n = mapped_normal(n, v.tangent, v.material, v.uv, uv_dx, uv_dy);
#endif
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

// The G-buffer of MSAA's alpha-masked geometry: the alpha test per sample, at pixel rate. The
// texture is read at each of the four samples' positions (the standard 4× pattern), the UV moved
// there from the pixel's centre along its screen derivatives, and the samples that fail leave the
// coverage: a cut-out edge is resolved as finely as a triangle's edge, where one test at the
// pixel's centre would keep or drop all four samples together.
struct GBufferCovered {
    @location(0) uv: vec2<f32>,
    @location(1) normal_material: vec4<f32>,
    @location(2) uv_grad: vec4<f32>,
    @builtin(sample_mask) mask: u32,
}

@fragment
fn gbuffer_masked_samples(v: VertexOut, @builtin(front_facing) front_facing: bool) -> GBufferCovered {
    let g = write_gbuffer(v, front_facing);
    let uv_dx = g.uv_grad.xy;
    let uv_dy = g.uv_grad.zw;
    // Offsets of the four samples from the pixel's centre, in pixels, y down.
    var offsets = array<vec2<f32>, 4>(
        vec2<f32>(-0.125, -0.375),
        vec2<f32>(0.375, -0.125),
        vec2<f32>(-0.375, 0.125),
        vec2<f32>(0.125, 0.375),
    );
    var mask = 0u;
    for (var i = 0u; i < 4u; i++) {
        let uv = v.uv + uv_dx * offsets[i].x + uv_dy * offsets[i].y;
        mask |= select(0u, 1u << i, passes_alpha_test(v.material, uv));
    }
    if mask == 0u {
        discard;
    }
    return GBufferCovered(g.uv, g.normal_material, g.uv_grad, mask);
}

// The G-buffer of temporal modes: the same, and the motion of each sample's point.
struct GBufferMotion {
    @location(0) uv: vec2<f32>,
    @location(1) normal_material: vec4<f32>,
    @location(2) uv_grad: vec4<f32>,
    // xy: the pixels the point moved since the previous frame, where it lies now (unjittered)
    // minus where it lay then, y down; z: its linear view depth then.
    @location(3) motion: vec4<f32>,
}

// The motion of the point that the fragment `v` sees: where it lies now (unjittered) minus where
// it lay then, in pixels, and its linear view depth then.
#ifdef MOVING
// Objects move: the vertex stage carried each point's place in the frame before. Both places
// are taken from clip space to the frame's pixels, so the motion is in the frame's pixels
// whatever the G-buffer's size.
fn motion(v: VertexOut) -> vec4<f32> {
    let size = frame.jitter.zw;
    let now = (v.now.xy / v.now.w * vec2<f32>(0.5, -0.5) + 0.5) * size + frame.jitter.xy;
    let then = (v.then.xy / v.then.w * vec2<f32>(0.5, -0.5) + 0.5) * size;
    return vec4<f32>(now - then, v.then.w, 0.0);
}
#else
// The scene stands still, so a point moves with the camera alone: the fragment's clip position
// (NDC and depth; `position.w` is 1 / its clip w) goes through the previous frame's camera in
// one matrix.
fn motion(v: VertexOut) -> vec4<f32> {
    let position = v.clip;
    let size = frame.jitter.zw;
    let ndc = position.xy / size * vec2<f32>(2.0, -2.0) + vec2<f32>(-1.0, 1.0);
    let before = frame.reprojection * vec4<f32>(ndc, position.z, 1.0);
    let then = (before.xy / before.w * vec2<f32>(0.5, -0.5) + 0.5) * size;
    return vec4<f32>(position.xy + frame.jitter.xy - then, before.w / position.w, 0.0);
}
#endif

fn with_motion(g: GBuffer, v: VertexOut) -> GBufferMotion {
    return GBufferMotion(g.uv, g.normal_material, g.uv_grad, motion(v));
}

@fragment
fn gbuffer_opaque_motion(
    v: VertexOut,
    @builtin(front_facing) front_facing: bool,
) -> GBufferMotion {
    return with_motion(write_gbuffer(v, front_facing), v);
}

@fragment
fn gbuffer_masked_motion(
    v: VertexOut,
    @builtin(front_facing) front_facing: bool,
) -> GBufferMotion {
    if !passes_alpha_test(v.material, v.uv) {
        discard;
    }
    return with_motion(write_gbuffer(v, front_facing), v);
}
