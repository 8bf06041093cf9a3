// Shading one G-buffer sample: metallic-roughness BRDF under the scene's lights, albedo,
// emission and occlusion fetched here, shadows of shadow-casting lights, and an optional stall
// that simulates an expensive shader.

#include "lib/finite.wgsl"
#include "lib/shadows.wgsl"

const PI: f32 = 3.14159265358979;

// Dependent integer operations per sample that the compiler can neither fold nor skip. Set per
// pipeline: `-stalled` modes use the scene's stall count, the others 0.
override STALL_ITERATIONS: u32 = 0u;

// A chain of STALL_ITERATIONS steps, each needing the one before. Its result is written to the
// alpha channel of the HDR target, which keeps it live without touching the image.
//
// lavapipe ends a shader invocation's loops after 65 535 iterations in all (gallivm's
// LP_MAX_TGSI_LOOP_ITERATIONS; a longer stall silently stopped growing), so the chain takes 16
// steps per iteration, written out, and the rest one by one: up to MAX_STALL_ITERATIONS
// (renderer/src/lib.rs) steps stay within the limit, with room for the shader's other loops.
fn stall_step(h: u32) -> u32 {
    return (h ^ (h >> 15u)) * 0x2c1b3c6du;
}

// Four steps, written out: an inner loop would count against the limit like the outer one.
fn stall_step4(h: u32) -> u32 {
    return stall_step(stall_step(stall_step(stall_step(h))));
}

fn stall(texel: vec2<i32>) -> f32 {
    var h = (u32(texel.x) * 0x8da6b343u) ^ (u32(texel.y) * 0xd8163841u);
    for (var i = 0u; i < STALL_ITERATIONS / 16u; i += 1u) {
        h = stall_step4(stall_step4(stall_step4(stall_step4(h))));
    }
    for (var i = 0u; i < STALL_ITERATIONS % 16u; i += 1u) {
        h = stall_step(h);
    }
    return f32(h >> 8u) * (1.0 / 16777216.0);
}

// What a surface reflects of one light, and how that changes with its albedo.
struct Reflected {
    value: vec3<f32>,
    // d value / d albedo, channel by channel: exact for dielectrics, whose reflectance is
    // affine in albedo; for metals, whose Fresnel term also follows albedo, the tangent.
    slope: vec3<f32>,
}

// GGX's distribution of normals at n·h = `n_h`, for a2 = roughness⁴.
fn ggx(n_h: f32, a2: f32) -> f32 {
    let d_denominator = n_h * n_h * (a2 - 1.0) + 1.0;
    return a2 / (PI * d_denominator * d_denominator);
}

// Hammon's approximation of height-correlated Smith visibility, for a = roughness².
fn smith_visibility(n_l: f32, n_v: f32, a: f32) -> f32 {
    return 0.5 / mix(2.0 * n_l * n_v, n_l + n_v, a);
}

// Schlick's Fresnel weight (1 − v·h)⁵, by multiplication rather than pow() (exp2 of log2).
fn schlick_weight(v_h: f32) -> f32 {
    let x = 1.0 - v_h;
    let x2 = x * x;
    return x2 * x2 * x;
}

// glTF's metallic-roughness model: Lambert diffuse, GGX distribution, Schlick Fresnel, and
// Hammon's approximation of height-correlated Smith visibility (no square roots; Filament's
// "fast" variant), with its slope in albedo. `n_l` > 0 is the caller's.
fn reflect_light(n: vec3<f32>, v: vec3<f32>, l: vec3<f32>, n_l: f32, albedo: vec3<f32>, metallic: f32, a2: f32, a: f32) -> Reflected {
    let h = normalize(v + l);
    let n_v = max(dot(n, v), 1e-4);
    let n_h = max(dot(n, h), 0.0);
    let v_h = max(dot(v, h), 0.0);
    let distribution = ggx(n_h, a2);
    let visibility = smith_visibility(n_l, n_v, a);
    let f0 = mix(vec3<f32>(0.04), albedo, metallic);
    let x5 = schlick_weight(v_h);
    let fresnel = f0 + (1.0 - f0) * x5;
    let diffuse_scale = (1.0 - metallic) / PI;
    let diffuse = (1.0 - fresnel) * diffuse_scale * albedo;
    let specular = distribution * visibility;
    // f0 moves with albedo at the rate `metallic`, and the Fresnel term with f0 at 1 − x⁵.
    let fresnel_slope = metallic * (1.0 - x5);
    let slope = (1.0 - fresnel) * diffuse_scale + fresnel_slope * (specular - diffuse_scale * albedo);
    return Reflected((diffuse + fresnel * specular) * n_l, slope * n_l);
}

// KHR_lights_punctual's inverse-square falloff with a smooth window to zero at `range`, from
// the squared distance and its inverse.
fn attenuation(distance2: f32, inverse2: f32, range: f32) -> f32 {
    let ratio2 = distance2 / (range * range);
    let window = clamp(1.0 - ratio2 * ratio2, 0.0, 1.0);
    return window * window * inverse2;
}

// A surface nearer a light than this fraction of the light's range is lit as if at that
// distance: the inverse square stays finite for a light on a surface, in any unit (a fixed
// floor in world units darkened a Cornell box modelled in kilometres).
const NEAREST_LIGHT: f32 = 1e-4;

// The way from a shading point to a light: `to_light` (not normalized; the reverse of a
// directional light's direction) and its squared length, kept at least NEAREST_LIGHT of the
// light's range (1 for a directional light, which does not fall off).
struct LightRay {
    to_light: vec3<f32>,
    distance2: f32,
    positional: bool,
}

fn light_ray(light: Light, position: vec3<f32>) -> LightRay {
#ifdef LIGHT_KINDS
    // Kinds are told apart with `select`, never with a branch: lavapipe specializes a shader
    // on uniform values that steer control flow and then looks the variant up on every pass
    // (a branch on `kind` added 2 ms to every 160×120 frame). A point light's cone factor is
    // exactly 1 (scale 0, offset 1).
    let positional = light.kind != LIGHT_DIRECTIONAL;
    let to_light = select(-light.direction, light.position - position, positional);
    let nearest = NEAREST_LIGHT * light.range;
    let distance2 = select(1.0, max(dot(to_light, to_light), nearest * nearest), positional);
    return LightRay(to_light, distance2, positional);
#else
    let to_light = light.position - position;
    let nearest = NEAREST_LIGHT * light.range;
    return LightRay(to_light, max(dot(to_light, to_light), nearest * nearest), true);
#endif
}

// A spot light's fade at the unit direction `l` towards it: clamp(cos θ · scale + offset, 0, 1)².
fn spot_fade(light: Light, l: vec3<f32>) -> f32 {
    let cone = clamp(dot(light.direction, -l) * light.spot_scale + light.spot_offset, 0.0, 1.0);
    return cone * cone;
}

#ifdef TEXTURED
// Most taps of one anisotropic lookup.
const MAX_ANISOTROPY: f32 = 16.0;

// Anisotropic filtering in the shader: up to MAX_ANISOTROPY trilinear taps spread along the
// major axis of the footprint (c.dx, c.dy), each tap covering its share of that axis. lavapipe's
// own sampler anisotropy costs about 100 times a trilinear lookup, taps taken here about their
// number (`docs/lavapipe.md`).
fn sample_filtered(textures: texture_2d_array<f32>, texture: i32, c: TexCoords) -> vec4<f32> {
    // The ratio of the axes, which alone this size enters, is the same in any unit.
    let size = vec2<f32>(textureDimensions(textures));
    let length_x = length(c.dx * size);
    let length_y = length(c.dy * size);
    let x_is_major = length_x >= length_y;
    let major = select(c.dy, c.dx, x_is_major);
    let minor = select(c.dx, c.dy, x_is_major);
    let ratio = max(length_x, length_y) / max(min(length_x, length_y), 1e-20);
    let taps = u32(clamp(ceil(ratio), 1.0, MAX_ANISOTROPY));
    let step = major / f32(taps);
    var sum = vec4<f32>(0.0);
    for (var i = 0u; i < taps; i += 1u) {
        let offset = (f32(i) + 0.5) / f32(taps) - 0.5;
        sum += texture_lookup(textures, texture, c.uv + major * offset, step, minor);
    }
    return sum / f32(taps);
}

// Where `slot` of the surface's material is read, its footprint scaled by `footprint`.
fn surface_coords(s: Surface, slot: u32, footprint: f32) -> TexCoords {
    return slot_coords(s.material, slot, s.uv, s.uv_dx * footprint, s.uv_dy * footprint);
}
#endif

// Linear HDR radiance of the sample at `texel`; alpha carries the stall result. `footprint`
// scales the stored UV derivatives: 1 for the reference, sqrt((1 + M²/n) / 2) when n adaptive
// samples share an M×M window (adaptive.wgsl: footprint).
fn shade(texel: vec2<i32>, footprint: f32) -> vec4<f32> {
    let s = load_surface(texel);
    return shade_surface(texel, s, world_position(texel, s.depth), footprint);
}

// A sample's surface and shading position as if taken `offset` G-buffer texels away on its own
// surface: the UV moves along its derivatives and the position along the sample's tangent
// plane, to where the view ray through the offset point meets it. A ray that meets the plane
// at a grazing angle, behind the camera or at more than twice or less than half the sample's
// depth leaves the position where it was (the offset is under a pixel; such a plane is an
// edge, which takes its samples where they lie).
struct Moved {
    surface: Surface,
    position: vec3<f32>,
}

fn move_on_surface(texel: vec2<i32>, offset: vec2<f32>) -> Moved {
    var s = load_surface(texel);
    s.uv += s.uv_dx * offset.x + s.uv_dy * offset.y;
    let centre = vec2<f32>(texel) + 0.5;
    let ray = world_ray(centre + offset);
    let facing = dot(ray, s.normal);
    // The view depth at which the offset ray meets the plane through the sample.
    let depth = s.depth * dot(world_ray(centre), s.normal) / facing;
    var point = centre;
    if abs(facing) > 1e-6 && depth > 0.5 * s.depth && depth < 2.0 * s.depth {
        point += offset;
        s.depth = depth;
    }
    return Moved(s, world_position_at(point, s.depth));
}

// The sample at `texel` shaded as if taken `offset` G-buffer texels away (move_on_surface).
fn shade_offset(texel: vec2<i32>, offset: vec2<f32>, footprint: f32) -> vec4<f32> {
    let moved = move_on_surface(texel, offset);
    return shade_surface(texel, moved.surface, moved.position, footprint);
}

// The albedo that shading reads for surface `s`: the base colour, times its texture filtered
// over `footprint`.
fn surface_albedo(s: Surface, footprint: f32) -> vec3<f32> {
    let material = materials[s.material];
    var albedo = material.base_color.rgb;
#ifdef TEXTURED
    if material.texture >= 0 {
        albedo *= sample_filtered(scene_textures, material.texture, surface_coords(s, SLOT_BASE, footprint)).rgb;
    }
#endif
    return albedo;
}

// The metalness and roughness that shading reads for surface `s`: the material's factors,
// times its metallic-roughness texture filtered over `footprint`; roughness kept in [0.03, 1].
struct Finish {
    metallic: f32,
    roughness: f32,
}

fn surface_finish(s: Surface, footprint: f32) -> Finish {
    let material = materials[s.material];
#ifdef METALLIC_ROUGHNESS
    var metallic = material.metallic;
    var rough = material.roughness;
    if material.metallic_roughness_texture >= 0 {
        let coords = surface_coords(s, SLOT_METALLIC_ROUGHNESS, footprint);
        let texel = sample_filtered(scene_data_textures, material.metallic_roughness_texture, coords);
        rough *= texel.g;
        metallic *= texel.b;
    }
    let roughness = clamp(rough, 0.03, 1.0);
#else
    let metallic = material.metallic;
    let roughness = clamp(material.roughness, 0.03, 1.0);
#endif
    return Finish(metallic, roughness);
}

// The ambient light that reaches surface `s`: the frame's, times the material's occlusion
// texture filtered over `footprint` at its strength.
fn surface_ambient(s: Surface, footprint: f32) -> vec3<f32> {
#ifdef OCCLUSION
    let material = materials[s.material];
    var ambient = frame.ambient.rgb;
    if material.occlusion_texture >= 0 {
        let coords = surface_coords(s, SLOT_OCCLUSION, footprint);
        let occlusion = sample_filtered(scene_data_textures, material.occlusion_texture, coords).r;
        ambient *= 1.0 + material.occlusion_strength * (occlusion - 1.0);
    }
    return ambient;
#else
    return frame.ambient.rgb;
#endif
}

#ifdef EMISSIVE
// The radiance that surface `s` emits: the material's factor, times its emissive texture
// filtered over `footprint`.
fn surface_emitted(s: Surface, footprint: f32) -> vec3<f32> {
    let material = materials[s.material];
    var emitted = material.emissive;
#ifdef TEXTURED
    if material.emissive_texture >= 0 {
        emitted *= sample_filtered(scene_textures, material.emissive_texture, surface_coords(s, SLOT_EMISSIVE, footprint)).rgb;
    }
#endif
    return emitted;
}
#endif

// Shading of surface `s` at `position`; `texel` seeds the stall.
fn shade_surface(texel: vec2<i32>, s: Surface, position: vec3<f32>, footprint: f32) -> vec4<f32> {
    return light_surface(texel, s, position, footprint).color;
}

// A shaded sample: its radiance (alpha: the stall's result), the albedo it was shaded with and
// the radiance's slope in that albedo, with which the `-coverage` variant carries the light of
// one sample to the albedos of the samples it stands for; and `penumbra`, how fast its light
// can change across the surface where a shadow's filter straddles an occluder's edge: the
// luminance that each light seeing the sample partly would give it unshadowed, over that
// light's filter radius in world units (`-coverage`'s shadow term reads it). Passes that read only
// `color` leave the rest to dead-code elimination; `color` is computed by the same operations
// either way.
struct Lit {
    color: vec4<f32>,
    albedo: vec3<f32>,
    slope: vec3<f32>,
    penumbra: f32,
}

fn light_surface(texel: vec2<i32>, s: Surface, position: vec3<f32>, footprint: f32) -> Lit {
    let stalled = stall(texel);
    if s.material == BACKGROUND {
        return Lit(vec4<f32>(frame.background.rgb, stalled), vec3<f32>(0.0), vec3<f32>(0.0), 0.0);
    }
    let albedo = surface_albedo(s, footprint);
    let finish = surface_finish(s, footprint);
    let metallic = finish.metallic;
    let roughness = finish.roughness;
    let a = roughness * roughness;
    let a2 = a * a;
    let v = normalize(frame.eye.xyz - position);
    let ambient = surface_ambient(s, footprint);
    var radiance = ambient * albedo;
    var slope = ambient;
#ifdef EMISSIVE
    radiance += surface_emitted(s, footprint);
#endif
    var penumbra = 0.0;
    for (var i = 0u; i < LIGHT_COUNT; i += 1u) {
        let light = lights.entries[i];
        let ray = light_ray(light, position);
        let inverse = inverseSqrt(ray.distance2);
        let l = ray.to_light * inverse;
        let n_l = dot(s.normal, l);
        if n_l > 0.0 {
#ifdef LIGHT_KINDS
            let falloff = select(1.0, attenuation(ray.distance2, inverse * inverse, light.range), ray.positional);
            let cone = spot_fade(light, l);
            let reflected = reflect_light(s.normal, v, l, n_l, albedo, metallic, a2, a);
            var contribution = reflected.value * light.radiance * falloff * cone;
            var contribution_slope = reflected.slope * light.radiance * falloff * cone;
#else
            let reflected = reflect_light(s.normal, v, l, n_l, albedo, metallic, a2, a);
            let falloff = attenuation(ray.distance2, inverse * inverse, light.range);
            var contribution = reflected.value * light.radiance * falloff;
            var contribution_slope = reflected.slope * light.radiance * falloff;
#endif
#ifdef SHADOWS
            if light.shadow >= 0 {
                let view_distance = length(frame.eye.xyz - position);
                let visible = shadow_visibility(light, position, s.normal, view_distance);
                if visible > 0.0 && visible < 1.0 {
                    penumbra += luminance(contribution) / pcf_radius(light, view_distance);
                }
                contribution *= visible;
                contribution_slope *= visible;
            }
#endif
            radiance += contribution;
            slope += contribution_slope;
        }
    }
    // The HDR targets are f16: radiance past their largest value (a light 10⁵ times the others
    // on a glossy highlight) would be stored as +Inf. It is kept at HALF_MAX instead, which
    // the tonemap reads as "brighter than anything shown".
    return Lit(
        vec4<f32>(min(radiance, vec3<f32>(HALF_MAX)), stalled),
        albedo,
        min(slope, vec3<f32>(HALF_MAX)),
        min(penumbra, HALF_MAX),
    );
}
