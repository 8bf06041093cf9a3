// Temporal anti-aliasing on the linear HDR image, after Karis (2014), Playdead's INSIDE and
// Bevy's TAA. Every frame the projection is jittered by a Halton(2, 3) offset within the pixel
// (`jitter` in the frame uniforms). This pass fetches the history (the earlier frames,
// resolved) where the pixel's surface was in the previous frame, through a Catmull-Rom
// filter; clips it into the colour box of the new frame's 3×3 neighbourhood in YCoCg (its
// minimum and maximum, along the line to the box's centre); and blends the new sample in with
// weight 1 / n, n the frames the history averages: at most MOVING_FRAMES where the pixel
// moves (the blend factor of moving pixels is 0.1, Bevy's default) and STILL_FRAMES where it
// is still. After a reset the first frames are a plain average.
//
// Colours are blended after a reversible tonemap, c / (1 + max(c)) of the exposed radiance,
// so that one bright sample does not dominate its pixel for many frames. The motion is taken
// from the nearest surface in the 3×3 neighbourhood, so an edge in front is reprojected with
// its own motion. Texture loads only: lavapipe's bilinear sampler costs about ten loads a tap
// (see fxaa.wgsl). docs/taa.md measures the choices against the alternatives.

#include "lib/common.wgsl"
#include "lib/finite.wgsl"

override MOVING_FRAMES: f32 = 10.0;
override STILL_FRAMES: f32 = 32.0;
// Below this many pixels of motion in each axis, a pixel counts as still.
const STILL_MOTION: f32 = 0.01;
// The largest tonemapped channel the history keeps: the inverse of the tonemap is finite.
const COMPRESSED_MAX: f32 = 0.999;

// This frame's HDR image.
@group(2) @binding(0) var current: texture_2d<f32>;
// The previous frame's output: tonemapped colour, and in alpha the frames it averages.
@group(2) @binding(1) var history: texture_2d<f32>;
// xy: the pixels the surface moved since the previous frame (see gbuffer.wgsl).
@group(2) @binding(2) var gb_motion: texture_2d<f32>;
@group(2) @binding(3) var gb_depth: texture_depth_2d;

struct Resolved {
    // The anti-aliased radiance; alpha the new frame's (the stall's result).
    @location(0) color: vec4<f32>,
    // The same, tonemapped, and in alpha the frames it averages: the next frame's history.
    @location(1) history_next: vec4<f32>,
}

fn max3(c: vec3<f32>) -> f32 {
    return max(c.r, max(c.g, c.b));
}

fn compress(c: vec3<f32>) -> vec3<f32> {
    return c / (1.0 + max3(c));
}

fn expand(c: vec3<f32>) -> vec3<f32> {
    let kept = clamp(c, vec3<f32>(0.0), vec3<f32>(COMPRESSED_MAX));
    return kept / (1.0 - max3(kept));
}

fn to_ycocg(c: vec3<f32>) -> vec3<f32> {
    return vec3<f32>(
        0.25 * c.r + 0.5 * c.g + 0.25 * c.b,
        0.5 * c.r - 0.5 * c.b,
        -0.25 * c.r + 0.5 * c.g - 0.25 * c.b,
    );
}

fn from_ycocg(c: vec3<f32>) -> vec3<f32> {
    return vec3<f32>(c.x + c.y - c.z, c.x + c.z, c.x - c.y - c.z);
}

fn clamped(p: vec2<i32>, size: vec2<i32>) -> vec2<i32> {
    return clamp(p, vec2<i32>(0), size - 1);
}

// This frame's colour at `p` (clamped to the image), exposed and tonemapped.
fn current_at(p: vec2<i32>, size: vec2<i32>) -> vec3<f32> {
    return compress(sanitize3(textureLoad(current, clamped(p, size), 0).rgb) * frame.display.x);
}

// The four Catmull-Rom weights of the texels at −1, 0, 1, 2 around a point `f` ∈ [0, 1) past
// texel 0.
fn catmull_rom(f: f32) -> vec4<f32> {
    return vec4<f32>(
        f * (-0.5 + f * (1.0 - 0.5 * f)),
        1.0 + f * f * (-2.5 + 1.5 * f),
        f * (0.5 + f * (2.0 - 1.5 * f)),
        f * f * (-0.5 + 0.5 * f),
    );
}

// The history's tonemapped colour at `point` (in pixels, a texel's centre at + 0.5) through
// the 4×4 Catmull-Rom filter without its four corner texels, whose weights are the smallest
// (at most 1/16 each; Jimenez, "Filmic SMAA", 2016): 12 loads instead of 16, the weights
// renormalised, edges clamped; the overshoot below 0 is cut.
fn history_at(point: vec2<f32>, size: vec2<i32>) -> vec3<f32> {
    let t = point - 0.5;
    let base = floor(t);
    let wx = catmull_rom(t.x - base.x);
    let wy = catmull_rom(t.y - base.y);
    let origin = vec2<i32>(base) - 1;
    var sum = vec3<f32>(0.0);
    var weights = 0.0;
    for (var j = 0; j < 4; j += 1) {
        // Rows 0 and 3 take their two middle texels, rows 1 and 2 all four.
        let edge = j == 0 || j == 3;
        for (var i = select(0, 1, edge); i < select(4, 3, edge); i += 1) {
            let w = wx[i] * wy[j];
            sum += textureLoad(history, clamped(origin + vec2<i32>(i, j), size), 0).rgb * w;
            weights += w;
        }
    }
    return max(sum / weights, vec3<f32>(0.0));
}

// Moves `past` along the line to the box's centre until it lies in the box (centre ± extent).
fn clip_to_box(past: vec3<f32>, centre: vec3<f32>, extent: vec3<f32>) -> vec3<f32> {
    let offset = past - centre;
    let reach = max3(abs(offset) / max(extent, vec3<f32>(1e-7)));
    return select(past, centre + offset / reach, reach > 1.0);
}

@fragment
fn taa(@builtin(position) position: vec4<f32>) -> Resolved {
    let size = vec2<i32>(textureDimensions(current));
    let p = vec2<i32>(position.xy);
    let raw = textureLoad(current, p, 0);
    if !is_finite3(raw.rgb) {
        // The frame's checks see it in the HDR image; the history starts again here.
        return Resolved(raw, vec4<f32>(0.0));
    }
    let exposure = max(frame.display.x, 1e-20);
    let now = current_at(p, size);

    // The neighbourhood's colour box in YCoCg, and its nearest surface (reversed depth:
    // larger is nearer).
    var low = vec3<f32>(3.4e38);
    var high = vec3<f32>(-3.4e38);
    var nearest = p;
    var nearest_depth = -1.0;
    for (var dy = -1; dy <= 1; dy += 1) {
        for (var dx = -1; dx <= 1; dx += 1) {
            let q = clamped(p + vec2<i32>(dx, dy), size);
            let c = to_ycocg(current_at(q, size));
            low = min(low, c);
            high = max(high, c);
            let d = textureLoad(gb_depth, q, 0);
            if d > nearest_depth {
                nearest_depth = d;
                nearest = q;
            }
        }
    }
    let motion = textureLoad(gb_motion, nearest, 0).xy;
    let previous = position.xy - motion;
    let inside = all(previous >= vec2<f32>(0.0)) && all(previous <= vec2<f32>(size));
    if frame.history.x == 0.0 || !inside {
        return Resolved(raw, vec4<f32>(now, 1.0));
    }
    let past = from_ycocg(clip_to_box(to_ycocg(history_at(previous, size)), 0.5 * (low + high), 0.5 * (high - low)));
    let still = all(abs(motion) < vec2<f32>(STILL_MOTION));
    let averaged = textureLoad(history, clamped(vec2<i32>(previous), size), 0).a;
    let frames = min(averaged + 1.0, select(MOVING_FRAMES, STILL_FRAMES, still));
    let blended = clamp(mix(past, now, 1.0 / frames), vec3<f32>(0.0), vec3<f32>(COMPRESSED_MAX));
    return Resolved(vec4<f32>(expand(blended) / exposure, raw.a), vec4<f32>(blended, frames));
}
