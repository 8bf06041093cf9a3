// Encodes the linear HDR image for display: exposure, clamp to [0, 1], sRGB transfer. The 8-bit
// target quantizes; quality metrics are computed on this image.

#include "lib/common.wgsl"

@group(2) @binding(0) var hdr: texture_2d<f32>;

@fragment
fn display(@builtin(position) position: vec4<f32>) -> @location(0) vec4<f32> {
    let linear = textureLoad(hdr, vec2<i32>(position.xy), 0).rgb;
    return vec4<f32>(display_encode(linear), 1.0);
}
