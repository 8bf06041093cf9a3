// Finite values from anything: WGSL lets the compiler assume floats are finite, so a test such
// as `x != x` may be folded away. These look at the bits, which no such assumption touches.

// The largest finite value of the Rgba16Float HDR target: what +Inf stands for.
const HALF_MAX: f32 = 65504.0;

// Radiance the display can use: NaN and −Inf become 0, +Inf the HDR target's largest value,
// negatives 0.
fn sanitize(x: f32) -> f32 {
    let bits = bitcast<u32>(x);
    if (bits & 0x7f800000u) == 0x7f800000u {
        return select(0.0, HALF_MAX, bits == 0x7f800000u);
    }
    return clamp(x, 0.0, HALF_MAX);
}

fn sanitize3(c: vec3<f32>) -> vec3<f32> {
    return vec3<f32>(sanitize(c.r), sanitize(c.g), sanitize(c.b));
}

// Whether every channel is a finite number (neither NaN nor ±Inf), by the bits.
fn is_finite3(c: vec3<f32>) -> bool {
    let exponents = bitcast<vec3<u32>>(c) & vec3<u32>(0x7f800000u);
    return all(exponents != vec3<u32>(0x7f800000u));
}
