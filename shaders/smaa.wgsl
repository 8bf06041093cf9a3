// SMAA 1x (Jimenez, Echevarria, Sousa and Gutierrez, Eurographics 2012) on the display-encoded
// 1×1 image, ported from the reference implementation (SMAA.hlsl, MIT licence) with its
// default quality preset, which is its HIGH preset: threshold 0.1, 16 orthogonal and 8
// diagonal search steps, corner rounding 25 %. Three passes:
//
//   smaa_edges    luma edges of the encoded image, with local contrast adaptation, packed as
//                 bits, and the list of pixels with an edge (compute, five steps);
//   smaa_weights  for each listed pixel, the line it lies on and the area its pixel covers on
//                 either side (read from the area texture);
//   smaa_blend    each pixel blended with its neighbours by those weights.
//
// The reference is built around a GPU's bilinear filter: one filtered read of its RG8 edges
// texture between four texels tells which of eight edges are set, and line searches step two
// pixels a read. On a CPU rasterizer a filtered read is four loads and a blend, so the edges
// are kept as bits here instead: two per pixel (left, top), sixteen pixels to a word, once in
// rows and once in columns. A line search is then a bit scan over at most three words, and
// each filtered read is computed exactly from the bits it would have blended (with only the
// loads its known offsets need), so the searches end where the reference's end and the search
// and area textures are read at the same places. The weights are the reference's; rendering
// the reference's own texture-based searches gave the same image, but for 174 of 786 432
// pixels one code apart (atrium, 1024×768), from the blend's arithmetic.
//
// Coordinates are in pixels (pixel centres at +0.5), not the reference's normalized texture
// coordinates: the reference's `mad(RT_METRICS.xy, offset, texcoord)` is `pixel + offset` here.
// Reads outside the image are clamped to it, as the reference's samplers clamp. Edge detection
// reads code values (gamma space, as the reference asks); blending decodes them to linear light
// and encodes the result, as the reference's sRGB reads and writes do, for whichever transfer
// function the display uses.

#include "lib/common.wgsl"
#include "lib/color.wgsl"
#include "lib/compact.wgsl"
#include "lib/pixel_list.wgsl"

// Luma contrast that makes an edge, in code values / STEPS.
override THRESHOLD: f32 = 0.1;
// An edge is dropped when a neighbouring edge has this many times its contrast.
override LOCAL_CONTRAST_ADAPTATION: f32 = 2.0;
// Search steps along horizontal and vertical lines, each of two pixels (at most 16: a search
// scans 32 pixels in at most three words).
override MAX_SEARCH_STEPS: u32 = 16u;
// Search steps along diagonal lines, each of one pixel.
override MAX_SEARCH_STEPS_DIAG: f32 = 8.0;
// How much sharp corners are rounded, in percent.
override CORNER_ROUNDING: f32 = 25.0;

// The lookup textures' layout (`renderer/data/smaa/README.md`).
const AREA_MAX_DISTANCE: f32 = 16.0;
const AREA_MAX_DISTANCE_DIAG: f32 = 20.0;
// Diagonal areas are in the right half of the area texture.
const AREA_DIAG_COLUMN: f32 = 80.0;

@group(2) @binding(0) var encoded: texture_2d<f32>;
// The edge bits and the list of edge pixels are `lib/pixel_list.wgsl`'s.
// The weights of the listed pixels, in list order in the compact target.
@group(2) @binding(5) var blend_weights: texture_2d<f32>;
@group(2) @binding(6) var smaa_area: texture_2d<f32>;
@group(2) @binding(7) var smaa_search: texture_2d<f32>;

// ---------------------------------------------------------------------------------------------
// The edge bits. Plane 0 holds the image's rows as `lib/pixel_list.wgsl` lays them out: bit
// 2·(x % 16) the left edge, 2·(x % 16) + 1 the top edge; the list holds the pixels with an
// edge. Plane 1 holds its columns the same way, as if the image were transposed: its "rows" are
// the image's columns and its left and top swapped, so that one search serves both directions.

fn plane_size(plane: u32) -> vec2<i32> {
    return select(vec2<i32>(i32(WIDTH), i32(HEIGHT)), vec2<i32>(i32(HEIGHT), i32(WIDTH)), plane == 1u);
}

fn plane_words(plane: u32) -> i32 {
    return (plane_size(plane).x + i32(SLOTS) - 1) / i32(SLOTS);
}

fn plane_base(plane: u32) -> i32 {
    return select(0, i32(HEIGHT) * plane_words(0u), plane == 1u);
}

// The word `w` of row `y` of a plane, both within it.
fn edge_word(plane: u32, w: i32, y: i32) -> u32 {
    return edges[plane_base(plane) + y * plane_words(plane) + w];
}

// The two edge bits of pixel `p` of a plane, clamped to it.
fn edge_slot(plane: u32, p: vec2<i32>) -> u32 {
    let c = vec2<u32>(clamp(p, vec2<i32>(0), plane_size(plane) - 1));
    return (edge_word(plane, i32(c.x / SLOTS), i32(c.y)) >> (2u * (c.x % SLOTS))) & 3u;
}

// A plane's edges at pixel `p`: (left, top) as 0 or 1.
fn plane_edges(plane: u32, p: vec2<i32>) -> vec2<f32> {
    let slot = edge_slot(plane, p);
    return vec2<f32>(f32(slot & 1u), f32(slot >> 1u));
}

// The image's edges at pixel `p`: x its left edge, y its top edge.
fn edge(p: vec2<i32>) -> vec2<f32> {
    return plane_edges(0u, p);
}

// What a linear, clamping sampler returns from the reference's RG8 edges texture at pixel
// position `p`, exactly. (Reads at known offsets are written out where they are made.)
fn bilinear_plane(plane: u32, p: vec2<f32>) -> vec2<f32> {
    let t = p - 0.5;
    let base = floor(t);
    let f = t - base;
    let i = vec2<i32>(base);
    let top = mix(plane_edges(plane, i), plane_edges(plane, i + vec2<i32>(1, 0)), f.x);
    let bottom = mix(plane_edges(plane, i + vec2<i32>(0, 1)), plane_edges(plane, i + 1), f.x);
    return mix(top, bottom, f.y);
}

// The area texture blended bilinearly at texel-space position `t` (texel centres at integers).
fn bilinear_area(t: vec2<f32>) -> vec2<f32> {
    let base = floor(t);
    let f = t - base;
    let hi = vec2<i32>(textureDimensions(smaa_area)) - 1;
    let p0 = clamp(vec2<i32>(base), vec2<i32>(0), hi);
    let p1 = clamp(vec2<i32>(base) + 1, vec2<i32>(0), hi);
    let top = mix(textureLoad(smaa_area, p0, 0).rg, textureLoad(smaa_area, vec2<i32>(p1.x, p0.y), 0).rg, f.x);
    let bottom =
        mix(textureLoad(smaa_area, vec2<i32>(p0.x, p1.y), 0).rg, textureLoad(smaa_area, p1, 0).rg, f.x);
    return mix(top, bottom, f.y);
}

// ---------------------------------------------------------------------------------------------
// Pass 1: luma edge detection, into the edge bits

fn luma_at(p: vec2<i32>) -> f32 {
    let hi = vec2<i32>(i32(WIDTH), i32(HEIGHT)) - 1;
    return luminance(textureLoad(encoded, clamp(p, vec2<i32>(0), hi), 0).rgb);
}

// The reference's luma edge detection at pixel `p`: bit 0 its left edge, bit 1 its top edge.
fn detect(p: vec2<i32>) -> u32 {
    let l = luma_at(p);
    let left = luma_at(p + vec2<i32>(-1, 0));
    let top = luma_at(p + vec2<i32>(0, -1));
    let delta = abs(l - vec2<f32>(left, top));
    let found = delta >= vec2<f32>(THRESHOLD);
    if !any(found) {
        return 0u;
    }
    let right = luma_at(p + vec2<i32>(1, 0));
    let bottom = luma_at(p + vec2<i32>(0, 1));
    var max_delta = max(delta, abs(l - vec2<f32>(right, bottom)));
    let left_left = luma_at(p + vec2<i32>(-2, 0));
    let top_top = luma_at(p + vec2<i32>(0, -2));
    max_delta = max(max_delta, abs(vec2<f32>(left, top) - vec2<f32>(left_left, top_top)));
    let final_delta = max(max_delta.x, max_delta.y);
    let kept = found & (LOCAL_CONTRAST_ADAPTATION * delta >= vec2<f32>(final_delta));
    return select(0u, 1u, kept.x) | select(0u, 2u, kept.y);
}

// The pixel's marks (`lib/pixel_list.wgsl`): its edges.
fn pixel_marks(p: vec2<i32>) -> u32 {
    return detect(p);
}

// One word of plane 0: sixteen pixels of a row.
@compute @workgroup_size(64)
fn smaa_detect(@builtin(global_invocation_id) id: vec3<u32>) {
    write_mark_word(id.x);
}

// One word of plane 1 from sixteen words of plane 0: sixteen pixels of a column, left and top
// swapped.
@compute @workgroup_size(64)
fn smaa_transpose(@builtin(global_invocation_id) id: vec3<u32>) {
    let words = u32(plane_words(1u));
    if id.x >= WIDTH * words {
        return;
    }
    let x = id.x / words;
    let y0 = (id.x % words) * SLOTS;
    var word = 0u;
    for (var i = 0u; i < SLOTS; i++) {
        let y = y0 + i;
        if y < HEIGHT {
            let slot = (edge_words[y * row_words() + x / SLOTS] >> (2u * (x % SLOTS))) & 3u;
            word |= (((slot & 1u) << 1u) | (slot >> 1u)) << (2u * i);
        }
    }
    edge_words[u32(plane_base(1u)) + id.x] = word;
}

// ---------------------------------------------------------------------------------------------
// Pass 2: blending weights. Diagonal lines first.

struct DiagSearch {
    // Steps taken, and whether the last read still saw the line (> 0.9).
    end: vec2<f32>,
    // The last edges read.
    e: vec2<f32>,
}

// Walks along the diagonal `dir` through pixels with both edges set.
fn search_diag1(start: vec2<i32>, dir: vec2<i32>) -> DiagSearch {
    var q = start;
    var end = vec2<f32>(-1.0, 1.0);
    var e = vec2<f32>(0.0);
    while end.x < MAX_SEARCH_STEPS_DIAG - 1.0 && end.y > 0.9 {
        q += dir;
        e = edge(q);
        end = vec2<f32>(end.x + 1.0, dot(e, vec2<f32>(0.5)));
    }
    return DiagSearch(end, e);
}

// Walks along the other diagonal through pixels with a top edge whose right neighbour has a
// left edge. (The reference reads both in one filtered read a quarter pixel to the right and
// decodes them; these are the two texels it decodes.)
fn search_diag2(start: vec2<i32>, dir: vec2<i32>) -> DiagSearch {
    var q = start;
    var end = vec2<f32>(-1.0, 1.0);
    var e = vec2<f32>(0.0);
    while end.x < MAX_SEARCH_STEPS_DIAG - 1.0 && end.y > 0.9 {
        q += dir;
        e = vec2<f32>(edge(q + vec2<i32>(1, 0)).x, edge(q).y);
        end = vec2<f32>(end.x + 1.0, dot(e, vec2<f32>(0.5)));
    }
    return DiagSearch(end, e);
}

// The area on either side of a diagonal line `dist` pixels long each way, with crossing edges
// `e` (0–3 at each end): whole numbers, so one texel.
fn area_diag(dist: vec2<f32>, e: vec2<f32>) -> vec2<f32> {
    let t = AREA_MAX_DISTANCE_DIAG * e + dist + vec2<f32>(AREA_DIAG_COLUMN, 0.0);
    return textureLoad(smaa_area, vec2<i32>(t), 0).rg;
}

// Crossing edges at both ends merged into one value each; dropped where the search stopped
// without finding the line's end.
fn crossing(c: vec4<f32>, found: vec2<f32>) -> vec2<f32> {
    return select(2.0 * c.xz + c.yw, vec2<f32>(0.0), found >= vec2<f32>(0.9));
}

fn diag_weights(p: vec2<i32>, e: vec2<f32>) -> vec2<f32> {
    var weights = vec2<f32>(0.0);
    var d = vec4<f32>(0.0);
    if e.r > 0.0 {
        let s = search_diag1(p, vec2<i32>(-1, 1));
        d = vec4<f32>(s.end.x + f32(s.e.y > 0.9), d.y, s.end.y, d.w);
    }
    let up = search_diag1(p, vec2<i32>(1, -1));
    d = vec4<f32>(d.x, up.end.x, d.z, up.end.y);
    if d.x + d.y > 2.0 {
        let n = vec2<i32>(d.xy);
        let c = vec4<f32>(
            edge(p + vec2<i32>(-n.x - 1, n.x)).y,
            edge(p + vec2<i32>(-n.x, n.x)).x,
            edge(p + vec2<i32>(n.y + 1, -n.y)).y,
            edge(p + vec2<i32>(n.y + 1, -n.y - 1)).x,
        );
        weights += area_diag(d.xy, crossing(c, d.zw));
    }

    let down = search_diag2(p, vec2<i32>(-1, -1));
    d = vec4<f32>(down.end.x, 0.0, down.end.y, 0.0);
    if edge(p + vec2<i32>(1, 0)).x > 0.0 {
        let s = search_diag2(p, vec2<i32>(1, 1));
        d = vec4<f32>(d.x, s.end.x + f32(s.e.y > 0.9), d.z, s.end.y);
    }
    if d.x + d.y > 2.0 {
        let n = vec2<i32>(d.xy);
        let c = vec4<f32>(
            edge(p + vec2<i32>(-n.x - 1, -n.x)).y,
            edge(p + vec2<i32>(-n.x, -n.x - 1)).x,
            edge(p + vec2<i32>(n.y + 1, n.y)).yx,
        );
        weights += area_diag(d.xy, crossing(c, d.zw)).yx;
    }
    return weights;
}

// Horizontal and vertical lines. The reference searches two pixels a step from a filtered
// read that sees both pixels and the row above (offset by (−0.25, −0.125) and the like): it goes
// on while both pixels have a top edge and none of the four a left (crossing) edge. That is a
// bit scan here. The search texture then turns the last read into how far the line went
// within its last step.
fn search_length(e: vec2<f32>, offset: f32) -> f32 {
    let t = round(e * vec2<f32>(32.0, -32.0) + vec2<f32>(66.0 * offset, 32.0));
    let hi = vec2<i32>(textureDimensions(smaa_search)) - 1;
    return textureLoad(smaa_search, clamp(vec2<i32>(t), vec2<i32>(0), hi), 0).r;
}

// Bit 0 of each slot of word `w` of row `y`: the pixel lets a line through (a top edge, no
// left edge, none on the pixel above). Pixels outside the plane, and whole words before or
// after it, are its border pixel's, as a clamping read sees them.
fn open_slots(plane: u32, w: i32, y: i32) -> u32 {
    let c = clamp(w, 0, plane_words(plane) - 1);
    let here = edge_word(plane, c, y);
    let open = (here >> 1u) & ~here & ~edge_word(plane, c, max(y - 1, 0)) & LOW_BITS;
    let width = plane_size(plane).x;
    let inside = select(clamp(width - w * i32(SLOTS), 0, i32(SLOTS)), 0, w < 0);
    let border_slot = select(u32((width - 1) % i32(SLOTS)), 0u, w < 0);
    let border = select(0u, LOW_BITS, ((open >> (2u * border_slot)) & 1u) == 1u);
    let kept = select((1u << (2u * u32(inside))) - 1u, 0xFFFFFFFFu, inside == i32(SLOTS));
    return (open & kept) | (border & ~kept);
}

// How many pixels from `pixel` towards `dir` (±1) let the line through before the first that
// does not: 0 when `pixel` itself does not; 2 · MAX_SEARCH_STEPS or more when all do. The 32
// pixels a search can reach lie in three words.
fn open_run(plane: u32, pixel: vec2<i32>, dir: i32) -> i32 {
    let w = pixel.x >> 4u;
    let s = u32(pixel.x & 15);
    var closed0 = ~open_slots(plane, w, pixel.y) & LOW_BITS;
    let closed1 = ~open_slots(plane, w + dir, pixel.y) & LOW_BITS;
    let closed2 = ~open_slots(plane, w + 2 * dir, pixel.y) & LOW_BITS;
    if dir < 0 {
        // Towards lower slots: the highest closed slot at or below the start.
        closed0 &= (4u << (2u * s)) - 1u;
        let r0 = i32(s) - i32(firstLeadingBit(closed0) / 2u);
        let r1 = i32(s) + 16 - i32(firstLeadingBit(closed1) / 2u);
        let r2 = i32(s) + 32 - i32(firstLeadingBit(closed2) / 2u);
        return select(select(select(64, r2, closed2 != 0u), r1, closed1 != 0u), r0, closed0 != 0u);
    }
    closed0 &= 0xFFFFFFFFu << (2u * s);
    let r0 = i32(firstTrailingBit(closed0) / 2u) - i32(s);
    let r1 = 16 - i32(s) + i32(firstTrailingBit(closed1) / 2u);
    let r2 = 32 - i32(s) + i32(firstTrailingBit(closed2) / 2u);
    return select(select(select(64, r2, closed2 != 0u), r1, closed1 != 0u), r0, closed0 != 0u);
}

// The end of the line through `pixel` towards `dir` as the reference's search returns it: the
// last read's position after the step that ended the search, corrected by the search texture.
fn search_line(plane: u32, pixel: vec2<i32>, dir: i32) -> f32 {
    // The reads to the left see the pixel and the one before it; those to the right start
    // with the next pixel.
    let first = pixel + vec2<i32>(max(dir, 0), 0);
    let steps = min(open_run(plane, first, dir) / 2, i32(MAX_SEARCH_STEPS) - 1);
    let centre = vec2<f32>(pixel) + 0.5;
    // The reference's starts: (−0.25, −0.125) to the left, (1.25, −0.125) to the right.
    let start = centre + vec2<f32>(select(-0.25, 1.25, dir > 0), -0.125);
    let last = start + vec2<f32>(f32(2 * dir * steps), 0.0);
    let e = bilinear_plane(plane, last);
    let after = last.x + f32(2 * dir);
    let length = -(255.0 / 127.0) * search_length(e, select(0.0, 0.5, dir > 0)) + 3.25;
    return after - f32(dir) * length;
}

fn search_x_left(pixel: vec2<i32>) -> f32 {
    return search_line(0u, pixel, -1);
}

fn search_x_right(pixel: vec2<i32>) -> f32 {
    return search_line(0u, pixel, 1);
}

fn search_y_up(pixel: vec2<i32>) -> f32 {
    return search_line(1u, pixel.yx, -1);
}

fn search_y_down(pixel: vec2<i32>) -> f32 {
    return search_line(1u, pixel.yx, 1);
}

// The area on either side of a line `sqrt_d`² pixels long each way with crossing edges e1, e2
// (the area texture's distances are compressed quadratically).
fn area(sqrt_d: vec2<f32>, e1: f32, e2: f32) -> vec2<f32> {
    return bilinear_area(AREA_MAX_DISTANCE * round(4.0 * vec2<f32>(e1, e2)) + sqrt_d);
}

// How much of a corner's blending to keep: less at the ends of short lines with an edge
// turning away.
fn corner_rounding(d: vec2<f32>) -> vec2<f32> {
    let left_right = step(d.xy, d.yx);
    return (1.0 - CORNER_ROUNDING / 100.0) * left_right / (left_right.x + left_right.y);
}

// Corners of a horizontal line from pixel `ends.x` to `ends.y` of row `y`.
fn horizontal_corners(weights: vec2<f32>, ends: vec2<i32>, y: i32, d: vec2<f32>) -> vec2<f32> {
    let rounding = corner_rounding(d);
    var factor = vec2<f32>(1.0);
    factor.x -= rounding.x * edge(vec2<i32>(ends.x, y + 1)).x;
    factor.x -= rounding.y * edge(vec2<i32>(ends.y + 1, y + 1)).x;
    factor.y -= rounding.x * edge(vec2<i32>(ends.x, y - 2)).x;
    factor.y -= rounding.y * edge(vec2<i32>(ends.y + 1, y - 2)).x;
    return weights * saturate(factor);
}

// Corners of a vertical line from pixel `ends.x` to `ends.y` of column `x`.
fn vertical_corners(weights: vec2<f32>, ends: vec2<i32>, x: i32, d: vec2<f32>) -> vec2<f32> {
    let rounding = corner_rounding(d);
    var factor = vec2<f32>(1.0);
    factor.x -= rounding.x * edge(vec2<i32>(x + 1, ends.x)).y;
    factor.x -= rounding.y * edge(vec2<i32>(x + 1, ends.y + 1)).y;
    factor.y -= rounding.x * edge(vec2<i32>(x - 2, ends.x)).y;
    factor.y -= rounding.y * edge(vec2<i32>(x - 2, ends.y + 1)).y;
    return weights * saturate(factor);
}

// The pixel a search's end (a pixel centre) lies in.
fn end_pixel(end: vec2<f32>) -> vec2<i32> {
    return vec2<i32>(round(end - 0.5));
}

@vertex
fn smaa_rows(@builtin(vertex_index) index: u32) -> @builtin(position) vec4<f32> {
    return compact_rect(index, list[LIST_LENGTH]);
}

// For the edge pixel of this texel's list entry: red and green, the weights of its top edge
// (blending with the pixel above and this one); blue and alpha, of its left edge. The last
// block's tail past the list's end computes weights that nothing reads.
@fragment
fn smaa_weights(@builtin(position) position: vec4<f32>) -> @location(0) vec4<f32> {
    let p = listed_pixel(compact_index(vec2<u32>(position.xy)));
    let pixel = vec2<f32>(p) + 0.5;
    var weights = vec4<f32>(0.0);
    var e = edge(p);
    if e.g > 0.0 {
        // Diagonals have both a top and a left edge: searching from the top edge finds them,
        // and a diagonal found takes the place of the pixel's horizontal and vertical lines.
        let diagonal = diag_weights(p, e);
        weights = vec4<f32>(diagonal, 0.0, 0.0);
        if diagonal.x == -diagonal.y {
            let ends = vec2<f32>(search_x_left(p), search_x_right(p));
            let d = abs(round(ends - pixel.x));
            let x = end_pixel(ends);
            // Crossing edges at the ends, read a quarter pixel above the row as the reference
            // reads them.
            let e1 = mix(edge(vec2<i32>(x.x, p.y)).x, edge(vec2<i32>(x.x, p.y - 1)).x, 0.25);
            let e2 = mix(edge(vec2<i32>(x.y + 1, p.y)).x, edge(vec2<i32>(x.y + 1, p.y - 1)).x, 0.25);
            let found = area(sqrt(d), e1, e2);
            weights = vec4<f32>(horizontal_corners(found, x, p.y, d), 0.0, 0.0);
        } else {
            e.r = 0.0;
        }
    }
    if e.r > 0.0 {
        let ends = vec2<f32>(search_y_up(p), search_y_down(p));
        let d = abs(round(ends - pixel.y));
        let y = end_pixel(ends);
        // Crossing edges a quarter pixel left of the column.
        let e1 = mix(edge(vec2<i32>(p.x, y.x)).y, edge(vec2<i32>(p.x - 1, y.x)).y, 0.25);
        let e2 = mix(edge(vec2<i32>(p.x, y.y + 1)).y, edge(vec2<i32>(p.x - 1, y.y + 1)).y, 0.25);
        let found = area(sqrt(d), e1, e2);
        weights = vec4<f32>(weights.xy, vertical_corners(found, y, p.x, d));
    }
    return weights;
}

// ---------------------------------------------------------------------------------------------
// Pass 3: neighbourhood blending

// The encoded colour at `p`, decoded to display-relative linear light.
fn linear_at(p: vec2<i32>) -> vec3<f32> {
    let hi = vec2<i32>(i32(WIDTH), i32(HEIGHT)) - 1;
    let s = textureLoad(encoded, clamp(p, vec2<i32>(0), hi), 0).rgb;
    return vec3<f32>(transfer_decode(s.r), transfer_decode(s.g), transfer_decode(s.b));
}

// The blending weights of pixel `p`: zero without an edge, else its list entry's.
fn weights_of(p: vec2<i32>) -> vec4<f32> {
    let index = list_index(vec2<u32>(p));
    if index < 0 {
        return vec4<f32>(0.0);
    }
    return textureLoad(blend_weights, compact_texel(u32(index)), 0);
}

@fragment
fn smaa_blend(@builtin(position) position: vec4<f32>) -> @location(0) vec4<f32> {
    let p = vec2<i32>(position.xy);
    let hi = vec2<i32>(i32(WIDTH), i32(HEIGHT)) - 1;
    let here = weights_of(p);
    // The weights of this pixel's four sides: right and bottom come from the neighbours.
    let a = vec4<f32>(
        weights_of(min(p + vec2<i32>(1, 0), hi)).a,
        weights_of(min(p + vec2<i32>(0, 1), hi)).g,
        here.z,
        here.x,
    );
    if dot(a, vec4<f32>(1.0)) < 1e-5 {
        return textureLoad(encoded, p, 0);
    }
    // Blend along the axis with the larger weight, with the neighbours on either side: what
    // the reference's two filtered reads a fraction of a pixel off blend.
    let horizontal = max(a.x, a.z) > max(a.y, a.w);
    let amounts = select(a.yw, a.xz, horizontal);
    let step = select(vec2<i32>(0, 1), vec2<i32>(1, 0), horizontal);
    let centre = linear_at(p);
    let after = mix(centre, linear_at(p + step), amounts.x);
    let before = mix(centre, linear_at(p - step), amounts.y);
    let linear = (amounts.x * after + amounts.y * before) / (amounts.x + amounts.y);
    let signal = vec3<f32>(transfer_encode(linear.r), transfer_encode(linear.g), transfer_encode(linear.b));
    return vec4<f32>(requantize(signal), 1.0);
}
