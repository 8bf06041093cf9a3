//! What a scene is rendered with besides its geometry and lights, and the stall limits.

use crate::color::ColorSettings;
use crate::technique::adaptive::AdaptiveSettings;

/// What a scene is rendered with, besides its geometry and lights.
#[derive(Debug, Clone, PartialEq)]
pub struct RenderSettings {
    /// Output resolution; the G-buffer of an M×M mode is M·width × M·height.
    pub width: u32,
    pub height: u32,
    /// Dependent ALU iterations per shaded sample in `-stalled` modes.
    pub stall_iterations: u32,
    pub adaptive: AdaptiveSettings,
    /// From linear HDR to the display image: tonemap (HDR scenes), transfer, dither, bits.
    pub color: ColorSettings,
}

/// The longest stall honoured: lavapipe ends a shader invocation's loops after 65 535
/// iterations in all, and the stall loop takes 16 steps per iteration (plus up to 15 single
/// steps), which leaves room for the shader's light and shadow loops.
pub const MAX_STALL_ITERATIONS: u32 = 1_000_000;

/// The longest stall that `ExtraSamples::Loop` honours at M×M: its gather shades up to M²
/// samples in one invocation, and lavapipe's limit covers all their loops together (allowing
/// each sample 320 iterations of light and shadow loops beside the stall's). 54 880 at 4×4.
pub fn loop_stall_limit(m: u32) -> u32 {
    16 * (60_000 / (m * m).max(1)).saturating_sub(320)
}
