// Reading the enlarged G-buffer. It holds what shading needs but not albedo: albedo is fetched
// at shading time with `textureSampleGrad`, so a sample's filter footprint can follow the number
// of samples that share its pixel. Layout:
//

//   gb_uv             Rg32Float     UV (f32: tiled UVs grow large)
//   gb_normal         Rgba16Float   unit world-space normal, material index in w (f16 holds
//                                   integers exactly up to 2048; the importer checks)
//   gb_uv_grad        Rgba16Float   d(uv)/dx, d(uv)/dy per G-buffer texel
//   gb_depth          Depth32Float  reversed depth, from which linear depth is recovered
@group(1) @binding(0) var gb_uv: texture_2d<f32>;
@group(1) @binding(1) var gb_normal: texture_2d<f32>;
@group(1) @binding(2) var gb_uv_grad: texture_2d<f32>;
@group(1) @binding(3) var gb_depth: texture_depth_2d;

// Material index of samples that no geometry covers.
const BACKGROUND: i32 = -1;

struct Surface {
    uv: vec2<f32>,
    // Linear view depth: distance along the viewing axis, positive in front of the camera.
    depth: f32,
    material: i32,
    // Unit world-space shading normal, facing the camera side of the surface.
    normal: vec3<f32>,
    // d(uv)/dx and d(uv)/dy per G-buffer texel.
    uv_dx: vec2<f32>,
    uv_dy: vec2<f32>,
}

// Linear view depth from reversed depth d (near → 1, far → 0): n·f / (d·(f − n) + n). With f32
// depth its relative precision is about 2^-24 at every distance, as good as storing it.
fn linear_depth(texel: vec2<i32>) -> f32 {
    return linear_depth_of(textureLoad(gb_depth, texel, 0));
}

fn linear_depth_of(d: f32) -> f32 {
    let near = frame.projection.z;
    let far = frame.projection.w;
    return near * far / (d * (far - near) + near);
}

// The material index and normal of a sample, without the rest.
fn load_normal_material(texel: vec2<i32>) -> vec4<f32> {
    return textureLoad(gb_normal, texel, 0);
}

fn load_surface(texel: vec2<i32>) -> Surface {
    let nm = textureLoad(gb_normal, texel, 0);
    let g = textureLoad(gb_uv_grad, texel, 0);
    return Surface(textureLoad(gb_uv, texel, 0).xy, linear_depth(texel), i32(nm.w), nm.xyz, g.xy, g.zw);
}

// World position of the sample at `texel` seen at view depth `depth`.
fn world_position(texel: vec2<i32>, depth: f32) -> vec3<f32> {
    return world_position_at(vec2<f32>(texel) + 0.5, depth);
}

// World position of the point `point` (in G-buffer texels, a texel's centre at + 0.5) seen at
// view depth `depth`.
fn world_position_at(point: vec2<f32>, depth: f32) -> vec3<f32> {
    return world_position_in(point, vec2<f32>(textureDimensions(gb_uv)), depth);
}

// The same point in a target of `size` texels.
fn world_position_in(point: vec2<f32>, size: vec2<f32>, depth: f32) -> vec3<f32> {
    return (frame.inv_view * vec4<f32>(view_ray_in(point, size) * depth, 1.0)).xyz;
}

// The view-space ray through `point` (as in world_position_at) that reaches view depth 1.
fn view_ray(point: vec2<f32>) -> vec3<f32> {
    return view_ray_in(point, vec2<f32>(textureDimensions(gb_uv)));
}

// The same ray through a target of `size` texels.
fn view_ray_in(point: vec2<f32>, size: vec2<f32>) -> vec3<f32> {
    let tile_ndc = point / size * vec2<f32>(2.0, -2.0) + vec2<f32>(-1.0, 1.0);
    let ndc = tile_ndc * frame.tile.xy + frame.tile.zw;
    return vec3<f32>(ndc * frame.projection.xy, -1.0);
}

// The same ray in world space: a direction, free of the camera's position (whose size would
// cost a far scene its precision).
fn world_ray(point: vec2<f32>) -> vec3<f32> {
    return (frame.inv_view * vec4<f32>(view_ray(point), 0.0)).xyz;
}
