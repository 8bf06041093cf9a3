// The colour pipeline (Lottes, "Advanced Techniques and Optimization of HDR/VDR Color
// Pipelines", GDC 2016): sanitizing, the tonemap on max(R, G, B), transfer functions, grain,
// energy-preserving dither and quantization. `renderer/src/color.rs` holds the CPU twin of
// every function here and solves the constants.
//
// No function relies on infinities or NaN: WGSL lets the compiler assume finite floats, so a
// `x != x` test may be folded away and `pow(0.0, y)` (exp2(y · log2(0))) is not promised to be 0.

#include "lib/finite.wgsl"

// Tonemap: y = z / (z^SHOULDER · CURVE_B + CURVE_C), z = x^CONTRAST, on the largest channel.
override CONTRAST: f32 = 1.0;
override SHOULDER: f32 = 1.0;
override CURVE_B: f32 = 0.0;
override CURVE_C: f32 = 1.0;
override HDR_MAX: f32 = 1.0;
override CROSSTALK: f32 = 1.0;
override SATURATION: f32 = 1.0;
override CROSS_SATURATION: f32 = 1.0;

// Display: transfer 0 sRGB, 1 Rec. 709, 2 gamma 2.2, 3 PQ (linear 1 = PEAK_FRACTION of 10 000
// nits); code values 0…STEPS; dither 0 off, 1 symmetric, 2 asymmetric grain.
override TRANSFER: u32 = 0u;
override PEAK_FRACTION: f32 = 1.0;
override STEPS: f32 = 255.0;
override DITHER: u32 = 0u;
override DITHER_BLACK: f32 = 0.0;
override DITHER_BIGGEST: f32 = 0.0;
override DITHER_TOP: f32 = 1.0;

// Below this the tonemap returns black (its powers would underflow through log2(0)).
const PEAK_FLOOR: f32 = 1e-20;
const RATIO_FLOOR: f32 = 1e-12;

// Sanitized radiance times the exposure, kept finite however large the exposure.
fn exposed(c: vec3<f32>, exposure: f32) -> vec3<f32> {
    return min(sanitize3(c) * exposure, vec3<f32>(HALF_MAX));
}

// x^y for x ≥ 0, exactly 0 at 0.
fn power(x: f32, y: f32) -> f32 {
    return select(pow(max(x, 1e-30), y), 0.0, x <= 0.0);
}

// The tonemap curve on one value above PEAK_FLOOR: a grey's display-relative linear light.
fn tonemap_curve(peak: f32) -> f32 {
    let z = pow(min(peak, HDR_MAX), CONTRAST);
    return min(z / (pow(z, SHOULDER) * CURVE_B + CURVE_C), 1.0);
}

// Linear exposed HDR (finite, ≥ 0) to display-relative linear [0, 1].
fn tonemap_rgb(rgb: vec3<f32>) -> vec3<f32> {
    let peak = max(rgb.r, max(rgb.g, rgb.b));
    if peak <= PEAK_FLOOR {
        return vec3<f32>(0.0);
    }
    let mapped = tonemap_curve(peak);
    let white = power(mapped, CROSSTALK);
    let ratio = pow(max(rgb / peak, vec3<f32>(RATIO_FLOOR)), vec3<f32>(SATURATION / CROSS_SATURATION));
    return pow(mix(ratio, vec3<f32>(1.0), white), vec3<f32>(CROSS_SATURATION)) * mapped;
}

fn pq_encode(y: f32) -> f32 {
    let p = power(y, 0.1593017578125);
    return pow((0.8359375 + 18.8515625 * p) / (1.0 + 18.6875 * p), 78.84375);
}

// Display-relative linear [0, 1] to the signal.
fn transfer_encode(l: f32) -> f32 {
    switch TRANSFER {
        case 0u: {
            return select(1.055 * pow(max(l, 0.0031308), 1.0 / 2.4) - 0.055, 12.92 * l, l <= 0.0031308);
        }
        case 1u: {
            let alpha = 1.09929682680944;
            let beta = 0.018053968510807;
            return select(alpha * pow(max(l, beta), 0.45) - (alpha - 1.0), 4.5 * l, l < beta);
        }
        case 2u: {
            return power(l, 1.0 / 2.2);
        }
        default: {
            return pq_encode(l * PEAK_FRACTION);
        }
    }
}

fn pq_decode(signal: f32) -> f32 {
    let p = power(signal, 1.0 / 78.84375);
    return power(max(p - 0.8359375, 0.0) / (18.8515625 - 18.6875 * p), 1.0 / 0.1593017578125);
}

// The signal back to display-relative linear [0, 1]: the inverse of `transfer_encode`.
fn transfer_decode(s: f32) -> f32 {
    switch TRANSFER {
        case 0u: {
            return select(pow((max(s, 0.04045) + 0.055) / 1.055, 2.4), s / 12.92, s <= 0.04045);
        }
        case 1u: {
            let alpha = 1.09929682680944;
            let beta = 0.018053968510807;
            return select(pow((max(s, 4.5 * beta) + alpha - 1.0) / alpha, 1.0 / 0.45), s / 4.5, s < 4.5 * beta);
        }
        case 2u: {
            return power(s, 2.2);
        }
        default: {
            return pq_decode(s) / PEAK_FRACTION;
        }
    }
}

// PCG's output permutation as a hash (Jarzynski & Olano 2020): integers only, so the grain is
// the same bits on every device.
fn hash(v: u32) -> u32 {
    let state = v * 747796405u + 2891336453u;
    let word = ((state >> ((state >> 28u) + 4u)) ^ state) * 277803737u;
    return (word >> 22u) ^ word;
}

// The grain of one channel of a pixel of the whole frame, in [−1, 1] with mean 0.
fn grain(pixel: vec2<u32>, channel: u32) -> f32 {
    let unit = (f32(hash(hash(hash(pixel.x) + pixel.y) + channel) >> 8u) + 0.5) / 16777216.0;
    if DITHER == 2u {
        return select(3.0 * (unit - 2.0 / 3.0), -0.75 * unit, unit < 2.0 / 3.0);
    }
    return 2.0 * unit - 1.0;
}

// Display-relative linear light to the code value / STEPS: grain scaled by
// min(colour + black, biggest, top − colour) so that blacks stay black, every step is dithered
// and no grain rounds past the top code, then the transfer function and rounding. Exact multiples of 1 / STEPS pass any unorm target
// unchanged.
fn quantize(linear: vec3<f32>, pixel: vec2<u32>) -> vec3<f32> {
    var l = clamp(linear, vec3<f32>(0.0), vec3<f32>(1.0));
    if DITHER != 0u {
        let g = vec3<f32>(grain(pixel, 0u), grain(pixel, 1u), grain(pixel, 2u));
        let amplitude = min(min(l + DITHER_BLACK, vec3<f32>(DITHER_BIGGEST)), DITHER_TOP - l);
        l = clamp(l + g * amplitude, vec3<f32>(0.0), vec3<f32>(1.0));
    }
    let signal = vec3<f32>(transfer_encode(l.r), transfer_encode(l.g), transfer_encode(l.b));
    return requantize(signal);
}

// A signal in [0, 1] rounded to the nearest code value.
fn requantize(signal: vec3<f32>) -> vec3<f32> {
    return round(clamp(signal, vec3<f32>(0.0), vec3<f32>(1.0)) * STEPS) / STEPS;
}
