// Box-filters the M·w × M·h supersampled image down to w × h.

#include "lib/common.wgsl"

override M: u32;

@group(2) @binding(0) var supersampled: texture_2d<f32>;

@fragment
fn resolve(@builtin(position) position: vec4<f32>) -> @location(0) vec4<f32> {
    let origin = vec2<i32>(position.xy) * i32(M);
    var sum = vec4<f32>(0.0);
    for (var y = 0; y < i32(M); y += 1) {
        for (var x = 0; x < i32(M); x += 1) {
            sum += textureLoad(supersampled, origin + vec2<i32>(x, y), 0);
        }
    }
    return sum / f32(M * M);
}
