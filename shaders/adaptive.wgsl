// Adaptive supersampling (Holländer, Boubekeur & Eisemann 2013) on the M·w × M·h G-buffer:
//
//   shade_first   S: one sample per pixel, at dither rank 0, filtered over the whole pixel
//   evaluate      n = 1 + round(k) samples per pixel from the geometry and shading metrics
//   scan_rows,    a prefix sum over the counts lists every (pixel, rank) still to shade,
//   scan_total,   densely, so the next pass runs one fragment per extra sample with no idle
//   emit          SIMD lanes
//   shade_extra   shades the list
//   gather        averages S with the pixel's extra samples (gather_loop shades them itself in a
//                 loop instead: the paper's simplest variant, kept for comparison); a pixel that
//                 takes all M² samples leaves S out and equals the reference. The `-area`
//                 variant weights each sample by the share of the pixel nearest to it (its
//                 cell); the `-cells` variant also shades each sample for its cell as a whole
//                 (technique/adaptive: Reconstruction::Cells)
//
// The `-coverage` variant (Reconstruction::Coverage) keeps S, the list and its passes, and
// changes what they hold: evaluate_coverage groups the window's samples into the surfaces they
// lie on and picks one sample per surface (more where the shading metric asks); shade_group
// shades each for the samples it stands for; gather_coverage weights each by their share of
// the pixel and, where textures vary inside the pixel, moves its light onto their own albedos.
//
// The metric is specified by its CPU twin in renderer/src/technique/adaptive/metric.rs; keep the
// two in step. The passes after S are in lib/adaptive/: evaluate, stable, list, gather, coverage.
// Passes bind group 2 by name (renderer/src/bindings.rs): each variable below is a port of the
// passes that use it, so binding numbers need only be unique.

#include "lib/common.wgsl"
#include "lib/finite.wgsl"
#include "lib/scene.wgsl"
#include "lib/gbuffer.wgsl"
#include "lib/shading.wgsl"
#include "lib/color.wgsl"
#include "lib/compact.wgsl"

// Set by technique/adaptive/passes.rs from AdaptiveSettings; no defaults here, so Rust is the one source.
override M: u32;
// k = C · M² · metric.
override C_DEPTH: f32;
// The depth variance relative to the squared mean depth (unit-free), or in world units².
override RELATIVE_DEPTH: bool;
override C_NORMAL: f32;
override C_SHADING: f32;
override T_MIN: f32;
override T_EDGE: f32;
override USE_GEOMETRY: bool;
override USE_SHADING: bool;
override FORCE_ALL: bool;
// Each sample stands for its cell of the pixel (the `-cells` variant): S is the pixel's
// centre, and extra samples are shaded at their cells' centroids with their cells' footprints.
override CELLS: bool;
// Each listed sample stands for the samples of its surface nearest to it (the `-coverage`
// variant); S is shaded as under CELLS.
override COVERAGE: bool;

// Whether the scene has textures: only through them can S differ from the reference's sample
// at rank 0, whose texture footprint is one G-buffer texel where S's spans the pixel
// (`footprint`).
#ifdef TEXTURED
const TEXTURED_SCENE: bool = true;
#else
const TEXTURED_SCENE: bool = false;
#endif

// The first rank a pixel of n samples shades after S. A pixel that takes its whole window is
// shaded exactly like the reference: in a scene with textures, rank 0 again at the reference's
// footprint instead of reusing S; without textures S is that same sample (the same texel,
// shaded alike) and is reused. Any other pixel reuses S, as the paper does, except under
// CELLS, where S stands for the whole pixel and so for no cell of one that takes more samples
// (technique/adaptive: Reconstruction::reshades_first).
fn first_extra_rank(n: u32) -> u32 {
    return select(1u, 0u, (TEXTURED_SCENE && n == M * M) || ((CELLS || COVERAGE) && n > 1u));
}

// Entry (n − 1)·M² + rank: the cell of sample `rank` among the first n, as (its share of the
// pixel, its centroid less the sample's position in G-buffer texels, its side in G-buffer
// texels) (technique/adaptive: sample_cells). Read by the `-area` and `-cells` variants.
@group(2) @binding(11) var<storage, read> sample_cells: array<vec4<f32>>;

fn sample_cell(n: u32, rank: u32) -> vec4<f32> {
    return sample_cells[(n - 1u) * M * M + rank];
}

// Sample `rank` of the pixel's first n, shaded for its cell.
fn shade_cell(texel: vec2<i32>, n: u32, rank: u32) -> vec4<f32> {
    let cell = sample_cell(n, rank);
    return shade_offset(texel, cell.yz, cell.w);
}

// Rank → row-major window cell, from the paper's Fig. 3 matrices: eight 4-bit cells per word,
// rank 0 lowest (technique/adaptive: packed_sample_order).
override ORDER_LOW: u32;
override ORDER_HIGH: u32;

fn window_cell(rank: u32) -> u32 {
    let word = select(ORDER_HIGH, ORDER_LOW, rank < 8u);
    return (word >> (4u * (rank % 8u))) & 15u;
}

// Window cell → rank, the paper's matrix itself, packed the same way (technique/adaptive:
// packed_dither_matrix).
override RANK_LOW: u32;
override RANK_HIGH: u32;

fn texel_rank(texel: vec2<i32>) -> u32 {
    let cell = u32(texel.y % i32(M)) * M + u32(texel.x % i32(M));
    let word = select(RANK_HIGH, RANK_LOW, cell < 8u);
    return (word >> (4u * (cell % 8u))) & 15u;
}

// S, the shade-first image.
@group(2) @binding(1) var first: texture_2d<f32>;
// Samples per pixel, written by evaluate.
@group(2) @binding(2) var counts: texture_2d<u32>;

fn window_texel(pixel: vec2<i32>, rank: u32) -> vec2<i32> {
    let cell = window_cell(rank);
    return pixel * i32(M) + vec2<i32>(i32(cell % M), i32(cell / M));
}

// A list entry holds what shading one extra sample needs, decoded with shifts alone: its
// G-buffer texel (x, y) and its pixel's sample count n, as x | y << TEXEL_BITS | (n − 1) <<
// 2·TEXEL_BITS. Storing the pixel and rank instead cost shade_extra a texture load (the count)
// and a division by the image width per sample (scalar on lavapipe's SIMD lanes).
const TEXEL_BITS: u32 = 14u;

fn list_entry(texel: vec2<i32>, n: u32) -> u32 {
    return u32(texel.x) | (u32(texel.y) << TEXEL_BITS) | ((n - 1u) << (2u * TEXEL_BITS));
}

fn entry_texel(entry: u32) -> vec2<i32> {
    let mask = (1u << TEXEL_BITS) - 1u;
    return vec2<i32>(i32(entry & mask), i32((entry >> TEXEL_BITS) & mask));
}

fn entry_count(entry: u32) -> u32 {
    return (entry >> (2u * TEXEL_BITS)) + 1u;
}

// A sample's texture footprint, in G-buffer texels, when n samples share the pixel: the filter
// width that gives the n samples together the same spread (variance) as the reference's M²
// one-texel samples, sqrt((1 + M²/n) / 2). It is 1 at n = M², like the reference's own.
fn footprint(n: u32) -> f32 {
    return sqrt(0.5 + 0.5 * f32(M * M) / f32(n));
}

@fragment
fn shade_first(@builtin(position) position: vec4<f32>) -> @location(0) vec4<f32> {
    let texel = window_texel(vec2<i32>(position.xy), 0u);
    if CELLS {
        return shade_cell(texel, 1u, 0u);
    }
    return shade(texel, footprint(1u));
}

#include "lib/adaptive/evaluate.wgsl"

#include "lib/adaptive/stable.wgsl"

#include "lib/adaptive/list.wgsl"

#include "lib/adaptive/gather.wgsl"

#include "lib/adaptive/coverage.wgsl"
