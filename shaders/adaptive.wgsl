// Adaptive supersampling (Holländer, Boubekeur & Eisemann 2013) on the M·w × M·h G-buffer:
//
//   shade_first   S: one sample per pixel, at dither rank 0, filtered over the whole pixel
//   evaluate      n = 1 + round(k) samples per pixel from the geometry and shading metrics
//   scan_rows,    a prefix sum over the counts lists every (pixel, rank) still to shade,
//   scan_total,   densely, so the next pass runs one fragment per extra sample with no idle
//   emit          SIMD lanes
//   shade_extra   shades the list
//   gather        averages S with the pixel's extra samples (gather_loop shades them itself in a
//                 loop instead: the paper's simplest variant, kept for comparison); a pixel that
//                 takes all M² samples leaves S out and equals the reference. The `-area`
//                 variant weights each sample by the share of the pixel nearest to it (its
//                 cell); the `-cells` variant also shades each sample for its cell as a whole
//                 (adaptive.rs: Reconstruction::Cells)
//
// The `-coverage` variant (Reconstruction::Coverage) keeps S, the list and its passes, and
// changes what they hold: evaluate_coverage groups the window's samples into the surfaces they
// lie on and picks one sample per surface (more where the shading metric asks); shade_group
// shades each for the samples it stands for; gather_coverage weights each by their share of
// the pixel and, where textures vary inside the pixel, moves its light onto their own albedos.
//
// The metric is specified by its CPU twin in renderer/src/adaptive.rs; keep the two in step.
// Passes bind group 2 by name (renderer/src/bindings.rs): each variable below is a port of the
// passes that use it, so binding numbers need only be unique.

#include "lib/common.wgsl"
#include "lib/finite.wgsl"
#include "lib/scene.wgsl"
#include "lib/gbuffer.wgsl"
#include "lib/shading.wgsl"
#include "lib/color.wgsl"
#include "lib/compact.wgsl"

// Set by passes/adaptive.rs from AdaptiveSettings; no defaults here, so Rust is the one source.
override M: u32;
// k = C · M² · metric.
override C_DEPTH: f32;
// The depth variance relative to the squared mean depth (unit-free), or in world units².
override RELATIVE_DEPTH: bool;
override C_NORMAL: f32;
override C_SHADING: f32;
override T_MIN: f32;
override T_EDGE: f32;
override USE_GEOMETRY: bool;
override USE_SHADING: bool;
override FORCE_ALL: bool;
// Each sample stands for its cell of the pixel (the `-cells` variant): S is the pixel's
// centre, and extra samples are shaded at their cells' centroids with their cells' footprints.
override CELLS: bool;
// Each listed sample stands for the samples of its surface nearest to it (the `-coverage`
// variant); S is shaded as under CELLS.
override COVERAGE: bool;

// The first rank a pixel of n samples shades after S. A pixel that takes its whole window is
// shaded exactly like the reference: rank 0 again, at the reference's footprint, instead of
// reusing S (whose footprint spans the pixel). Any other pixel reuses S, as the paper does,
// except under CELLS, where S stands for the whole pixel and so for no cell of one that takes
// more samples (adaptive.rs: Reconstruction::reshades_first).
fn first_extra_rank(n: u32) -> u32 {
    return select(1u, 0u, n == M * M || ((CELLS || COVERAGE) && n > 1u));
}

// Entry (n − 1)·M² + rank: the cell of sample `rank` among the first n, as (its share of the
// pixel, its centroid less the sample's position in G-buffer texels, its side in G-buffer
// texels) (adaptive.rs: sample_cells). Read by the `-area` and `-cells` variants.
@group(2) @binding(11) var<storage, read> sample_cells: array<vec4<f32>>;

fn sample_cell(n: u32, rank: u32) -> vec4<f32> {
    return sample_cells[(n - 1u) * M * M + rank];
}

// Sample `rank` of the pixel's first n, shaded for its cell.
fn shade_cell(texel: vec2<i32>, n: u32, rank: u32) -> vec4<f32> {
    let cell = sample_cell(n, rank);
    return shade_offset(texel, cell.yz, cell.w);
}

// Rank → row-major window cell, from the paper's Fig. 3 matrices: eight 4-bit cells per word,
// rank 0 lowest (adaptive.rs: packed_sample_order).
override ORDER_LOW: u32;
override ORDER_HIGH: u32;

fn window_cell(rank: u32) -> u32 {
    let word = select(ORDER_HIGH, ORDER_LOW, rank < 8u);
    return (word >> (4u * (rank % 8u))) & 15u;
}

// Window cell → rank, the paper's matrix itself, packed the same way (adaptive.rs:
// packed_dither_matrix).
override RANK_LOW: u32;
override RANK_HIGH: u32;

fn texel_rank(texel: vec2<i32>) -> u32 {
    let cell = u32(texel.y % i32(M)) * M + u32(texel.x % i32(M));
    let word = select(RANK_HIGH, RANK_LOW, cell < 8u);
    return (word >> (4u * (cell % 8u))) & 15u;
}

// S, the shade-first image.
@group(2) @binding(1) var first: texture_2d<f32>;
// Samples per pixel, written by evaluate.
@group(2) @binding(2) var counts: texture_2d<u32>;

fn window_texel(pixel: vec2<i32>, rank: u32) -> vec2<i32> {
    let cell = window_cell(rank);
    return pixel * i32(M) + vec2<i32>(i32(cell % M), i32(cell / M));
}

// A list entry holds what shading one extra sample needs, decoded with shifts alone: its
// G-buffer texel (x, y) and its pixel's sample count n, as x | y << TEXEL_BITS | (n − 1) <<
// 2·TEXEL_BITS. Storing the pixel and rank instead cost shade_extra a texture load (the count)
// and a division by the image width per sample (scalar on lavapipe's SIMD lanes).
const TEXEL_BITS: u32 = 14u;

fn list_entry(texel: vec2<i32>, n: u32) -> u32 {
    return u32(texel.x) | (u32(texel.y) << TEXEL_BITS) | ((n - 1u) << (2u * TEXEL_BITS));
}

fn entry_texel(entry: u32) -> vec2<i32> {
    let mask = (1u << TEXEL_BITS) - 1u;
    return vec2<i32>(i32(entry & mask), i32((entry >> TEXEL_BITS) & mask));
}

fn entry_count(entry: u32) -> u32 {
    return (entry >> (2u * TEXEL_BITS)) + 1u;
}

// A sample's texture footprint, in G-buffer texels, when n samples share the pixel: the filter
// width that gives the n samples together the same spread (variance) as the reference's M²
// one-texel samples, sqrt((1 + M²/n) / 2). It is 1 at n = M², like the reference's own.
fn footprint(n: u32) -> f32 {
    return sqrt(0.5 + 0.5 * f32(M * M) / f32(n));
}

@fragment
fn shade_first(@builtin(position) position: vec4<f32>) -> @location(0) vec4<f32> {
    let texel = window_texel(vec2<i32>(position.xy), 0u);
    if CELLS {
        return shade_cell(texel, 1u, 0u);
    }
    return shade(texel, footprint(1u));
}

// ---- evaluate: reads S and the G-buffer

// Perceptual luma of an S pixel: the square root (a gamma-2 stand-in for sRGB, without pow)
// of the luminance of the exposed colour clamped to [0, 1]. S is sanitized first: a NaN or
// infinity from shading must not reach the metric (the frame checks count them).
fn first_luma(pixel: vec2<i32>) -> f32 {
    let size = vec2<i32>(textureDimensions(first));
    let p = clamp(pixel, vec2<i32>(0), size - 1);
    let exposed = sanitize3(textureLoad(first, p, 0).rgb) * frame.display.x;
    let linear = clamp(exposed, vec3<f32>(0.0), vec3<f32>(1.0));
    return sqrt(luminance(linear));
}

// Evaluate reads depths four at a time: textureGather returns a 2×2 block of texels in one
// call, where a load returns one (14% of evaluate at 4×4, measured). Nearest, clamped.
@group(2) @binding(12) var texel_sampler: sampler;

// The linear depths of the 2×2 block whose top-left texel is `texel`, in textureGather's order:
// x bottom-left, y bottom-right, z top-right, w top-left. Each is linear_depth's, bit for bit.
fn depth_block(texel: vec2<i32>) -> vec4<f32> {
    let size = vec2<f32>(textureDimensions(gb_depth));
    // The shared corner of the four texels, half a texel from any other block.
    let d = textureGather(gb_depth, texel_sampler, vec2<f32>(texel + 1) / size);
    let near = frame.projection.z;
    let far = frame.projection.w;
    return near * far / (d * (far - near) + near);
}

// Running sums of a window's depths, shifted by its first depth.
struct DepthSums {
    shift: f32,
    sum: f32,
    square_sum: f32,
}

fn add_depth(sums: ptr<function, DepthSums>, depth: f32) {
    let d = depth - (*sums).shift;
    (*sums).sum += d;
    (*sums).square_sum += d * d;
}

// One row of the window, left to right, from the row's halves of its two blocks (the right
// block only where M > 2; M ≤ 4, the largest dither matrix).
fn add_depth_row(sums: ptr<function, DepthSums>, left: vec2<f32>, right: vec2<f32>) {
    add_depth(sums, left.x);
    add_depth(sums, left.y);
    if M > 2u {
        add_depth(sums, right.x);
    }
    if M > 3u {
        add_depth(sums, right.y);
    }
}

// The window's depth sums in row-major order, the order of a loop over its texels, so the
// variance is the same bits as such a loop's.
fn window_depths(origin: vec2<i32>) -> DepthSums {
    var sums = DepthSums(linear_depth(origin), 0.0, 0.0);
    for (var row = 0u; row < M; row += 2u) {
        let left = depth_block(origin + vec2<i32>(0, i32(row)));
        var right = vec4<f32>(0.0);
        if M > 2u {
            right = depth_block(origin + vec2<i32>(2, i32(row)));
        }
        add_depth_row(&sums, left.wz, right.wz);
        if row + 1u < M {
            add_depth_row(&sums, left.xy, right.xy);
        }
    }
    return sums;
}

// max(C_DEPTH · variance, C_NORMAL · cone) of the window, before the M² scaling; see
// geometry_metric in adaptive.rs for the cases. The variance is shifted by the window's first
// depth: Σ(d − K)² − (Σ(d − K))²/n stays exact where E[d²] − E[d]² cancels at large depths, and
// in one pass (a two-pass version over private arrays took 65% longer on lavapipe, measured).
// Everything stays finite: depths lie in [near, far] ≤ 1e12 and the constants ≤ 1e12
// (MAX_METRIC_CONSTANT), so no product reaches f32's range; a silhouette returns 1, which
// alone takes every sample (k · M² ≥ M²) without an infinity to lean on.
fn geometry_k(pixel: vec2<i32>) -> f32 {
    let n = M * M;
    let origin = pixel * i32(M);
    var covered = 0u;
    var normal_sum = vec3<f32>(0.0);
    for (var i = 0u; i < n; i += 1u) {
        let nm = load_normal_material(origin + vec2<i32>(i32(i % M), i32(i / M)));
        let length_n = length(nm.xyz);
        covered += u32(i32(nm.w) != BACKGROUND);
        normal_sum += select(vec3<f32>(0.0), nm.xyz / length_n, length_n > 1e-6);
    }
    let depths = window_depths(origin);
    if covered == 0u {
        return 0.0;
    }
    if covered < n {
        // A silhouette against the background.
        return 1.0;
    }
    var variance = max(depths.square_sum - depths.sum * depths.sum / f32(n), 0.0) / f32(n);
    if RELATIVE_DEPTH {
        let mean = depths.shift + depths.sum / f32(n);
        variance /= mean * mean;
    }
    let sum_length = length(normal_sum);
    var cone = 1.0;
    if sum_length >= 1e-3 * f32(n) {
        let mean_normal = normal_sum / sum_length;
        var min_cos = 1.0;
        for (var i = 0u; i < n; i += 1u) {
            let normal = load_normal_material(origin + vec2<i32>(i32(i % M), i32(i / M))).xyz;
            let length_n = length(normal);
            let unit = select(vec3<f32>(0.0), normal / length_n, length_n > 1e-6);
            min_cos = min(min_cos, abs(dot(unit, mean_normal)));
        }
        cone = sqrt(max(1.0 - min_cos, 0.0));
    }
    return max(C_DEPTH * variance, C_NORMAL * cone);
}

// The shading metric also counts the contrast of base-colour textures below the pixel's scale
// (the `-cells` variant): S reads textures filtered over the whole pixel, so a checker whose
// cells are a pixel wide is a flat grey to it, although the samples inside the pixel, and the
// reference's, see black and white.
override TEXTURE_DETAIL: bool;

// The luminance of the base colour at `texel` filtered at the reference's footprint (one
// G-buffer texel), or -1 where the sample has no base-colour texture.
fn fine_albedo(texel: vec2<i32>) -> f32 {
#ifdef TEXTURED
    let s = load_surface(texel);
    if s.material == BACKGROUND || materials[s.material].texture < 0 {
        return -1.0;
    }
    let material = materials[s.material];
    let c = surface_coords(s, SLOT_BASE, 1.0);
    return luminance(texture_lookup(scene_textures, material.texture, c.uv, c.dx, c.dy).rgb * material.base_color.rgb);
#else
    return -1.0;
#endif
}

// The luma range that the base-colour texture spans inside the pixel, from the window's four
// corner samples read at the reference's footprint. A sample's colour is its albedo times its
// light, so with the light of S it is S scaled by the albedo over the pixel's mean albedo: the
// range of the metric's square-root luma is then luma(S) · (√a_max − √a_min) / √a_mean.
fn texture_range(pixel: vec2<i32>) -> f32 {
    let origin = pixel * i32(M);
    let last = i32(M) - 1;
    let a = vec4<f32>(
        fine_albedo(origin),
        fine_albedo(origin + vec2<i32>(last, 0)),
        fine_albedo(origin + vec2<i32>(0, last)),
        fine_albedo(origin + vec2<i32>(last, last)),
    );
    if min(min(a.x, a.y), min(a.z, a.w)) < 0.0 {
        return 0.0;
    }
    let high = max(max(a.x, a.y), max(a.z, a.w));
    let low = min(min(a.x, a.y), min(a.z, a.w));
    let mean = max(dot(a, vec4<f32>(0.25)), 1e-6);
    return first_luma(pixel) * (sqrt(high) - sqrt(low)) / sqrt(mean);
}

// The shading metric also bounds the specular highlights inside the pixel from the lights
// (`-cells` and `-coverage`; the paper's future work): S's luma cannot show a highlight that
// peaks between pixel centres.
override LIGHT_DETAIL: bool;

// How far the half vector of a light can turn against the normal inside the pixel, less the
// light's own share: the spread of the normals of the window's corners on S's surface plus half
// the angle the pixel subtends from the eye; and `reach`, the pixel's half-diagonal on the
// surface in world units, a grazing view stretching it.
struct Turn {
    eye: f32,
    reach: f32,
}

fn pixel_turn(pixel: vec2<i32>, material: i32, normal: vec3<f32>, depth: f32, v: vec3<f32>) -> Turn {
    let origin = pixel * i32(M);
    let last = i32(M) - 1;
    var min_cos = 1.0;
    for (var corner = 0u; corner < 4u; corner += 1u) {
        let nm = load_normal_material(origin + vec2<i32>(i32(corner & 1u), i32(corner >> 1u)) * last);
        if i32(nm.w) == material {
            min_cos = min(min_cos, dot(nm.xyz, normal));
        }
    }
    let centre = view_ray(vec2<f32>(origin) + 0.5 * f32(M));
    let half_diagonal = length(centre - view_ray(vec2<f32>(origin)));
    let eye = half_diagonal / length(centre);
    let reach = depth * half_diagonal / max(abs(dot(normal, v)), 0.25);
    return Turn(acos(clamp(min_cos, -1.0, 1.0)) + 0.5 * eye, reach);
}

// A light whose lobe (about `a` radians wide) spans more than this many of the pixel's turns
// changes the highlight slowly enough for the luma cross on S to see it, and is skipped.
const LOBE_TURNS: f32 = 16.0;

// The luma range of the specular highlights inside the pixel, bounded on S's sample: for each
// light, n·h at S lies at angle θ from the lobe's peak and moves by at most δ inside the pixel
// (pixel_turn, plus half the angle the pixel subtends from a near light), so the GGX lobe spans
// its values at max(θ − δ, 0) and min(θ + δ, 90°). The lobe is weighted by S's visibility,
// Fresnel term and light; shadows and metallic-roughness textures are left out (a highlight
// in shadow is over-counted, a texture-sharpened one under-counted).
fn specular_range(pixel: vec2<i32>) -> f32 {
    let texel = window_texel(pixel, 0u);
    let nm = load_normal_material(texel);
    let index = i32(nm.w);
    if index == BACKGROUND {
        return 0.0;
    }
    let normal = nm.xyz;
    let depth = linear_depth(texel);
    let material = materials[index];
    let position = world_position(texel, depth);
    let v = normalize(frame.eye.xyz - position);
    let turn = pixel_turn(pixel, index, normal, depth, v);
    let a = clamp(material.roughness, 0.03, 1.0) * clamp(material.roughness, 0.03, 1.0);
    let a2 = a * a;
    let n_v = max(dot(normal, v), 1e-4);
    let f0 = mix(vec3<f32>(0.04), material.base_color.rgb, material.metallic);
    var above = 0.0;
    var below = 0.0;
    for (var i = 0u; i < LIGHT_COUNT; i += 1u) {
        let light = lights.entries[i];
        let ray = light_ray(light, position);
        let inverse = inverseSqrt(ray.distance2);
        let l = ray.to_light * inverse;
        let n_l = dot(normal, l);
        let delta = min(turn.eye + 0.5 * select(0.0, turn.reach * inverse, ray.positional), 0.5 * PI);
        if n_l <= 0.0 || a > LOBE_TURNS * delta {
            continue;
        }
        let h = normalize(v + l);
        let n_h = clamp(dot(normal, h), 0.0, 1.0);
        // cos(θ ∓ δ) from cos θ = n·h, without inverse trigonometry; cos δ and sin δ by their
        // Taylor polynomials, within 0.02 up to 90°.
        let d2 = delta * delta;
        let cos_delta = 1.0 - d2 * (0.5 - d2 / 24.0);
        let sines = sqrt(max(1.0 - n_h * n_h, 0.0)) * delta * (1.0 - d2 * (1.0 / 6.0 - d2 / 120.0));
        let highest = ggx(select(n_h * cos_delta + sines, 1.0, n_h >= cos_delta), a2);
        let here = ggx(n_h, a2);
        let lowest = ggx(max(n_h * cos_delta - sines, 0.0), a2);
        let fresnel = f0 + (1.0 - f0) * schlick_weight(max(dot(v, h), 0.0));
        var falloff = attenuation(ray.distance2, inverse * inverse, light.range);
#ifdef LIGHT_KINDS
        falloff = select(1.0, falloff, ray.positional) * spot_fade(light, l);
#endif
        let weight = luminance(fresnel * light.radiance) * smith_visibility(n_l, n_v, a) * n_l * falloff;
        above += weight * (highest - here);
        below += weight * (here - lowest);
    }
    let exposure = frame.display.x;
    let lum = luminance(sanitize3(textureLoad(first, pixel, 0).rgb));
    return shown_luma((lum + above) * exposure) - shown_luma((lum - below) * exposure);
}

// The metric's luma of exposed linear luminance `x` as the display shows it: through the
// scene's tonemap (set by passes/adaptive.rs; without one, color.wgsl's defaults clamp to
// [0, 1]), under the metric's square root. Unlike first_luma's clamp, it tells a highlight's
// core from its rim.
fn shown_luma(x: f32) -> f32 {
    return select(sqrt(tonemap_curve(min(x, HALF_MAX))), 0.0, x <= PEAK_FLOOR);
}

fn shading_k(pixel: vec2<i32>) -> f32 {
    let c = first_luma(pixel);
    let l = first_luma(pixel + vec2<i32>(-1, 0));
    let r = first_luma(pixel + vec2<i32>(1, 0));
    let u = first_luma(pixel + vec2<i32>(0, -1));
    let d = first_luma(pixel + vec2<i32>(0, 1));
    let l_max = max(max(max(c, l), max(r, u)), d);
    let l_min = min(min(min(c, l), min(r, u)), d);
    var range = l_max - l_min;
    if TEXTURE_DETAIL {
        range = max(range, texture_range(pixel));
    }
    // The light-aware term only where the range so far leaves samples to ask for.
    if LIGHT_DETAIL && C_SHADING * range * f32(M * M) + 0.5 < f32(M * M - 1u) {
        range = max(range, specular_range(pixel));
    }
    if range < max(T_MIN, l_max * T_EDGE) {
        return 0.0;
    }
    return C_SHADING * range;
}

@fragment
fn evaluate(@builtin(position) position: vec4<f32>) -> @location(0) u32 {
    return metric_count(vec2<i32>(position.xy));
}

// The paper's count: 1 + round(k · M²) from the geometry and shading metrics.
fn metric_count(pixel: vec2<i32>) -> u32 {
    let total = M * M;
    if FORCE_ALL {
        return total;
    }
    var k = 0.0;
    if USE_GEOMETRY {
        k = max(k, geometry_k(pixel));
    }
    // A window that geometry fills already (a silhouette takes k = 1) needs no shading
    // metric: the count is clamped to the window either way, so skipping it changes no count.
    if USE_SHADING && k * f32(total) + 0.5 < f32(total - 1u) {
        k = max(k, shading_k(pixel));
    }
    // 1 + round(k · M²), clamped to the window; k is finite and ≥ 0 (geometry_k, shading_k).
    let extra = min(floor(k * f32(total) + 0.5), f32(total - 1u));
    return 1u + u32(extra);
}

// ---- evaluate_stable: the `-stable` variant's counts, which follow the frame before's
//
// The metric's count n of this frame and the count c that the pixel's surface had in the frame
// before combine by adaptive.rs: StableCounts::next (its CPU twin): c rises at once to n, and
// falls only where n asks for more than STABLE_HOLD samples fewer, and then by at most the
// share STABLE_DECAY of itself a frame. The frame before's count is the one of the pixel where
// the window's nearest sample lay then (the reprojection in the frame uniforms: the scenes are
// static, so points move with the camera alone), taken only where that pixel could see the
// point: where it lay no deeper than the deepest sample of that pixel's window, by
// STABLE_DEPTH_TOLERANCE (the background counts as deepest). A depth within a tolerance of one
// sample's would fail on grazing surfaces, whose depth changes by a percent across a pixel.
// Elsewhere (a disocclusion, the frame's edge, the first frame after a reset) n is taken alone.

override STABLE_HOLD: f32;
override STABLE_DECAY: f32;
override STABLE_DEPTH_TOLERANCE: f32;

// The frame before's counts: x the count (held as a float: the decay may leave it between
// whole samples), y the linear view depth of the deepest sample in its pixel's window,
// or -1 where a sample of it saw the background.
@group(2) @binding(16) var count_history: texture_2d<f32>;

const SAW_BACKGROUND: f32 = -1.0;

struct StableOut {
    @location(0) counts: u32,
    // This frame's, for the next: the same layout as count_history.
    @location(1) count_history_next: vec4<f32>,
}

// A window's nearest sample (its texel and reversed depth, 0 where no surface covers it) and
// its deepest reversed depth.
struct WindowDepths {
    nearest_texel: vec2<i32>,
    nearest: f32,
    deepest: f32,
}

fn add_window_depth(w: ptr<function, WindowDepths>, texel: vec2<i32>, depth: f32) {
    if depth > (*w).nearest {
        (*w).nearest_texel = texel;
        (*w).nearest = depth;
    }
    (*w).deepest = min((*w).deepest, depth);
}

// One row of the window, left to right, from the row's halves of its two blocks (as
// add_depth_row reads them).
fn add_window_row(w: ptr<function, WindowDepths>, start: vec2<i32>, left: vec2<f32>, right: vec2<f32>) {
    add_window_depth(w, start, left.x);
    add_window_depth(w, start + vec2<i32>(1, 0), left.y);
    if M > 2u {
        add_window_depth(w, start + vec2<i32>(2, 0), right.x);
    }
    if M > 3u {
        add_window_depth(w, start + vec2<i32>(3, 0), right.y);
    }
}

// The nearest sample is the first of the largest reversed depth in row-major order. Read four
// at a time as window_depths reads them (sixteen loads cost evaluate a fifth more at 4×4).
fn window_extent(origin: vec2<i32>) -> WindowDepths {
    let size = vec2<f32>(textureDimensions(gb_depth));
    var w = WindowDepths(origin, 0.0, 1.0);
    for (var row = 0u; row < M; row += 2u) {
        let start = origin + vec2<i32>(0, i32(row));
        let left = textureGather(gb_depth, texel_sampler, vec2<f32>(start + 1) / size);
        var right = vec4<f32>(0.0);
        if M > 2u {
            right = textureGather(gb_depth, texel_sampler, vec2<f32>(start + vec2<i32>(3, 1)) / size);
        }
        add_window_row(&w, start, left.wz, right.wz);
        if row + 1u < M {
            add_window_row(&w, start + vec2<i32>(0, 1), left.xy, right.xy);
        }
    }
    return w;
}

// The count the pixel's surface had in the frame before, or -1 where the history does not hold
// it.
fn count_before(w: WindowDepths) -> f32 {
    if frame.history.x == 0.0 {
        return -1.0;
    }
    let size = frame.jitter.zw;
    let gbuffer_size = vec2<f32>(textureDimensions(gb_depth));
    let ndc = (vec2<f32>(w.nearest_texel) + 0.5) / gbuffer_size * vec2<f32>(2.0, -2.0) + vec2<f32>(-1.0, 1.0);
    let before = frame.reprojection * vec4<f32>(ndc, w.nearest, 1.0);
    let then = (before.xy / before.w * vec2<f32>(0.5, -0.5) + 0.5) * size;
    // Also false for NaN: a point that no camera can reproject.
    if !(all(then >= vec2<f32>(0.0)) && all(then < size)) {
        return -1.0;
    }
    let kept = textureLoad(count_history, vec2<i32>(then), 0);
    if kept.y == SAW_BACKGROUND {
        return kept.x;
    }
    if w.nearest == 0.0 {
        // The background now, where the pixel before saw none.
        return -1.0;
    }
    // before.w is the point's clip w then over its clip w now: its linear depth then over now.
    let depth_then = before.w * linear_depth_of(w.nearest);
    return select(-1.0, kept.x, depth_then <= kept.y * (1.0 + STABLE_DEPTH_TOLERANCE));
}

@fragment
fn evaluate_stable(@builtin(position) position: vec4<f32>) -> StableOut {
    let pixel = vec2<i32>(position.xy);
    let now = f32(metric_count(pixel));
    let w = window_extent(pixel * i32(M));
    let before = count_before(w);
    var count = now;
    if before >= 1.0 {
        let held = now >= before - STABLE_HOLD;
        count = select(max(now, before * (1.0 - STABLE_DECAY)), max(now, before), held);
    }
    let deepest = select(SAW_BACKGROUND, linear_depth_of(w.deepest), w.deepest > 0.0);
    // A whole count in [1, M²]: `count` lies between two counts that do.
    let samples = clamp(u32(ceil(count - 0.001)), 1u, M * M);
    return StableOut(samples, vec4<f32>(count, deepest, 0.0, 0.0));
}

// ---- scan_rows, scan_total, emit: the list of extra samples

@group(2) @binding(3) var<storage, read_write> row_offsets: array<u32>;
@group(2) @binding(4) var<storage, read_write> totals: array<u32>;
@group(2) @binding(5) var<storage, read_write> pixel_offsets: array<u32>;
@group(2) @binding(6) var<storage, read_write> entries: array<u32>;

// List entries of each row.
@compute @workgroup_size(64)
fn scan_rows(@builtin(global_invocation_id) id: vec3<u32>) {
    let size = textureDimensions(counts);
    let y = id.x;
    if y >= size.y {
        return;
    }
    var sum = 0u;
    for (var x = 0u; x < size.x; x += 1u) {
        let n = textureLoad(counts, vec2<u32>(x, y), 0).r;
        sum += n - first_extra_rank(n);
    }
    row_offsets[y] = sum;
}

// Exclusive prefix sum over the rows; totals[0] = all extra samples.
@compute @workgroup_size(1)
fn scan_total() {
    let rows = textureDimensions(counts).y;
    var total = 0u;
    for (var y = 0u; y < rows; y += 1u) {
        let sum = row_offsets[y];
        row_offsets[y] = total;
        total += sum;
    }
    totals[0] = total;
}

// Writes each pixel's first list index and the entries of its extra samples.
@compute @workgroup_size(64)
fn emit(@builtin(global_invocation_id) id: vec3<u32>) {
    let size = textureDimensions(counts);
    let y = id.x;
    if y >= size.y {
        return;
    }
    var offset = row_offsets[y];
    for (var x = 0u; x < size.x; x += 1u) {
        let pixel = y * size.x + x;
        let n = textureLoad(counts, vec2<u32>(x, y), 0).r;
        pixel_offsets[pixel] = offset;
        for (var rank = first_extra_rank(n); rank < n; rank += 1u) {
            entries[offset] = list_entry(window_texel(vec2<i32>(i32(x), i32(y)), rank), n);
            offset += 1u;
        }
    }
}

// ---- shade_extra: the list, read only

@group(2) @binding(7) var<storage, read> list_entries: array<u32>;
@group(2) @binding(8) var<storage, read> list_totals: array<u32>;

// The compact target's rectangles (`compact_rect`). The tail of the last block reads past
// the list's end: a stale or zero entry, or past the buffer (robust access clamps or reads 0),
// it decodes to some texel below 2^14 and 1 ≤ n ≤ 16, and its colour lands where gather never
// reads. So shade_extra needs no test against the length: a storage load per fragment (per
// SIMD lane on lavapipe) that cost 4–5% of shade_extra (thin, every sample listed), and a
// rectangle over whole bands shaded up to 65 535 fragments more.
@vertex
fn compact_rows(@builtin(vertex_index) index: u32) -> @builtin(position) vec4<f32> {
    return compact_rect(index, list_totals[0]);
}

@fragment
fn shade_extra(@builtin(position) position: vec4<f32>) -> @location(0) vec4<f32> {
    let entry = list_entries[compact_index(vec2<u32>(position.xy))];
    let texel = entry_texel(entry);
    if CELLS {
        return shade_cell(texel, entry_count(entry), texel_rank(texel));
    }
    return shade(texel, footprint(entry_count(entry)));
}

// ---- gather: S, the counts, each pixel's first list index and the extra samples

@group(2) @binding(9) var<storage, read> list_offsets: array<u32>;
@group(2) @binding(10) var extra_samples: texture_2d<f32>;

// Average each pixel's samples weighted by the area of their cells (the `-area` and `-cells`
// variants), instead of alike (the paper). A pixel of 1 or M² samples is averaged alike
// either way (adaptive.rs: Reconstruction::weighted).
override WEIGHTED: bool;

// A pixel's samples, summed as they arrive and averaged at the end: alike, in the paper's
// order of operations, or weighted by area. `first_rank` is 1 where S is reused, else 0.
struct Average {
    sum: vec4<f32>,
    n: u32,
    weighted: bool,
}

// The paper's path keeps its exact operations (no multiplication by 1) and reads no weight.
fn start_average(pixel: vec2<i32>, n: u32, first_rank: u32) -> Average {
    let weighted = WEIGHTED && n > 1u && n < M * M;
    let s = select(vec4<f32>(0.0), textureLoad(first, pixel, 0), first_rank == 1u);
    if weighted {
        return Average(s * sample_cell(n, 0u).x, n, true);
    }
    return Average(s, n, false);
}

fn add_sample(average: ptr<function, Average>, rank: u32, sample: vec4<f32>) {
    if (*average).weighted {
        (*average).sum += sample * sample_cell((*average).n, rank).x;
    } else {
        (*average).sum += sample;
    }
}

fn finish_average(average: Average) -> vec4<f32> {
    return select(average.sum / f32(average.n), average.sum, average.weighted);
}

@fragment
fn gather(@builtin(position) position: vec4<f32>) -> @location(0) vec4<f32> {
    let pixel = vec2<i32>(position.xy);
    let n = textureLoad(counts, pixel, 0).r;
    let first_rank = first_extra_rank(n);
    var average = start_average(pixel, n, first_rank);
    let width = textureDimensions(first).x;
    let base = list_offsets[u32(pixel.y) * width + u32(pixel.x)];
    for (var j = 0u; j < n - first_rank; j += 1u) {
        add_sample(&average, first_rank + j, textureLoad(extra_samples, compact_texel(base + j), 0));
    }
    return finish_average(average);
}

@fragment
fn gather_loop(@builtin(position) position: vec4<f32>) -> @location(0) vec4<f32> {
    let pixel = vec2<i32>(position.xy);
    let n = textureLoad(counts, pixel, 0).r;
    let first_rank = first_extra_rank(n);
    var average = start_average(pixel, n, first_rank);
    let scale = footprint(n);
    for (var rank = first_rank; rank < n; rank += 1u) {
        let texel = window_texel(pixel, rank);
        if CELLS {
            add_sample(&average, rank, shade_cell(texel, n, rank));
        } else {
            add_sample(&average, rank, shade(texel, scale));
        }
    }
    return finish_average(average);
}

// ---- the `-coverage` variant: one sample per surface of the window, weighted by coverage

// Two samples lie on one surface when they share a material, their normals' cosine is at
// least SURFACE_COS and the second lies within SURFACE_GAP · depth of the first's tangent
// plane (adaptive.rs: SurfaceTolerance).
override SURFACE_COS: f32;
override SURFACE_GAP: f32;

// What evaluate_coverage leaves for the passes after it, per pixel: x holds the mask of the
// window cells that are shaded (bit c for cell c, row-major) and, in bit 16, whether a surface
// of the pixel has a base-colour texture; y and z hold, four bits per cell (cells 0–7 in y, 8–15 in z), the slot
// of the shaded sample that stands for the cell, slots numbered in cell order. The count (the
// mask's bits) goes to `counts` as in the other variants.
@group(2) @binding(13) var groups: texture_2d<u32>;

const TEXTURE_VARIES: u32 = 0x10000u;

struct Groups {
    shaded: u32,
    slots: vec2<u32>,
    detail: bool,
}

fn load_groups(pixel: vec2<i32>) -> Groups {
    let g = textureLoad(groups, pixel, 0);
    return Groups(g.x & 0xffffu, g.yz, (g.x & TEXTURE_VARIES) != 0u);
}

fn cell_slot(g: Groups, cell: u32) -> u32 {
    let word = select(g.slots.y, g.slots.x, cell < 8u);
    return (word >> (4u * (cell % 8u))) & 15u;
}

fn cell_offset(cell: u32) -> vec2<i32> {
    return vec2<i32>(i32(cell % M), i32(cell / M));
}

// What the shaded sample of window cell `cell` stands for: (its share of the pixel, the
// centroid of its cells less its own position in G-buffer texels, the side of a square of
// their area in texels), as a `sample_cell` entry is.
fn group_share(g: Groups, cell: u32) -> vec4<f32> {
    let slot = cell_slot(g, cell);
    var count = 0u;
    var sum = vec2<f32>(0.0);
    for (var j = 0u; j < M * M; j += 1u) {
        if cell_slot(g, j) == slot {
            count += 1u;
            sum += cell_point(j);
        }
    }
    let centroid = sum / f32(count);
    return vec4<f32>(f32(count) / f32(M * M), centroid - cell_point(cell), sqrt(f32(count)));
}

// A window sample as the grouping compares it: view-space position and normal, and material.
struct WindowSample {
    position: vec3<f32>,
    normal: vec3<f32>,
    material: i32,
}

fn window_sample(origin: vec2<i32>, cell: u32) -> WindowSample {
    let texel = origin + cell_offset(cell);
    let nm = load_normal_material(texel);
    let position = view_ray(vec2<f32>(texel) + 0.5) * linear_depth(texel);
    let normal = (frame.view * vec4<f32>(nm.xyz, 0.0)).xyz;
    return WindowSample(position, normal, i32(nm.w));
}

// Whether `b` lies on the surface of `a`. Every background sample lies on one surface.
fn same_surface(a: WindowSample, b: WindowSample) -> bool {
    if a.material != b.material {
        return false;
    }
    if a.material == BACKGROUND {
        return true;
    }
    let gap = abs(dot(b.position - a.position, a.normal));
    return dot(a.normal, b.normal) >= SURFACE_COS && gap <= SURFACE_GAP * -a.position.z;
}

struct CoverageOut {
    @location(0) count: u32,
    @location(1) groups: vec4<u32>,
}

// The window's cells as points, for the nearest-sample searches below.
fn cell_point(cell: u32) -> vec2<f32> {
    return vec2<f32>(f32(cell % M), f32(cell / M));
}

// The cells of the first four surfaces of a window, as masks; a cell in none of them is a
// surface of its own (a window of more than four surfaces is shaded sample by sample there).
fn surface_cells(surfaces: vec4<u32>, cell: u32) -> u32 {
    let bit = 1u << cell;
    if (surfaces.x & bit) != 0u {
        return surfaces.x;
    }
    if (surfaces.y & bit) != 0u {
        return surfaces.y;
    }
    if (surfaces.z & bit) != 0u {
        return surfaces.z;
    }
    if (surfaces.w & bit) != 0u {
        return surfaces.w;
    }
    return bit;
}

// The cell of `cells` (a non-empty mask) nearest to `point`, the lowest on a tie.
fn nearest_cell(cells: u32, point: vec2<f32>) -> u32 {
    var rest = cells;
    var best = firstTrailingBit(cells);
    var best_distance = 1e9;
    while rest != 0u {
        let cell = firstTrailingBit(rest);
        rest &= rest - 1u;
        let d = cell_point(cell) - point;
        if dot(d, d) < best_distance {
            best = cell;
            best_distance = dot(d, d);
        }
    }
    return best;
}

// The centroid of the cells of a non-empty mask.
fn cells_centroid(cells: u32) -> vec2<f32> {
    var rest = cells;
    var sum = vec2<f32>(0.0);
    while rest != 0u {
        sum += cell_point(firstTrailingBit(rest));
        rest &= rest - 1u;
    }
    return sum / f32(countOneBits(cells));
}

// Whether `material` has a base-colour texture. A pixel with one is filtered at the
// reference's rate: a test on a few of its samples (the texture term of `-cells`) missed the
// checker detail of one pixel in ten on the texture scene.
fn has_base_texture(material: i32) -> bool {
#ifdef TEXTURED
    return material != BACKGROUND && materials[material].texture >= 0;
#else
    return false;
#endif
}

@fragment
fn evaluate_coverage(@builtin(position) position: vec4<f32>) -> CoverageOut {
    let pixel = vec2<i32>(position.xy);
    let origin = pixel * i32(M);
    let total = M * M;
    let window = (1u << total) - 1u;
    // Each sample joins the first surface it lies on, in cell order, or starts a new one. The
    // first samples of the first four surfaces are kept as variables: lavapipe spills a private
    // array that is indexed by a variable to memory, lane by lane.
    var surfaces = vec4<u32>(0u);
    var found = 0u;
    var first0: WindowSample;
    var first1: WindowSample;
    var first2: WindowSample;
    var first3: WindowSample;
    var textured = false;
    for (var cell = 0u; cell < total; cell += 1u) {
        let sample = window_sample(origin, cell);
        let bit = 1u << cell;
        if found > 0u && same_surface(first0, sample) {
            surfaces.x |= bit;
        } else if found > 1u && same_surface(first1, sample) {
            surfaces.y |= bit;
        } else if found > 2u && same_surface(first2, sample) {
            surfaces.z |= bit;
        } else if found > 3u && same_surface(first3, sample) {
            surfaces.w |= bit;
        } else {
            textured = textured || has_base_texture(sample.material);
        }
        if found < 4u && ((surfaces.x | surfaces.y | surfaces.z | surfaces.w) & bit) == 0u {
            switch found {
                case 0u: { first0 = sample; }
                case 1u: { first1 = sample; }
                case 2u: { first2 = sample; }
                default: { first3 = sample; }
            }
            surfaces[found] = bit;
            found += 1u;
        }
    }
    // Each surface is shaded at its sample nearest to its cells' centroid; a cell in none of
    // the four is shaded itself.
    var shaded = window & ~(surfaces.x | surfaces.y | surfaces.z | surfaces.w);
    for (var s = 0u; s < found; s += 1u) {
        shaded |= 1u << nearest_cell(surfaces[s], cells_centroid(surfaces[s]));
    }
    // Where the shading metric asks for n samples, the first n of the dither order are
    // shaded too.
    if FORCE_ALL {
        shaded = window;
    } else if USE_SHADING {
        let extra = min(floor(shading_k(pixel) * f32(total) + 0.5), f32(total - 1u));
        for (var rank = 1u; rank <= u32(extra); rank += 1u) {
            shaded |= 1u << window_cell(rank);
        }
    }
    // Every cell is stood for by the nearest shaded cell of its surface; slots in cell order.
    var slots = vec2<u32>(0u);
    for (var cell = 0u; cell < total; cell += 1u) {
        let standing = nearest_cell(shaded & surface_cells(surfaces, cell), cell_point(cell));
        let slot = countOneBits(shaded & ((1u << standing) - 1u));
        if cell < 8u {
            slots.x |= slot << (4u * cell);
        } else {
            slots.y |= slot << (4u * (cell - 8u));
        }
    }
    let flags = shaded | select(0u, TEXTURE_VARIES, textured);
    return CoverageOut(countOneBits(shaded), vec4<u32>(flags, slots, 0u));
}

// `emit` for `-coverage`: each pixel of n > 1 lists its shaded cells, in cell order.
@compute @workgroup_size(64)
fn emit_groups(@builtin(global_invocation_id) id: vec3<u32>) {
    let size = textureDimensions(counts);
    let y = id.x;
    if y >= size.y {
        return;
    }
    var offset = row_offsets[y];
    for (var x = 0u; x < size.x; x += 1u) {
        let pixel = vec2<i32>(i32(x), i32(y));
        let n = textureLoad(counts, pixel, 0).r;
        pixel_offsets[y * size.x + x] = offset;
        if n == 1u {
            continue;
        }
        var rest = load_groups(pixel).shaded;
        while rest != 0u {
            entries[offset] = list_entry(pixel * i32(M) + cell_offset(firstTrailingBit(rest)), n);
            rest &= rest - 1u;
            offset += 1u;
        }
    }
}

struct ShadeOut {
    @location(0) color: vec4<f32>,
    @location(1) slope: vec4<f32>,
}

@fragment
fn shade_first_coverage(@builtin(position) position: vec4<f32>) -> ShadeOut {
    let texel = window_texel(vec2<i32>(position.xy), 0u);
    let cell = sample_cell(1u, 0u);
    let moved = move_on_surface(texel, cell.yz);
    let lit = light_surface(texel, moved.surface, moved.position, cell.w);
    return ShadeOut(lit.color, vec4<f32>(lit.slope, 0.0));
}

// A listed sample, shaded for the cells it stands for. Where textures vary inside its pixel,
// `color` holds its radiance less its albedo times the slope: the part that the albedo of each
// cell it stands for is added to (gather_coverage).
@fragment
fn shade_group(@builtin(position) position: vec4<f32>) -> ShadeOut {
    let texel = entry_texel(list_entries[compact_index(vec2<u32>(position.xy))]);
    let m = vec2<i32>(i32(M));
    let g = load_groups(texel / m);
    let share = group_share(g, u32((texel.y % m.y) * m.x + texel.x % m.x));
    let moved = move_on_surface(texel, share.yz);
    let lit = light_surface(texel, moved.surface, moved.position, share.w);
    var color = lit.color;
    if g.detail {
        color = vec4<f32>(color.rgb - lit.albedo * lit.slope, color.a);
    }
    return ShadeOut(color, vec4<f32>(lit.slope, 0.0));
}

// The slopes in albedo that shade_first_coverage and shade_group wrote beside their colours.
@group(2) @binding(14) var first_slope: texture_2d<f32>;
@group(2) @binding(15) var extra_slopes: texture_2d<f32>;

// The albedo of the sample at `texel` as the reference reads it; black for the background,
// whose slope is 0.
fn fine_sample_albedo(texel: vec2<i32>) -> vec3<f32> {
    let s = load_surface(texel);
    return select(surface_albedo(s, 1.0), vec3<f32>(0.0), s.material == BACKGROUND);
}

// The mean albedo of the pixel's cells, each read as the reference reads it.
fn pixel_albedo(pixel: vec2<i32>) -> vec3<f32> {
    var sum = vec3<f32>(0.0);
    for (var cell = 0u; cell < M * M; cell += 1u) {
        sum += fine_sample_albedo(pixel * i32(M) + cell_offset(cell));
    }
    return sum / f32(M * M);
}

// A pixel is the mean of its cells, each the colour of the shaded sample that stands for it.
// Where textures vary inside the pixel, a cell's colour is that sample's light carried to the
// cell's own albedo: radiance is affine in albedo (Lit.slope), so it is the listed part plus
// the albedo times the slope, and for S (which the metric reads whole) S moved by the pixel's
// mean albedo less its own.
@fragment
fn gather_coverage(@builtin(position) position: vec4<f32>) -> @location(0) vec4<f32> {
    let pixel = vec2<i32>(position.xy);
    let n = textureLoad(counts, pixel, 0).r;
    let g = load_groups(pixel);
    if n == 1u {
        let s = textureLoad(first, pixel, 0);
        if !g.detail {
            return s;
        }
        let cell = sample_cell(1u, 0u);
        let surface = move_on_surface(window_texel(pixel, 0u), cell.yz).surface;
        let used = select(surface_albedo(surface, cell.w), vec3<f32>(0.0), surface.material == BACKGROUND);
        let moved = s.rgb + (pixel_albedo(pixel) - used) * textureLoad(first_slope, pixel, 0).rgb;
        return vec4<f32>(max(moved, vec3<f32>(0.0)), s.a);
    }
    let width = textureDimensions(first).x;
    let base = list_offsets[u32(pixel.y) * width + u32(pixel.x)];
    var sum = vec4<f32>(0.0);
    if g.detail {
        for (var cell = 0u; cell < M * M; cell += 1u) {
            let at = compact_texel(base + cell_slot(g, cell));
            let albedo = fine_sample_albedo(pixel * i32(M) + cell_offset(cell));
            let color = textureLoad(extra_samples, at, 0);
            let carried = color.rgb + albedo * textureLoad(extra_slopes, at, 0).rgb;
            sum += vec4<f32>(max(carried, vec3<f32>(0.0)), color.a);
        }
        return sum / f32(M * M);
    }
    // Elsewhere each shaded sample is read once, weighted by its cells.
    let cells = slot_cells(g);
    for (var slot = 0u; slot < n; slot += 1u) {
        let count = (cells[slot / 6u] >> (5u * (slot % 6u))) & 31u;
        sum += textureLoad(extra_samples, compact_texel(base + slot), 0) * f32(count);
    }
    return sum / f32(M * M);
}

// The number of cells each slot stands for, five bits a slot, six slots a word.
fn slot_cells(g: Groups) -> vec3<u32> {
    var cells = vec3<u32>(0u);
    for (var cell = 0u; cell < M * M; cell += 1u) {
        let slot = cell_slot(g, cell);
        cells[slot / 6u] += 1u << (5u * (slot % 6u));
    }
    return cells;
}
