// MSAA-based deferred shading (Thibieroz 2009; Lauritzen 2010) on a G-buffer of 4 samples per
// pixel, at the standard 4× sample positions. The G-buffer's fragment shader runs once per
// pixel and triangle (hardware coverage), so every sample a triangle covers holds that
// triangle's attributes at the pixel's centre and its own depth. Three passes after it:
//
//   msaa_classify  marks the pixels whose samples do not all lie on one surface (material,
//                  normal, tangent plane: `per_sample`) and lists them (compute; the marks and
//                  list of `lib/pixel_list.wgsl`)
//   msaa_samples   shades the four samples of each listed pixel, packed four pixels to a 4×4
//                  block of a compact target, so no SIMD lane idles
//   msaa_pixels    shades every other pixel once, at its centre, and averages the samples of
//                  the listed ones (the resolve)
//
// Lauritzen's other way, one pass that branches per pixel and loops over the samples of edge
// pixels, runs the loop for every lane of a block that holds one edge pixel on a CPU
// rasterizer: on lavapipe it took 28–43 % longer than these three passes (docs/msaa.md).
//
// A pixel's shading reads a texture with the pixel's footprint, whether it shades once or four
// times: the G-buffer's UV derivatives are per pixel, as MSAA shades at pixel rate.

#include "lib/common.wgsl"
#include "lib/scene.wgsl"
#include "lib/gbuffer.wgsl"
#include "lib/shading.wgsl"
#include "lib/compact.wgsl"
#include "lib/pixel_list.wgsl"

// The multisampled G-buffer, laid out as lib/gbuffer.wgsl's, read sample by sample.
@group(1) @binding(5) var ms_uv: texture_multisampled_2d<f32>;
@group(1) @binding(6) var ms_normal: texture_multisampled_2d<f32>;
@group(1) @binding(7) var ms_uv_grad: texture_multisampled_2d<f32>;
@group(1) @binding(8) var ms_depth: texture_depth_multisampled_2d;
// The shaded samples of the listed pixels: list entry i's sample k at compact index 4·i + k.
@group(2) @binding(0) var shaded_samples: texture_2d<f32>;

const SAMPLES: u32 = 4u;

// The samples of a pixel lie on one surface when they share a material, their normals' cosine
// with sample 0's is at least EDGE_COS and each lies within EDGE_GAP · depth of sample 0's
// tangent plane (technique/msaa.rs: the thresholds).
override EDGE_COS: f32;
override EDGE_GAP: f32;

fn image_size() -> vec2<f32> {
    return vec2<f32>(f32(WIDTH), f32(HEIGHT));
}

// Where sample k lies in its pixel: Vulkan's standard 4× positions (lavapipe's too, the
// rotated grid of D3D and most GPUs), (3, 1), (7, 3), (1, 5) and (5, 7) eighths. Computed, not
// read from a constant array: indexing one by a variable costs a gather per SIMD lane on
// lavapipe (msaa_classify took 15.2 ms instead of 12.7 on the 1024×768 atrium).
fn sample_offset(k: u32) -> vec2<f32> {
    let f = f32(k);
    return vec2<f32>(fract(0.375 + 0.5 * f - 0.25 * f32(k / 2u)), 0.125 + 0.25 * f);
}

fn sample_point(pixel: vec2<i32>, k: u32) -> vec2<f32> {
    return vec2<f32>(pixel) + sample_offset(k);
}

fn sample_surface(pixel: vec2<i32>, k: u32) -> Surface {
    let nm = textureLoad(ms_normal, pixel, k);
    let g = textureLoad(ms_uv_grad, pixel, k);
    let depth = linear_depth_of(textureLoad(ms_depth, pixel, k));
    return Surface(textureLoad(ms_uv, pixel, k).xy, depth, i32(nm.w), nm.xyz, g.xy, g.zw);
}

// ---- msaa_classify

// Whether the pixel's samples need shading one by one: some sample does not lie on sample 0's
// surface. Background samples all lie on one.
fn per_sample(pixel: vec2<i32>) -> bool {
    let nm0 = textureLoad(ms_normal, pixel, 0u);
    let background = i32(nm0.w) == BACKGROUND;
    for (var k = 1u; k < SAMPLES; k++) {
        let nm = textureLoad(ms_normal, pixel, k);
        if nm.w != nm0.w || (!background && dot(nm.xyz, nm0.xyz) < EDGE_COS) {
            return true;
        }
    }
    if background {
        return false;
    }
    // A sample's distance from sample 0's tangent plane, along its view-space normal n, is
    // |t·(n · ray) − t0·(n · ray0)| for a sample at view depth t on the view ray `ray` that
    // reaches depth 1. That ray is affine in the point it passes through, and so is n · ray:
    // n · ray(pixel + o) = n · ray(pixel) + across · o.
    let size = image_size();
    let n = (frame.view * vec4<f32>(nm0.xyz, 0.0)).xyz;
    let corner = dot(n, view_ray_in(vec2<f32>(pixel), size));
    let across = n.xy * frame.tile.xy * frame.projection.xy * vec2<f32>(2.0, -2.0) / size;
    let t0 = linear_depth_of(textureLoad(ms_depth, pixel, 0u));
    let plane = t0 * (corner + dot(across, sample_offset(0u)));
    let gap = EDGE_GAP * t0;
    for (var k = 1u; k < SAMPLES; k++) {
        let t = linear_depth_of(textureLoad(ms_depth, pixel, k));
        if abs(t * (corner + dot(across, sample_offset(k))) - plane) > gap {
            return true;
        }
    }
    return false;
}

// The pixel's marks (`lib/pixel_list.wgsl`): bit 0 where it shades per sample.
fn pixel_marks(p: vec2<i32>) -> u32 {
    return select(0u, 1u, per_sample(p));
}

@compute @workgroup_size(64)
fn msaa_mark(@builtin(global_invocation_id) id: vec3<u32>) {
    write_mark_word(id.x);
}

// ---- msaa_samples: the list, four fragments per entry

@vertex
fn msaa_rows(@builtin(vertex_index) index: u32) -> @builtin(position) vec4<f32> {
    return compact_rect(index, SAMPLES * list[LIST_LENGTH]);
}

// Sample k of a listed pixel, where it lies. The tail of the last block reads past the list's
// end: its colour lands where msaa_pixels never reads.
@fragment
fn msaa_samples(@builtin(position) position: vec4<f32>) -> @location(0) vec4<f32> {
    let index = compact_index(vec2<u32>(position.xy));
    let pixel = listed_pixel(index / SAMPLES);
    let k = index % SAMPLES;
    let s = sample_surface(pixel, k);
    let point = world_position_in(sample_point(pixel, k), image_size(), s.depth);
    return shade_surface(pixel, s, point, 1.0);
}

// ---- msaa_pixels

struct PixelOut {
    @location(0) color: vec4<f32>,
    // Samples shaded for the pixel: 1 or 4.
    @location(1) count: u32,
}

// A pixel of one surface, shaded once at its centre as deferred shading shades it. Its samples
// hold the surface's attributes at the centre; the depth there is the mean of samples 0 and 3,
// which lie symmetrically about it, exact on a plane (reversed depth is affine in the image).
fn shade_centre(pixel: vec2<i32>) -> vec4<f32> {
    var s = sample_surface(pixel, 0u);
    s.depth = linear_depth_of(0.5 * (textureLoad(ms_depth, pixel, 0u) + textureLoad(ms_depth, pixel, 3u)));
    let point = world_position_in(vec2<f32>(pixel) + 0.5, image_size(), s.depth);
    return shade_surface(pixel, s, point, 1.0);
}

@fragment
fn msaa_pixels(@builtin(position) position: vec4<f32>) -> PixelOut {
    let pixel = vec2<i32>(position.xy);
    let index = list_index(vec2<u32>(pixel));
    if index < 0 {
        return PixelOut(shade_centre(pixel), 1u);
    }
    var sum = vec4<f32>(0.0);
    for (var k = 0u; k < SAMPLES; k++) {
        sum += textureLoad(shaded_samples, compact_texel(SAMPLES * u32(index) + k), 0);
    }
    return PixelOut(sum / f32(SAMPLES), SAMPLES);
}
