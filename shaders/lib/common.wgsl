// Shared by every pass: the per-frame uniforms, the fullscreen triangle and luminance.

struct Frame {
    view_proj: mat4x4<f32>,
    view: mat4x4<f32>,
    inv_view: mat4x4<f32>,
    // xyz: the camera's world position.
    eye: vec4<f32>,
    // x: tan(fov_y / 2) * aspect, y: tan(fov_y / 2), z: near, w: far.
    projection: vec4<f32>,
    // rgb: ambient radiance.
    ambient: vec4<f32>,
    // rgb: radiance where no geometry covers a sample.
    background: vec4<f32>,
    // x: exposure, a linear scale before tonemapping or display encoding; yz: the rendered
    // tile's origin in the frame's pixels (the dither's grain follows frame positions).
    display: vec4<f32>,
    // The rendered tile of the frame: its NDC maps to the frame's as ndc * tile.xy + tile.zw
    // ((1, 1, 0, 0) for the whole frame; the ground truth renders tile by tile).
    tile: vec4<f32>,
    // From this target's clip space to the previous frame's, unjittered: (NDC, depth, 1) maps
    // to where the point was, up to a factor of its clip w (temporal modes).
    reprojection: mat4x4<f32>,
    // xy: the sub-pixel jitter in pixels (a pixel's sample lies at its centre plus it, y down;
    // 0 but in temporal modes); zw: the whole frame's width and height in pixels.
    jitter: vec4<f32>,
    // x: 1 where the history holds earlier frames, 0 after a reset (temporal modes).
    history: vec4<f32>,
}

@group(0) @binding(0) var<uniform> frame: Frame;

// One triangle that covers the whole target: (-1, -1), (3, -1), (-1, 3).
@vertex
fn fullscreen(@builtin(vertex_index) index: u32) -> @builtin(position) vec4<f32> {
    let corner = vec2<f32>(f32((index << 1u) & 2u), f32(index & 2u));
    return vec4<f32>(corner * 2.0 - 1.0, 0.0, 1.0);
}

// Rec. 709 luminance of a linear colour, or with the same weights the luma of an encoded one
// (SMAA's edges). FXAA keeps the Rec. 601 weights of its reference.
fn luminance(c: vec3<f32>) -> f32 {
    return dot(c, vec3<f32>(0.2126, 0.7152, 0.0722));
}
