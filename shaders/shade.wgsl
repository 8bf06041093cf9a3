// Shades every texel of the G-buffer, one fragment per sample: the deferred 1×1 image when the
// G-buffer is w×h, the brute-force reference's supersampled image when it is M·w × M·h. On
// lavapipe one fragment per sample is the fastest brute force (LAVAPIPE.md), so it is the fair
// baseline for adaptive shading.

#include "lib/common.wgsl"
#include "lib/scene.wgsl"
#include "lib/gbuffer.wgsl"
#include "lib/shading.wgsl"

// A texture lookup's footprint in G-buffer texels: 1, but √½ in TAA (a mip bias of −½),
// whose jittered frames together sample each pixel many times (technique/taa.rs).
override FOOTPRINT: f32 = 1.0;

@fragment
fn shade_all(@builtin(position) position: vec4<f32>) -> @location(0) vec4<f32> {
    return shade(vec2<i32>(position.xy), FOOTPRINT);
}
