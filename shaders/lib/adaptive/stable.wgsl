// Adaptive supersampling, part of shaders/adaptive.wgsl: the `-stable` variant's counts.

// ---- evaluate_stable: the `-stable` variant's counts, which follow the frame before's
//
// The metric's count n of this frame and the count c that the pixel's surface had in the frame
// before combine by technique/adaptive: StableCounts::next (its CPU twin): c rises at once to n, and
// falls only where n asks for more than STABLE_HOLD samples fewer, and then by at most the
// share STABLE_DECAY of itself a frame. The frame before's count is the one of the pixel where
// the window's nearest sample lay then (the reprojection in the frame uniforms where the scene
// stands still, so points move with the camera alone; the G-buffer's motion vectors where objects
// move, and the reprojection still for the background), taken only where that pixel could see the
// point: where it lay no deeper than the deepest sample of that pixel's window, by
// STABLE_DEPTH_TOLERANCE (the background counts as deepest). A depth within a tolerance of one
// sample's would fail on grazing surfaces, whose depth changes by a percent across a pixel.
// Elsewhere (a disocclusion, the frame's edge, the first frame after a reset) n is taken alone.

override STABLE_HOLD: f32;
override STABLE_DECAY: f32;
override STABLE_DEPTH_TOLERANCE: f32;

// The frame before's counts: x the count (held as a float: the decay may leave it between
// whole samples), y the linear view depth of the deepest sample in its pixel's window,
// or -1 where a sample of it saw the background.
@group(2) @binding(16) var count_history: texture_2d<f32>;

#ifdef MOVING
// Each G-buffer sample's motion in the frame's pixels and its linear depth then (gbuffer.wgsl).
@group(2) @binding(17) var gb_motion: texture_2d<f32>;
#endif

const SAW_BACKGROUND: f32 = -1.0;

struct StableOut {
    @location(0) counts: u32,
    // This frame's, for the next: the same layout as count_history.
    @location(1) count_history_next: vec4<f32>,
}

// A window's nearest sample (its texel and reversed depth, 0 where no surface covers it) and
// its deepest reversed depth.
struct WindowDepths {
    nearest_texel: vec2<i32>,
    nearest: f32,
    deepest: f32,
}

fn add_window_depth(w: ptr<function, WindowDepths>, texel: vec2<i32>, depth: f32) {
    if depth > (*w).nearest {
        (*w).nearest_texel = texel;
        (*w).nearest = depth;
    }
    (*w).deepest = min((*w).deepest, depth);
}

// One row of the window, left to right, from the row's halves of its two blocks (as
// add_depth_row reads them).
fn add_window_row(w: ptr<function, WindowDepths>, start: vec2<i32>, left: vec2<f32>, right: vec2<f32>) {
    add_window_depth(w, start, left.x);
    add_window_depth(w, start + vec2<i32>(1, 0), left.y);
    if M > 2u {
        add_window_depth(w, start + vec2<i32>(2, 0), right.x);
    }
    if M > 3u {
        add_window_depth(w, start + vec2<i32>(3, 0), right.y);
    }
}

// The nearest sample is the first of the largest reversed depth in row-major order. Read four
// at a time as window_depths reads them (sixteen loads cost evaluate a fifth more at 4×4).
fn window_extent(origin: vec2<i32>) -> WindowDepths {
    let size = vec2<f32>(textureDimensions(gb_depth));
    var w = WindowDepths(origin, 0.0, 1.0);
    for (var row = 0u; row < M; row += 2u) {
        let start = origin + vec2<i32>(0, i32(row));
        let left = textureGather(gb_depth, texel_sampler, vec2<f32>(start + 1) / size);
        var right = vec4<f32>(0.0);
        if M > 2u {
            right = textureGather(gb_depth, texel_sampler, vec2<f32>(start + vec2<i32>(3, 1)) / size);
        }
        add_window_row(&w, start, left.wz, right.wz);
        if row + 1u < M {
            add_window_row(&w, start + vec2<i32>(0, 1), left.xy, right.xy);
        }
    }
    return w;
}

// Where the window's nearest sample lay in the frame before, in the frame's pixels (xy), and its
// linear depth then (z), or a NaN where no camera can take it back.
fn place_before(w: WindowDepths) -> vec3<f32> {
    let gbuffer_size = vec2<f32>(textureDimensions(gb_depth));
    let point = vec2<f32>(w.nearest_texel) + 0.5;
#ifdef MOVING
    if w.nearest > 0.0 {
        let motion = textureLoad(gb_motion, w.nearest_texel, 0);
        return vec3<f32>(point / f32(M) - motion.xy, motion.z);
    }
#endif
    let size = frame.jitter.zw;
    let ndc = point / gbuffer_size * vec2<f32>(2.0, -2.0) + vec2<f32>(-1.0, 1.0);
    let before = frame.reprojection * vec4<f32>(ndc, w.nearest, 1.0);
    let then = (before.xy / before.w * vec2<f32>(0.5, -0.5) + 0.5) * size;
    // before.w is the point's clip w then over its clip w now: its linear depth then over now.
    return vec3<f32>(then, before.w * linear_depth_of(w.nearest));
}

// The count the pixel's surface had in the frame before, or -1 where the history does not hold
// it.
fn count_before(w: WindowDepths) -> f32 {
    if frame.history.x == 0.0 {
        return -1.0;
    }
    let size = frame.jitter.zw;
    let place = place_before(w);
    let then = place.xy;
    // Also false for NaN: a point that no camera can reproject.
    if !(all(then >= vec2<f32>(0.0)) && all(then < size)) {
        return -1.0;
    }
    let kept = textureLoad(count_history, vec2<i32>(then), 0);
    if kept.y == SAW_BACKGROUND {
        return kept.x;
    }
    if w.nearest == 0.0 {
        // The background now, where the pixel before saw none.
        return -1.0;
    }
    return select(-1.0, kept.x, place.z <= kept.y * (1.0 + STABLE_DEPTH_TOLERANCE));
}

@fragment
fn evaluate_stable(@builtin(position) position: vec4<f32>) -> StableOut {
    let pixel = vec2<i32>(position.xy);
    let now = f32(metric_count(pixel));
    let w = window_extent(pixel * i32(M));
    let before = count_before(w);
    var count = now;
    if before >= 1.0 {
        let held = now >= before - STABLE_HOLD;
        count = select(max(now, before * (1.0 - STABLE_DECAY)), max(now, before), held);
    }
    let deepest = select(SAW_BACKGROUND, linear_depth_of(w.deepest), w.deepest > 0.0);
    // A whole count in [1, M²]: `count` lies between two counts that do.
    let samples = clamp(u32(ceil(count - 0.001)), 1u, M * M);
    return StableOut(samples, vec4<f32>(count, deepest, 0.0, 0.0));
}
