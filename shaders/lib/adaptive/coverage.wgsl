// Adaptive supersampling, part of shaders/adaptive.wgsl: the `-coverage` variant.

// ---- the `-coverage` variant: one sample per surface of the window, weighted by coverage

// Two samples lie on one surface when they share a material, their normals' cosine is at
// least SURFACE_COS and the second lies within SURFACE_GAP · depth of the first's tangent
// plane (technique/adaptive: SurfaceTolerance).
override SURFACE_COS: f32;
override SURFACE_GAP: f32;

// What evaluate_coverage leaves for the passes after it, per pixel: x holds the mask of the
// window cells that are shaded (bit c for cell c, row-major) and, in bit 16, whether a surface
// of the pixel has a base-colour texture; y and z hold, four bits per cell (cells 0–7 in y, 8–15 in z), the slot
// of the shaded sample that stands for the cell, slots numbered in cell order. The count (the
// mask's bits) goes to `counts` as in the other variants.
@group(2) @binding(13) var groups: texture_2d<u32>;

const TEXTURE_VARIES: u32 = 0x10000u;

struct Groups {
    shaded: u32,
    slots: vec2<u32>,
    detail: bool,
}

fn load_groups(pixel: vec2<i32>) -> Groups {
    return groups_in(groups, pixel);
}

// A pixel's Groups in `texture`, laid out as `groups` (emit_row's texture is a parameter).
fn groups_in(texture: texture_2d<u32>, pixel: vec2<i32>) -> Groups {
    let g = textureLoad(texture, pixel, 0);
    return Groups(g.x & 0xffffu, g.yz, (g.x & TEXTURE_VARIES) != 0u);
}

fn cell_slot(g: Groups, cell: u32) -> u32 {
    let word = select(g.slots.y, g.slots.x, cell < 8u);
    return (word >> (4u * (cell % 8u))) & 15u;
}

fn cell_offset(cell: u32) -> vec2<i32> {
    return vec2<i32>(i32(cell % M), i32(cell / M));
}

// What the shaded sample of window cell `cell` stands for: (its share of the pixel, the
// centroid of its cells less its own position in G-buffer texels, the side of a square of
// their area in texels), as a `sample_cell` entry is.
fn group_share(g: Groups, cell: u32) -> vec4<f32> {
    let slot = cell_slot(g, cell);
    var count = 0u;
    var sum = vec2<f32>(0.0);
    for (var j = 0u; j < M * M; j += 1u) {
        if cell_slot(g, j) == slot {
            count += 1u;
            sum += cell_point(j);
        }
    }
    let centroid = sum / f32(count);
    return vec4<f32>(f32(count) / f32(M * M), centroid - cell_point(cell), sqrt(f32(count)));
}

// A window sample as the grouping compares it: view-space position and normal, and material.
struct WindowSample {
    position: vec3<f32>,
    normal: vec3<f32>,
    material: i32,
}

fn window_sample(origin: vec2<i32>, cell: u32) -> WindowSample {
    let texel = origin + cell_offset(cell);
    let nm = load_normal_material(texel);
    let position = view_ray(vec2<f32>(texel) + 0.5) * linear_depth(texel);
    let normal = (frame.view * vec4<f32>(nm.xyz, 0.0)).xyz;
    return WindowSample(position, normal, i32(nm.w));
}

// Whether `b` lies on the surface of `a`. Every background sample lies on one surface.
fn same_surface(a: WindowSample, b: WindowSample) -> bool {
    if a.material != b.material {
        return false;
    }
    if a.material == BACKGROUND {
        return true;
    }
    let gap = abs(dot(b.position - a.position, a.normal));
    return dot(a.normal, b.normal) >= SURFACE_COS && gap <= SURFACE_GAP * -a.position.z;
}

struct CoverageOut {
    @location(0) count: u32,
    @location(1) groups: vec4<u32>,
}

// The window's cells as points, for the nearest-sample searches below.
fn cell_point(cell: u32) -> vec2<f32> {
    return vec2<f32>(f32(cell % M), f32(cell / M));
}

// The cells of the first four surfaces of a window, as masks; a cell in none of them is a
// surface of its own (a window of more than four surfaces is shaded sample by sample there).
fn surface_cells(surfaces: vec4<u32>, cell: u32) -> u32 {
    let bit = 1u << cell;
    if (surfaces.x & bit) != 0u {
        return surfaces.x;
    }
    if (surfaces.y & bit) != 0u {
        return surfaces.y;
    }
    if (surfaces.z & bit) != 0u {
        return surfaces.z;
    }
    if (surfaces.w & bit) != 0u {
        return surfaces.w;
    }
    return bit;
}

// The cell of `cells` (a non-empty mask) nearest to `point`, the lowest on a tie.
fn nearest_cell(cells: u32, point: vec2<f32>) -> u32 {
    var rest = cells;
    var best = firstTrailingBit(cells);
    var best_distance = 1e9;
    while rest != 0u {
        let cell = firstTrailingBit(rest);
        rest &= rest - 1u;
        let d = cell_point(cell) - point;
        if dot(d, d) < best_distance {
            best = cell;
            best_distance = dot(d, d);
        }
    }
    return best;
}

// The centroid of the cells of a non-empty mask.
fn cells_centroid(cells: u32) -> vec2<f32> {
    var rest = cells;
    var sum = vec2<f32>(0.0);
    while rest != 0u {
        sum += cell_point(firstTrailingBit(rest));
        rest &= rest - 1u;
    }
    return sum / f32(countOneBits(cells));
}

// Whether `material` has a base-colour texture. A pixel with one is filtered at the
// reference's rate: a test on a few of its samples (the texture term of `-cells`) missed the
// checker detail of one pixel in ten on the texture scene.
fn has_base_texture(material: i32) -> bool {
#ifdef TEXTURED
    return material != BACKGROUND && materials[material].texture >= 0;
#else
    return false;
#endif
}

@fragment
fn evaluate_coverage(@builtin(position) position: vec4<f32>) -> CoverageOut {
    let pixel = vec2<i32>(position.xy);
    let origin = pixel * i32(M);
    let total = M * M;
    let window = (1u << total) - 1u;
    // Each sample joins the first surface it lies on, in cell order, or starts a new one. The
    // first samples of the first four surfaces are kept as variables: lavapipe spills a private
    // array that is indexed by a variable to memory, lane by lane.
    var surfaces = vec4<u32>(0u);
    var found = 0u;
    var first0: WindowSample;
    var first1: WindowSample;
    var first2: WindowSample;
    var first3: WindowSample;
    var textured = false;
    for (var cell = 0u; cell < total; cell += 1u) {
        let sample = window_sample(origin, cell);
        let bit = 1u << cell;
        if found > 0u && same_surface(first0, sample) {
            surfaces.x |= bit;
        } else if found > 1u && same_surface(first1, sample) {
            surfaces.y |= bit;
        } else if found > 2u && same_surface(first2, sample) {
            surfaces.z |= bit;
        } else if found > 3u && same_surface(first3, sample) {
            surfaces.w |= bit;
        } else {
            textured = textured || has_base_texture(sample.material);
        }
        if found < 4u && ((surfaces.x | surfaces.y | surfaces.z | surfaces.w) & bit) == 0u {
            switch found {
                case 0u: { first0 = sample; }
                case 1u: { first1 = sample; }
                case 2u: { first2 = sample; }
                default: { first3 = sample; }
            }
            surfaces[found] = bit;
            found += 1u;
        }
    }
    // Each surface is shaded at its sample nearest to its cells' centroid; a cell in none of
    // the four is shaded itself.
    var shaded = window & ~(surfaces.x | surfaces.y | surfaces.z | surfaces.w);
    for (var s = 0u; s < found; s += 1u) {
        shaded |= 1u << nearest_cell(surfaces[s], cells_centroid(surfaces[s]));
    }
    // Where the shading metric asks for n samples, the first n of the dither order are
    // shaded too.
    if FORCE_ALL {
        shaded = window;
    } else if USE_SHADING {
        var k = shading_k(pixel);
#ifdef SHADOWS
        if SHADOW_DETAIL {
            k = max(k, shadow_k(pixel));
        }
#endif
        let extra = min(floor(k * f32(total) + 0.5), f32(total - 1u));
        for (var rank = 1u; rank <= u32(extra); rank += 1u) {
            shaded |= 1u << window_cell(rank);
        }
    }
    // Every cell is stood for by the nearest shaded cell of its surface; slots in cell order.
    var slots = vec2<u32>(0u);
    for (var cell = 0u; cell < total; cell += 1u) {
        let standing = nearest_cell(shaded & surface_cells(surfaces, cell), cell_point(cell));
        let slot = countOneBits(shaded & ((1u << standing) - 1u));
        if cell < 8u {
            slots.x |= slot << (4u * cell);
        } else {
            slots.y |= slot << (4u * (cell - 8u));
        }
    }
    let flags = shaded | select(0u, TEXTURE_VARIES, textured);
    return CoverageOut(countOneBits(shaded), vec4<u32>(flags, slots, 0u));
}

// `emit` for `-coverage`: each pixel of n > 1 lists its shaded cells, in cell order.
@compute @workgroup_size(64)
fn emit_groups(@builtin(global_invocation_id) id: vec3<u32>) {
    emit_row(id, groups, true);
}

struct ShadeOut {
    @location(0) color: vec4<f32>,
    @location(1) slope: vec4<f32>,
}

@fragment
fn shade_first_coverage(@builtin(position) position: vec4<f32>) -> ShadeOut {
    let texel = window_texel(vec2<i32>(position.xy), 0u);
    let cell = sample_cell(1u, 0u);
    let moved = move_on_surface(texel, cell.yz);
    let lit = light_surface(texel, moved.surface, moved.position, cell.w);
    return ShadeOut(lit.color, vec4<f32>(lit.slope, lit.penumbra));
}

// A listed sample, shaded for the cells it stands for. Where textures vary inside its pixel,
// `color` holds its radiance less its albedo times the slope: the part that the albedo of each
// cell it stands for is added to (gather_coverage).
@fragment
fn shade_group(@builtin(position) position: vec4<f32>) -> ShadeOut {
    let texel = entry_texel(list_entries[compact_index(vec2<u32>(position.xy))]);
    let m = vec2<i32>(i32(M));
    let g = load_groups(texel / m);
    let share = group_share(g, u32((texel.y % m.y) * m.x + texel.x % m.x));
    let moved = move_on_surface(texel, share.yz);
    let lit = light_surface(texel, moved.surface, moved.position, share.w);
    var color = lit.color;
    if g.detail {
        color = vec4<f32>(color.rgb - lit.albedo * lit.slope, color.a);
    }
    return ShadeOut(color, vec4<f32>(lit.slope, 0.0));
}

// The slopes in albedo that shade_first_coverage and shade_group wrote beside their colours
// (S's alpha: its light's penumbra, Lit.penumbra).
@group(2) @binding(14) var first_slope: texture_2d<f32>;
@group(2) @binding(15) var extra_slopes: texture_2d<f32>;

// The shading metric also asks for samples where S lies in a shadow's penumbra (`-coverage`):
// there the filtered visibility steps by a twentieth of the light (one PCF tap) wherever an
// occluder's edge crosses a tap's ray, so S's one sample misses steps inside the pixel that
// change it by less than the luma cross's thresholds notice, but by more than a code value.
override SHADOW_DETAIL: bool;
override C_SHADOW: f32;

#ifdef SHADOWS

// C_SHADOW times the luma range by which S's light can change across the pixel in a
// penumbra: S's penumbra rate (light per world unit of the filter's radius) over the pixel's
// reach on S's surface, spread over the √3 radii by which the filter's taps lean. Unlike the
// luma cross, it is not held to T_MIN and T_EDGE: a penumbra's steps are small everywhere.
fn shadow_k(pixel: vec2<i32>) -> f32 {
    let rate = textureLoad(first_slope, pixel, 0).a;
    if !(rate > 0.0) {
        return 0.0;
    }
    let texel = window_texel(pixel, 0u);
    let nm = load_normal_material(texel);
    let depth = linear_depth(texel);
    let v = normalize(frame.eye.xyz - world_position(texel, depth));
    let reach = surface_reach(pixel_rays(pixel), nm.xyz, depth, v);
    let half_spread = min(rate * reach * (0.5 / 1.7320508), HALF_MAX);
    return C_SHADOW * shown_span(pixel, half_spread, half_spread);
}
#endif

// The albedo of the sample at `texel` as the reference reads it; black for the background,
// whose slope is 0.
fn fine_sample_albedo(texel: vec2<i32>) -> vec3<f32> {
    let s = load_surface(texel);
    return select(surface_albedo(s, 1.0), vec3<f32>(0.0), s.material == BACKGROUND);
}

// The mean albedo of the pixel's cells, each read as the reference reads it.
fn pixel_albedo(pixel: vec2<i32>) -> vec3<f32> {
    var sum = vec3<f32>(0.0);
    for (var cell = 0u; cell < M * M; cell += 1u) {
        sum += fine_sample_albedo(pixel * i32(M) + cell_offset(cell));
    }
    return sum / f32(M * M);
}

// A pixel is the mean of its cells, each the colour of the shaded sample that stands for it.
// Where textures vary inside the pixel, a cell's colour is that sample's light carried to the
// cell's own albedo: radiance is affine in albedo (Lit.slope), so it is the listed part plus
// the albedo times the slope, and for S (which the metric reads whole) S moved by the pixel's
// mean albedo less its own.
@fragment
fn gather_coverage(@builtin(position) position: vec4<f32>) -> @location(0) vec4<f32> {
    let pixel = vec2<i32>(position.xy);
    let n = textureLoad(counts, pixel, 0).r;
    let g = load_groups(pixel);
    if n == 1u {
        let s = textureLoad(first, pixel, 0);
        if !g.detail {
            return s;
        }
        let cell = sample_cell(1u, 0u);
        let surface = move_on_surface(window_texel(pixel, 0u), cell.yz).surface;
        let used = select(surface_albedo(surface, cell.w), vec3<f32>(0.0), surface.material == BACKGROUND);
        let moved = s.rgb + (pixel_albedo(pixel) - used) * textureLoad(first_slope, pixel, 0).rgb;
        return vec4<f32>(max(moved, vec3<f32>(0.0)), s.a);
    }
    let width = textureDimensions(first).x;
    let base = list_offsets[u32(pixel.y) * width + u32(pixel.x)];
    var sum = vec4<f32>(0.0);
    if g.detail {
        for (var cell = 0u; cell < M * M; cell += 1u) {
            let at = compact_texel(base + cell_slot(g, cell));
            let albedo = fine_sample_albedo(pixel * i32(M) + cell_offset(cell));
            let color = textureLoad(extra_samples, at, 0);
            let carried = color.rgb + albedo * textureLoad(extra_slopes, at, 0).rgb;
            sum += vec4<f32>(max(carried, vec3<f32>(0.0)), color.a);
        }
        return sum / f32(M * M);
    }
    // Elsewhere each shaded sample is read once, weighted by its cells.
    let cells = slot_cells(g);
    for (var slot = 0u; slot < n; slot += 1u) {
        let count = (cells[slot / 6u] >> (5u * (slot % 6u))) & 31u;
        sum += textureLoad(extra_samples, compact_texel(base + slot), 0) * f32(count);
    }
    return sum / f32(M * M);
}

// The number of cells each slot stands for, five bits a slot, six slots a word.
fn slot_cells(g: Groups) -> vec3<u32> {
    var cells = vec3<u32>(0u);
    for (var cell = 0u; cell < M * M; cell += 1u) {
        let slot = cell_slot(g, cell);
        cells[slot / 6u] += 1u << (5u * (slot % 6u));
    }
    return cells;
}
