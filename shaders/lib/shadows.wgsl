// Omnidirectional shadows (LearnOpenGL, "Point Shadows"): percentage-closer filtering over 20
// offset directions around the light-to-surface vector, in a disk that grows with the viewer's
// distance, with a bias against acne.
//
// The cubes hold reversed depth along each face's axis (scene/shadow.rs). A tap in direction r
// reads the face of r's largest component ma; the occluder's depth there becomes its distance
// along r, z · |r| / |ma|. The tutorial compares that with the surface point's own distance, so
// a tap that leans towards the light's side of the surface finds the surface itself nearer
// and shadows it: only a bias as large as the disk hides that. Here each tap is compared with
// where its ray meets the surface's tangent plane instead (receiver-plane depth), so the bias
// need only cover the depth a texel spans. The plane stands in for the surface only near the
// point: a tap may lean at most √3 · radius off it, and the receiver stays within ½–2× the
// point's distance.

#ifdef SHADOWS
@group(1) @binding(4) var shadow_cubes: texture_depth_cube_array;
@group(0) @binding(6) var shadow_sampler: sampler;

// The tutorial's offsets: the 8 corners and 12 edge midpoints of a cube.
const PCF_OFFSETS = array<vec3<f32>, 20>(
    vec3<f32>(1.0, 1.0, 1.0), vec3<f32>(1.0, -1.0, 1.0), vec3<f32>(-1.0, -1.0, 1.0), vec3<f32>(-1.0, 1.0, 1.0),
    vec3<f32>(1.0, 1.0, -1.0), vec3<f32>(1.0, -1.0, -1.0), vec3<f32>(-1.0, -1.0, -1.0), vec3<f32>(-1.0, 1.0, -1.0),
    vec3<f32>(1.0, 1.0, 0.0), vec3<f32>(1.0, -1.0, 0.0), vec3<f32>(-1.0, -1.0, 0.0), vec3<f32>(-1.0, 1.0, 0.0),
    vec3<f32>(1.0, 0.0, 1.0), vec3<f32>(-1.0, 0.0, 1.0), vec3<f32>(1.0, 0.0, -1.0), vec3<f32>(-1.0, 0.0, -1.0),
    vec3<f32>(0.0, 1.0, 1.0), vec3<f32>(0.0, -1.0, 1.0), vec3<f32>(0.0, -1.0, -1.0), vec3<f32>(0.0, 1.0, -1.0),
);

// The radius of the PCF disk around a point seen from `view_distance`, in world units.
fn pcf_radius(light: Light, view_distance: f32) -> f32 {
    return light.shadow_radius * (1.0 + view_distance / light.range);
}

// The fraction of the PCF taps that see `position` (with unit `normal` facing the light) lit by
// `light`, seen from `view_distance`.
fn shadow_visibility(light: Light, position: vec3<f32>, normal: vec3<f32>, view_distance: f32) -> f32 {
    let to_surface = position - light.position;
    let distance = length(to_surface);
    let radius = pcf_radius(light, view_distance);
    // The light's signed distance to the tangent plane (negative: the normal faces the light).
    let plane = dot(to_surface, normal);
    let near = light.shadow_near;
    let far = light.range;
    var lit = 0.0;
    for (var i = 0u; i < 20u; i += 1u) {
        let r = to_surface + PCF_OFFSETS[i] * radius;
        let length_r = length(r);
        let a = abs(r);
        // Bounded away from zero, so a tap exactly at the light stays finite.
        let major = max(max(a.x, a.y), max(a.z, 1e-30));
        let stored = textureSampleLevel(shadow_cubes, shadow_sampler, r, light.shadow, 0);
        let occluder = near * far / (stored * (far - near) + near) * (length_r / major);
        // Where the tap's ray meets the tangent plane; rays that run along or away from it
        // keep the point's own distance. The bounds keep grazing rays finite.
        let facing = dot(r, normal) / max(length_r, 1e-30);
        let on_plane = select(distance, plane / facing, facing < -1e-4);
        let nearest = max(0.5 * distance, distance - 1.7320508 * radius);
        let receiver = clamp(on_plane, nearest, 2.0 * distance);
        // A cleared texel (0: nothing within the light's range) is lit.
        lit += select(0.0, 1.0, stored <= 0.0 || receiver - light.shadow_bias <= occluder);
    }
    return lit * (1.0 / 20.0);
}
#endif
