// Adaptive supersampling, part of shaders/adaptive.wgsl: the gather.

// ---- gather: S, the counts, each pixel's first list index and the extra samples

@group(2) @binding(9) var<storage, read> list_offsets: array<u32>;
@group(2) @binding(10) var extra_samples: texture_2d<f32>;

// Average each pixel's samples weighted by the area of their cells (the `-area` and `-cells`
// variants), instead of alike (the paper). A pixel of 1 or M² samples is averaged alike
// either way (technique/adaptive: Reconstruction::weighted).
override WEIGHTED: bool;

// A pixel's samples, summed as they arrive and averaged at the end: alike, in the paper's
// order of operations, or weighted by area. `first_rank` is 1 where S is reused, else 0.
struct Average {
    sum: vec4<f32>,
    n: u32,
    weighted: bool,
}

// The paper's path keeps its exact operations (no multiplication by 1) and reads no weight.
fn start_average(pixel: vec2<i32>, n: u32, first_rank: u32) -> Average {
    let weighted = WEIGHTED && n > 1u && n < M * M;
    let s = select(vec4<f32>(0.0), textureLoad(first, pixel, 0), first_rank == 1u);
    if weighted {
        return Average(s * sample_cell(n, 0u).x, n, true);
    }
    return Average(s, n, false);
}

fn add_sample(average: ptr<function, Average>, rank: u32, sample: vec4<f32>) {
    if (*average).weighted {
        (*average).sum += sample * sample_cell((*average).n, rank).x;
    } else {
        (*average).sum += sample;
    }
}

fn finish_average(average: Average) -> vec4<f32> {
    return select(average.sum / f32(average.n), average.sum, average.weighted);
}

@fragment
fn gather(@builtin(position) position: vec4<f32>) -> @location(0) vec4<f32> {
    let pixel = vec2<i32>(position.xy);
    let n = textureLoad(counts, pixel, 0).r;
    let first_rank = first_extra_rank(n);
    var average = start_average(pixel, n, first_rank);
    let width = textureDimensions(first).x;
    let base = list_offsets[u32(pixel.y) * width + u32(pixel.x)];
    for (var j = 0u; j < n - first_rank; j += 1u) {
        add_sample(&average, first_rank + j, textureLoad(extra_samples, compact_texel(base + j), 0));
    }
    return finish_average(average);
}

@fragment
fn gather_loop(@builtin(position) position: vec4<f32>) -> @location(0) vec4<f32> {
    let pixel = vec2<i32>(position.xy);
    let n = textureLoad(counts, pixel, 0).r;
    let first_rank = first_extra_rank(n);
    var average = start_average(pixel, n, first_rank);
    let scale = footprint(n);
    for (var rank = first_rank; rank < n; rank += 1u) {
        let texel = window_texel(pixel, rank);
        if CELLS {
            add_sample(&average, rank, shade_cell(texel, n, rank));
        } else {
            add_sample(&average, rank, shade(texel, scale));
        }
    }
    return finish_average(average);
}
