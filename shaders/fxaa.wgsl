// FXAA 3.11 (Timothy Lottes, NVIDIA 2011), the quality path with its default preset 12 (5 search steps),
// on the display-encoded 1×1 image. Luma is computed here from the encoded RGB with FXAA's
// Rec. 601 weights instead of being stored in alpha, so the display image stays opaque. The
// result is rounded back to the display's code values (STEPS, from lib/color.wgsl).
//
// Bilinear taps are four texture loads blended here: lavapipe's sampler costs about ten
// loads per bilinear tap, and took FXAA from 10 to 74 ms at 1024×768 (weights here are also
// exact, where a sampler rounds them to 8 bits).

#include "lib/common.wgsl"
#include "lib/color.wgsl"

// Amount of sub-pixel aliasing removal (FXAA's default 0.75).
override SUBPIX: f32 = 0.75;
// Local contrast, relative to the brightest neighbour, below which a pixel is left alone.
override EDGE_THRESHOLD: f32 = 0.166;
// Local contrast below which a dark pixel is left alone.
override EDGE_THRESHOLD_MIN: f32 = 0.0833;

// Preset 12's step lengths along the edge, in pixels. Preset 39 (12 steps of 1–8 pixels) took
// 81 ms against 12's 37 at 1024×768 on `thin`, and came 0.46 dB further from the truth.
const SEARCH_STEPS: u32 = 5u;
const SEARCH: array<f32, 5> = array<f32, 5>(1.0, 1.5, 2.0, 4.0, 12.0);

@group(2) @binding(0) var encoded: texture_2d<f32>;

// FXAA's luma: the Rec. 601 weights of FXAA 3.11's luma pass, on the encoded colour, not the
// renderer's Rec. 709 `luminance`, so that the edges it finds are its reference's.
fn luma(c: vec3<f32>) -> f32 {
    return dot(c, vec3<f32>(0.299, 0.587, 0.114));
}

fn texel_luma(p: vec2<i32>, size: vec2<i32>) -> f32 {
    return luma(textureLoad(encoded, clamp(p, vec2<i32>(0), size - 1), 0).rgb);
}

// The bilinear blend at `uv` with clamp-to-edge addressing.
fn bilinear(uv: vec2<f32>, size: vec2<i32>) -> vec3<f32> {
    let t = uv * vec2<f32>(size) - 0.5;
    let base = floor(t);
    let f = t - base;
    let p = vec2<i32>(base);
    let hi = size - 1;
    let p0 = clamp(p, vec2<i32>(0), hi);
    let p1 = clamp(p + 1, vec2<i32>(0), hi);
    let top = mix(textureLoad(encoded, p0, 0).rgb, textureLoad(encoded, vec2<i32>(p1.x, p0.y), 0).rgb, f.x);
    let bottom = mix(textureLoad(encoded, vec2<i32>(p0.x, p1.y), 0).rgb, textureLoad(encoded, p1, 0).rgb, f.x);
    return mix(top, bottom, f.y);
}

fn sample_luma(uv: vec2<f32>, size: vec2<i32>) -> f32 {
    return luma(bilinear(uv, size));
}

// The edge's direction, from second differences over the 3×3 neighbourhood of `p` (whose
// centre and edge neighbours the caller has read), and the neighbourhood's weighted sum that
// the sub-pixel term starts from.
struct Direction {
    horz_span: bool,
    subpix_a: f32,
}

fn edge_direction(p: vec2<i32>, size: vec2<i32>, luma_m: f32, luma_n: f32, luma_s: f32, luma_e: f32, luma_w: f32) -> Direction {
    let luma_nw = texel_luma(p + vec2<i32>(-1, -1), size);
    let luma_se = texel_luma(p + vec2<i32>(1, 1), size);
    let luma_ne = texel_luma(p + vec2<i32>(1, -1), size);
    let luma_sw = texel_luma(p + vec2<i32>(-1, 1), size);
    let luma_ns = luma_n + luma_s;
    let luma_we = luma_w + luma_e;
    let luma_nese = luma_ne + luma_se;
    let luma_nwne = luma_nw + luma_ne;
    let luma_nwsw = luma_nw + luma_sw;
    let luma_swse = luma_sw + luma_se;
    let edge_horz = abs(-2.0 * luma_w + luma_nwsw) + abs(-2.0 * luma_m + luma_ns) * 2.0
        + abs(-2.0 * luma_e + luma_nese);
    let edge_vert = abs(-2.0 * luma_s + luma_swse) + abs(-2.0 * luma_m + luma_we) * 2.0
        + abs(-2.0 * luma_n + luma_nwne);
    let horz_span = edge_horz >= edge_vert;
    let subpix_a = (luma_ns + luma_we) * 2.0 + luma_nwsw + luma_nese;
    return Direction(horz_span, subpix_a);
}

// The span's two ends: from `pos_b` out along −`off_np` and +`off_np`, by preset 12's steps,
// until the luma there differs from the pair's mean (`luma_nn` is the pair's sum) by at least
// `gradient_scaled`, or the steps run out. `end_n`, `end_p`: that difference at each end.
struct Span {
    pos_n: vec2<f32>,
    pos_p: vec2<f32>,
    end_n: f32,
    end_p: f32,
}

fn search_span(pos_b: vec2<f32>, off_np: vec2<f32>, luma_nn: f32, gradient_scaled: f32, size: vec2<i32>) -> Span {
    var pos_n = pos_b - off_np * SEARCH[0];
    var pos_p = pos_b + off_np * SEARCH[0];
    var end_n = sample_luma(pos_n, size) - luma_nn * 0.5;
    var end_p = sample_luma(pos_p, size) - luma_nn * 0.5;
    var done_n = abs(end_n) >= gradient_scaled;
    var done_p = abs(end_p) >= gradient_scaled;
    if !done_n {
        pos_n -= off_np * SEARCH[1];
    }
    if !done_p {
        pos_p += off_np * SEARCH[1];
    }
    for (var i = 2u; i < SEARCH_STEPS && !(done_n && done_p); i++) {
        if !done_n {
            end_n = sample_luma(pos_n, size) - luma_nn * 0.5;
            done_n = abs(end_n) >= gradient_scaled;
            if !done_n {
                pos_n -= off_np * SEARCH[i];
            }
        }
        if !done_p {
            end_p = sample_luma(pos_p, size) - luma_nn * 0.5;
            done_p = abs(end_p) >= gradient_scaled;
            if !done_p {
                pos_p += off_np * SEARCH[i];
            }
        }
    }
    return Span(pos_n, pos_p, end_n, end_p);
}

// How far to shift across the edge from `pos_m`: towards the nearer end of the span, if its
// luma crosses the right way, or by the sub-pixel amount, whichever is larger.
fn span_offset(pos_m: vec2<f32>, span: Span, horz_span: bool, luma_m_below: bool, subpix_c: f32) -> f32 {
    let dst_n = select(pos_m.x - span.pos_n.x, pos_m.y - span.pos_n.y, !horz_span);
    let dst_p = select(span.pos_p.x - pos_m.x, span.pos_p.y - pos_m.y, !horz_span);
    let nearer_n = dst_n < dst_p;
    let good_span = select((span.end_p < 0.0) != luma_m_below, (span.end_n < 0.0) != luma_m_below, nearer_n);
    let pixel_offset = select(0.0, 0.5 - min(dst_n, dst_p) / (dst_n + dst_p), good_span);
    let subpix_f = (-2.0 * subpix_c + 3.0) * subpix_c * subpix_c;
    let offset = max(pixel_offset, subpix_f * subpix_f * SUBPIX);
    return offset;
}

@fragment
fn fxaa(@builtin(position) position: vec4<f32>) -> @location(0) vec4<f32> {
    let size = vec2<i32>(textureDimensions(encoded));
    let rcp = 1.0 / vec2<f32>(size);
    let p = vec2<i32>(position.xy);
    let center = textureLoad(encoded, p, 0);
    let luma_m = luma(center.rgb);
    var luma_n = texel_luma(p + vec2<i32>(0, -1), size);
    var luma_s = texel_luma(p + vec2<i32>(0, 1), size);
    let luma_e = texel_luma(p + vec2<i32>(1, 0), size);
    let luma_w = texel_luma(p + vec2<i32>(-1, 0), size);
    let range_max = max(max(max(luma_n, luma_s), max(luma_e, luma_w)), luma_m);
    let range_min = min(min(min(luma_n, luma_s), min(luma_e, luma_w)), luma_m);
    let range = range_max - range_min;
    if range < max(EDGE_THRESHOLD_MIN, range_max * EDGE_THRESHOLD) {
        return vec4<f32>(center.rgb, 1.0);
    }

    // Is the edge horizontal or vertical?
    let direction = edge_direction(p, size, luma_m, luma_n, luma_s, luma_e, luma_w);
    let horz_span = direction.horz_span;

    // The side of the edge with the steeper gradient.
    var length_sign = select(rcp.x, rcp.y, horz_span);
    if !horz_span {
        luma_n = luma_w;
        luma_s = luma_e;
    }
    let subpix_b = direction.subpix_a * (1.0 / 12.0) - luma_m;
    let gradient_n = luma_n - luma_m;
    let gradient_s = luma_s - luma_m;
    let pair_n = abs(gradient_n) >= abs(gradient_s);
    let gradient = max(abs(gradient_n), abs(gradient_s));
    if pair_n {
        length_sign = -length_sign;
    }
    let luma_nn = select(luma_s + luma_m, luma_n + luma_m, pair_n);
    // range ≥ EDGE_THRESHOLD_MIN > 0 past the early exit.
    let subpix_c = saturate(abs(subpix_b) / range);

    // Walk along the edge, half a pixel towards the steeper side, until the luma of the pair
    // changes by a quarter of the gradient at each end.
    let pos_m = position.xy * rcp;
    let off_np = select(vec2<f32>(0.0, rcp.y), vec2<f32>(rcp.x, 0.0), horz_span);
    var pos_b = pos_m;
    if horz_span {
        pos_b.y += length_sign * 0.5;
    } else {
        pos_b.x += length_sign * 0.5;
    }
    let gradient_scaled = gradient * 0.25;
    let luma_m_below = luma_m - luma_nn * 0.5 < 0.0;
    let span = search_span(pos_b, off_np, luma_nn, gradient_scaled, size);

    let offset = span_offset(pos_m, span, horz_span, luma_m_below, subpix_c);
    var pos = pos_m;
    if horz_span {
        pos.y += offset * length_sign;
    } else {
        pos.x += offset * length_sign;
    }
    return vec4<f32>(requantize(bilinear(pos, size)), 1.0);
}
