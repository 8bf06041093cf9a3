// Adaptive supersampling, part of shaders/adaptive.wgsl: the list of extra samples and its shading.

// ---- scan_rows, scan_total, emit: the list of extra samples

@group(2) @binding(3) var<storage, read_write> row_offsets: array<u32>;
@group(2) @binding(4) var<storage, read_write> totals: array<u32>;
@group(2) @binding(5) var<storage, read_write> pixel_offsets: array<u32>;
@group(2) @binding(6) var<storage, read_write> entries: array<u32>;

// List entries of each row.
@compute @workgroup_size(64)
fn scan_rows(@builtin(global_invocation_id) id: vec3<u32>) {
    let size = textureDimensions(counts);
    let y = id.x;
    if y >= size.y {
        return;
    }
    var sum = 0u;
    for (var x = 0u; x < size.x; x += 1u) {
        let n = textureLoad(counts, vec2<u32>(x, y), 0).r;
        sum += n - first_extra_rank(n);
    }
    row_offsets[y] = sum;
}

// Exclusive prefix sum over the rows; totals[0] = all extra samples.
@compute @workgroup_size(1)
fn scan_total() {
    let rows = textureDimensions(counts).y;
    var total = 0u;
    for (var y = 0u; y < rows; y += 1u) {
        let sum = row_offsets[y];
        row_offsets[y] = total;
        total += sum;
    }
    totals[0] = total;
}

// Writes the first list index of each pixel of row `id.x` and the entries of its listed
// samples: its extra ranks, from first_extra_rank(n) (`emit`), or, `by_groups` (`-coverage`'s
// `emit_groups`), the shaded cells that `groups_texture` holds for each pixel of n > 1, in cell
// order. The texture is a parameter so that `emit` passes `counts` and binds no `groups`.
fn emit_row(id: vec3<u32>, groups_texture: texture_2d<u32>, by_groups: bool) {
    let size = textureDimensions(counts);
    let y = id.x;
    if y >= size.y {
        return;
    }
    var offset = row_offsets[y];
    for (var x = 0u; x < size.x; x += 1u) {
        let pixel = vec2<i32>(i32(x), i32(y));
        let n = textureLoad(counts, pixel, 0).r;
        pixel_offsets[y * size.x + x] = offset;
        if by_groups {
            if n == 1u {
                continue;
            }
            var rest = groups_in(groups_texture, pixel).shaded;
            while rest != 0u {
                entries[offset] = list_entry(pixel * i32(M) + cell_offset(firstTrailingBit(rest)), n);
                rest &= rest - 1u;
                offset += 1u;
            }
        } else {
            for (var rank = first_extra_rank(n); rank < n; rank += 1u) {
                entries[offset] = list_entry(window_texel(pixel, rank), n);
                offset += 1u;
            }
        }
    }
}

// Writes each pixel's first list index and the entries of its extra samples.
@compute @workgroup_size(64)
fn emit(@builtin(global_invocation_id) id: vec3<u32>) {
    emit_row(id, counts, false);
}

// ---- shade_extra: the list, read only

@group(2) @binding(7) var<storage, read> list_entries: array<u32>;
@group(2) @binding(8) var<storage, read> list_totals: array<u32>;

// The compact target's rectangles (`compact_rect`). The tail of the last block reads past
// the list's end: a stale or zero entry, or past the buffer (robust access clamps or reads 0),
// it decodes to some texel below 2^14 and 1 ≤ n ≤ 16, and its colour lands where gather never
// reads. So shade_extra needs no test against the length: a storage load per fragment (per
// SIMD lane on lavapipe) that cost 4–5% of shade_extra (thin, every sample listed), and a
// rectangle over whole bands shaded up to 65 535 fragments more.
@vertex
fn compact_rows(@builtin(vertex_index) index: u32) -> @builtin(position) vec4<f32> {
    return compact_rect(index, list_totals[0]);
}

@fragment
fn shade_extra(@builtin(position) position: vec4<f32>) -> @location(0) vec4<f32> {
    let entry = list_entries[compact_index(vec2<u32>(position.xy))];
    let texel = entry_texel(entry);
    if CELLS {
        return shade_cell(texel, entry_count(entry), texel_rank(texel));
    }
    return shade(texel, footprint(entry_count(entry)));
}
