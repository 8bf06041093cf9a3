// A list laid out in a compact target, one entry per texel: the adaptive modes' extra samples,
// SMAA's edge pixels and the samples of MSAA's listed pixels. Its size is the pass's COMPACT_WIDTH × COMPACT_HEIGHT (multiples of 4).

override COMPACT_WIDTH: u32;
override COMPACT_HEIGHT: u32;

// List index ↔ texel of the compact target, in 4×4 blocks of 16 consecutive entries: lavapipe
// shades 4×4 blocks together, and consecutive entries belong to neighbouring pixels, so each
// SIMD batch reads G-buffer texels close together.
fn compact_texel(index: u32) -> vec2<u32> {
    let block = index / 16u;
    let within = index % 16u;
    let blocks_per_row = COMPACT_WIDTH / 4u;
    return vec2<u32>((block % blocks_per_row) * 4u + within % 4u, (block / blocks_per_row) * 4u + within / 4u);
}

fn compact_index(texel: vec2<u32>) -> u32 {
    let block = (texel.y / 4u) * (COMPACT_WIDTH / 4u) + texel.x / 4u;
    return block * 16u + (texel.y % 4u) * 4u + texel.x % 4u;
}

// Vertex `index` (of 12) of two rectangles over the first `total` entries of the compact
// target, so that no fragment lies past the list's end: the full bands of 4 rows, then the
// last band up to the end of its last block. Only that block's tail (at most 15 fragments)
// lies past the end.
fn compact_rect(index: u32, total: u32) -> vec4<f32> {
    let band = 4u * COMPACT_WIDTH;
    let full_rows = 4u * (total / band);
    let last_columns = 4u * ((total % band + 15u) / 16u);
    // Rectangle 0 spans the full bands, rectangle 1 the last band's used blocks; either may
    // be empty.
    var low = vec2<u32>(0u, 0u);
    var high = vec2<u32>(COMPACT_WIDTH, full_rows);
    if index >= 6u {
        low = vec2<u32>(0u, full_rows);
        high = vec2<u32>(last_columns, select(full_rows, full_rows + 4u, last_columns > 0u));
    }
    // Two triangles: (0 1 2) (2 1 3) over the corners low/high × low/high.
    let corner = array<vec2<bool>, 6>(
        vec2<bool>(false, false), vec2<bool>(true, false), vec2<bool>(false, true),
        vec2<bool>(false, true), vec2<bool>(true, false), vec2<bool>(true, true),
    )[index % 6u];
    let texel = vec2<f32>(select(low, high, corner));
    let size = vec2<f32>(f32(COMPACT_WIDTH), f32(COMPACT_HEIGHT));
    return vec4<f32>(texel.x / size.x * 2.0 - 1.0, 1.0 - texel.y / size.y * 2.0, 0.0, 1.0);
}
