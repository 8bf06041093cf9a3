//! Temporal anti-aliasing (`shaders/taa.wgsl`): the jittered frame's HDR image blended into a
//! history reprojected along the G-buffer's motion vectors, and the history kept for the next
//! frame.
//!
//! The resolve pass reads the history of the previous frame and writes the next one, so the two
//! cannot be one texture: the resolve writes `history_next`, and `taa_history` copies it into
//! `history`, which the graph carries into the next frame (`passes/keep.rs`).

use super::Frame;
use crate::error::RenderError;
use crate::graph::{Access, Extent, PassDecl, PassId, Port, Resource};
use crate::passes::gbuffer::{DEPTH, DEPTH_FORMAT, MOTION, MOTION_FORMAT};
use crate::passes::keep::KeepNode;
use crate::passes::{BuildContext, FULLSCREEN, HDR_FORMAT, Io, Node, Pass, Program};
use crate::pipelines::Constants;

/// The most frames a history averages where its pixel moves: the newest frame's weight, the
/// blend factor, is at least 1/10 (Bevy's default, 0.1).
pub const MOVING_FRAMES: u32 = 10;
/// The most frames a history averages where its pixel is still (moves less than 0.01 pixel).
pub const STILL_FRAMES: u32 = 32;
/// Jitter offsets cycle through this many points of the Halton(2, 3) sequence.
pub const JITTER_PHASES: u32 = 8;
/// Frames a TAA still renders from a reset before its image is taken: two cycles of the jitter,
/// so that on a still camera every jitter offset has the same weight in the average.
pub const WARMUP_FRAMES: u32 = 2 * JITTER_PHASES;

/// A texture lookup's footprint in TAA's shading, relative to the pixel's: √½, a mip bias of
/// −½. The jittered frames together sample each pixel many times, so with the pixel's own
/// footprint their average filters a texture twice (the mip's filter and the jitter's box),
/// and engines pair TAA with a negative bias; a finer footprint flickers more in motion. On the
/// quick tier (256×192): `texture`'s still is 29.4, 32.6 and 35.0 dB against the truth at 1,
/// √½ and ½ (deferred-1x1 35.4); `thin`'s instability 2.0, 3.5 and 6.9 · 10⁻⁴ (deferred-1x1
/// 5.3 · 10⁻⁴).
pub const FOOTPRINT: f64 = std::f64::consts::FRAC_1_SQRT_2;

/// The history's format: tonemapped colour and, in alpha, the frames it averages.
const HISTORY_FORMAT: wgpu::TextureFormat = HDR_FORMAT;

/// The jitter of frame `index` after a reset, in pixels within ±½: the Halton(2, 3) point
/// `index mod JITTER_PHASES + 1` (the point 0 of the sequence, (0, 0), is skipped) minus ½.
pub fn jitter(index: u32) -> [f64; 2] {
    let point = index % JITTER_PHASES + 1;
    [halton(point, 2) - 0.5, halton(point, 3) - 0.5]
}

/// The radical inverse of `index` in `base`.
fn halton(mut index: u32, base: u32) -> f64 {
    let (mut result, mut scale) = (0.0, 1.0);
    while index > 0 {
        scale /= f64::from(base);
        result += scale * f64::from(index % base);
        index /= base;
    }
    result
}

/// The resolve: `current` (this frame's HDR image) and the reprojected `history` into `color`
/// and `history_next`.
#[derive(Debug)]
struct TaaNode;

impl Node for TaaNode {
    fn decl(&self) -> PassDecl {
        let image = |format| Resource::texture(format, Extent::Output);
        PassDecl {
            name: "taa",
            ports: vec![
                Port::new("current", image(HDR_FORMAT), Access::Loaded),
                Port::new("history", image(HISTORY_FORMAT), Access::Loaded),
                Port::new(MOTION, image(MOTION_FORMAT), Access::Loaded),
                Port::new(DEPTH, image(DEPTH_FORMAT), Access::Loaded),
                Port::new("color", image(HDR_FORMAT), Access::Attachment),
                Port::new("history_next", image(HISTORY_FORMAT), Access::Attachment),
            ],
        }
    }

    fn build(&self, ctx: &mut BuildContext, io: &mut Io) -> Result<Box<dyn Pass>, RenderError> {
        let constants =
            Constants::new().with("MOVING_FRAMES", MOVING_FRAMES).with("STILL_FRAMES", STILL_FRAMES);
        let program = Program { shader: "taa.wgsl", vertex: FULLSCREEN.0, fragment: Some("taa"), constants };
        let targets = ["color", "history_next"];
        Ok(Box::new(ctx.screen(io, "taa", program, &targets, FULLSCREEN.1, &[])?))
    }
}

/// Copies `history_next` into `history`, which the next frame's resolve reads.
fn keep_history() -> KeepNode {
    let history = Resource::texture(HISTORY_FORMAT, Extent::Output);
    KeepNode { name: "taa_history", next: "history_next", kept: "history", resource: history }
}

/// The jittered frame shaded with TAA's texture footprint, resolved against the history, and
/// the history kept for the next frame; the pass whose `color` is the HDR image.
pub(crate) fn add(frame: &mut Frame, stalled: bool) -> PassId {
    let shade = frame.shade_all(stalled, FOOTPRINT);
    let (g, gbuffer) = (&mut frame.graph, frame.sources.gbuffer);
    let taa = super::add(g, TaaNode);
    g.connect(shade, "color", taa, "current");
    g.connect_all(gbuffer, taa, &[MOTION, DEPTH]);
    let keep = super::add(g, keep_history());
    g.connect(taa, "history_next", keep, "history_next");
    g.carry(keep, "history", taa, "history");
    taa
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_jitter_is_halton_2_3_centred_and_cycles() {
        assert_eq!(jitter(0), [0.0, 1.0 / 3.0 - 0.5]);
        assert_eq!(jitter(1), [0.25 - 0.5, 2.0 / 3.0 - 0.5]);
        assert_eq!(jitter(2), [0.75 - 0.5, 1.0 / 9.0 - 0.5]);
        assert_eq!(jitter(JITTER_PHASES), jitter(0));
        let points: Vec<[f64; 2]> = (0..JITTER_PHASES).map(jitter).collect();
        for (i, p) in points.iter().enumerate() {
            assert!(p.iter().all(|v| v.abs() < 0.5), "{p:?}");
            assert!(!points[..i].contains(p), "{p:?} repeats");
        }
        // Over a cycle the offsets balance to within one eighth of a pixel.
        let mean = |axis: usize| points.iter().map(|p| p[axis]).sum::<f64>() / f64::from(JITTER_PHASES);
        assert!(mean(0).abs() < 0.125 && mean(1).abs() < 0.125, "{} {}", mean(0), mean(1));
    }
}
