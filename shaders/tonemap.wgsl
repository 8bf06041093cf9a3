// The tonemap pass of an HDR scene: sanitized linear HDR, exposed, to display-relative linear
// light in [0, 1] (Rgba32Float: PQ's darkest 10-bit codes lie below f16's smallest values),
// for the display pass to encode.

#include "lib/common.wgsl"
#include "lib/color.wgsl"

@group(2) @binding(0) var hdr: texture_2d<f32>;

@fragment
fn tonemap(@builtin(position) position: vec4<f32>) -> @location(0) vec4<f32> {
    let radiance = exposed(textureLoad(hdr, vec2<i32>(position.xy), 0).rgb, frame.display.x);
    return vec4<f32>(tonemap_rgb(radiance), 1.0);
}
