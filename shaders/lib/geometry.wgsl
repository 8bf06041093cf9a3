// Drawing the scene's triangles, shared by every pass that rasterizes them (the G-buffer and the
// shadow cubes): the vertex layout of scene::Vertex and the alpha test of MASK materials.

struct VertexIn {
    @location(0) position: vec3<f32>,
    @location(1) normal: vec3<f32>,
    @location(2) uv: vec2<f32>,
    @location(3) material: u32,
}

// Whether a fragment of a MASK material survives its alpha test.
fn passes_alpha_test(material_index: u32, uv: vec2<f32>) -> bool {
    let material = materials[material_index];
    var alpha = material.base_color.a;
#ifdef TEXTURED
    let texel = textureSample(scene_textures, scene_sampler, uv, max(material.texture, 0));
    alpha *= select(1.0, texel.a, material.texture >= 0);
#endif
    return alpha >= material.alpha_cutoff;
}
