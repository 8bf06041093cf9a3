// The display pass: display-relative linear light to code values. In an HDR scene its input is
// the tonemap pass's output; in an LDR scene it is the HDR image itself, sanitized, exposed and
// clamped (EXPOSE). Grain follows the pixel's position in the whole frame (frame.display.yz is
// the rendered tile's origin), so every mode of a scene, and the ground truth's tiles, share it.

#include "lib/common.wgsl"
#include "lib/color.wgsl"

override EXPOSE: bool = false;

@group(2) @binding(0) var linear: texture_2d<f32>;

@fragment
fn display(@builtin(position) position: vec4<f32>) -> @location(0) vec4<f32> {
    let exposure = select(1.0, frame.display.x, EXPOSE);
    let color = exposed(textureLoad(linear, vec2<i32>(position.xy), 0).rgb, exposure);
    let pixel = vec2<u32>(position.xy) + vec2<u32>(frame.display.yz);
    return vec4<f32>(quantize(color, pixel), 1.0);
}
