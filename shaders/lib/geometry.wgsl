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
    let coords = slot_coords(i32(material_index), SLOT_BASE, uv, vec2<f32>(0.0), vec2<f32>(0.0));
#ifdef TEXTURE_PAGES
    let texel = texture_lookup(scene_textures, max(material.texture, 0), coords.uv, dpdx(coords.uv), dpdy(coords.uv));
#else
    let texel = textureSample(scene_textures, scene_sampler, coords.uv, max(material.texture, 0));
#endif
    alpha *= select(1.0, texel.a, material.texture >= 0);
#endif
    return alpha >= material.alpha_cutoff;
}
