// Adaptive supersampling, part of shaders/adaptive.wgsl: the metric (evaluate).

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
    var sums = DepthSums(0.0, 0.0, 0.0);
    for (var row = 0u; row < M; row += 2u) {
        let left = depth_block(origin + vec2<i32>(0, i32(row)));
        var right = vec4<f32>(0.0);
        if M > 2u {
            right = depth_block(origin + vec2<i32>(2, i32(row)));
        }
        if row == 0u {
            // The window's first depth: its top-left texel, read in the first block.
            sums.shift = left.w;
        }
        add_depth_row(&sums, left.wz, right.wz);
        if row + 1u < M {
            add_depth_row(&sums, left.xy, right.xy);
        }
    }
    return sums;
}

// max(C_DEPTH · variance, C_NORMAL · cone) of the window, before the M² scaling; see
// geometry_metric in technique/adaptive/metric.rs for the cases. The variance is shifted by the window's first
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
    // Each normal is read once and kept for the cone's second loop: reading it again there cost
    // more than keeping sixteen vectors (M ≤ 4).
    var units: array<vec3<f32>, 16>;
    for (var i = 0u; i < n; i += 1u) {
        let nm = load_normal_material(origin + vec2<i32>(i32(i % M), i32(i / M)));
        let length_n = length(nm.xyz);
        covered += u32(i32(nm.w) != BACKGROUND);
        units[i] = select(vec3<f32>(0.0), nm.xyz / length_n, length_n > 1e-6);
        normal_sum += units[i];
    }
    if covered == 0u {
        return 0.0;
    }
    if covered < n {
        // A silhouette against the background.
        return 1.0;
    }
    // Only a window that geometry covers reads its depths.
    let depths = window_depths(origin);
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
            min_cos = min(min_cos, abs(dot(units[i], mean_normal)));
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
    let rays = pixel_rays(pixel);
    let eye = rays.half_diagonal / length(rays.centre);
    return Turn(acos(clamp(min_cos, -1.0, 1.0)) + 0.5 * eye, surface_reach(rays, normal, depth, v));
}

// The view ray through the pixel's centre, and how far the ray through its corner lies from it.
struct PixelRays {
    centre: vec3<f32>,
    half_diagonal: f32,
}

fn pixel_rays(pixel: vec2<i32>) -> PixelRays {
    let origin = vec2<f32>(pixel * i32(M));
    let centre = view_ray(origin + 0.5 * f32(M));
    return PixelRays(centre, length(centre - view_ray(origin)));
}

// The pixel's half-diagonal on a surface of unit `normal` at view depth `depth` seen along `v`, in
// world units: a grazing view stretches it (at most fourfold).
fn surface_reach(rays: PixelRays, normal: vec3<f32>, depth: f32, v: vec3<f32>) -> f32 {
    return depth * rays.half_diagonal / max(abs(dot(normal, v)), 0.25);
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
    return shown_span(pixel, above, below);
}

// The metric's luma range from S's luminance lowered by `below` to it raised by `above`, as the
// display shows them (shown_luma).
fn shown_span(pixel: vec2<i32>, above: f32, below: f32) -> f32 {
    let exposure = frame.display.x;
    let lum = luminance(sanitize3(textureLoad(first, pixel, 0).rgb));
    return shown_luma((lum + above) * exposure) - shown_luma((lum - below) * exposure);
}

// The metric's luma of exposed linear luminance `x` as the display shows it: through the
// scene's tonemap (set by technique/adaptive/passes.rs; without one, color.wgsl's defaults clamp to
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
