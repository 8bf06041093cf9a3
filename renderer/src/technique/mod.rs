//! The anti-aliasing techniques, one room each: `fxaa.rs`, `smaa/`, `msaa.rs`, `taa.rs`,
//! `reference.rs` and `adaptive/` hold a technique's settings, its passes and the part of the
//! frame it adds. Deferred shading, the G-buffer, shadows and the colour end that every
//! technique shares are in `passes/`.
//!
//! This file registers them: a technique is a variant of [`Technique`], its facts are the arms
//! of the `impl Technique` below (the compiler names every one a new variant lacks), and its
//! passes join a frame in `add_shading` (between the G-buffer and the HDR image) or
//! `add_post_process` (on the display image).

pub mod adaptive;
pub(crate) mod fxaa;
pub(crate) mod msaa;
pub(crate) mod reference;
pub mod smaa;
pub mod taa;

use std::ops::RangeInclusive;

use crate::color::ColorSettings;
use crate::error::RenderError;
use crate::graph::{Graph, PassId, Resource};
use crate::passes::shade::ShadeNode;
use crate::passes::{Node, gbuffer, shadow};
use adaptive::{AdaptiveSettings, Counts, Metrics, Reconstruction};

#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Technique {
    /// One sample per pixel.
    Deferred,
    /// One sample per pixel, then FXAA 3.11 on the display-encoded image.
    Fxaa,
    /// One sample per pixel, then SMAA 1x on the display-encoded image.
    Smaa,
    /// MSAA-based deferred shading: a w × h G-buffer of 4 samples per pixel (M = 2: as many
    /// samples as the 2×2 grid, at the rotated-grid positions), shaded per sample where they
    /// lie on more than one surface and once per pixel elsewhere.
    Msaa,
    /// Temporal anti-aliasing: one jittered sample per pixel and frame, blended into a history
    /// reprojected along per-pixel motion vectors (see `taa.rs`). Its image depends on the
    /// frames before: a still is the last of [`taa::WARMUP_FRAMES`] frames rendered from a
    /// reset at one camera.
    Taa,
    /// All M² samples of an M·w × M·h G-buffer shaded, box-filtered.
    Reference,
    /// Holländer et al. 2013: the same G-buffer, samples shaded where the metrics ask (in this
    /// frame alone, or also in the frame before), and the pixel reconstructed from them.
    Adaptive(Metrics, Reconstruction, Counts),
}

impl Technique {
    /// Adaptive supersampling as the paper has it: both metrics, samples alike, counts per
    /// frame (`adaptive-MxM`).
    pub const PAPER: Technique = Technique::Adaptive(Metrics::Both, Reconstruction::Equal, Counts::PerFrame);

    /// The techniques that adaptive supersampling is measured against, in the order their modes
    /// are listed: what engineers ship, and the reference.
    pub const COMPARED: [Technique; 6] = [
        Technique::Deferred,
        Technique::Fxaa,
        Technique::Smaa,
        Technique::Msaa,
        Technique::Taa,
        Technique::Reference,
    ];

    /// The first word of its mode ids: `deferred`, `fxaa`, `adaptive`, …
    pub fn name(self) -> &'static str {
        match self {
            Technique::Deferred => "deferred",
            Technique::Fxaa => "fxaa",
            Technique::Smaa => "smaa",
            Technique::Msaa => "msaa",
            Technique::Taa => "taa",
            Technique::Reference => "reference",
            Technique::Adaptive(..) => "adaptive",
        }
    }

    /// How people write it: `FXAA`, `adaptive supersampling`.
    pub fn label(self) -> &'static str {
        match self {
            Technique::Deferred => "deferred shading",
            Technique::Fxaa => "FXAA",
            Technique::Smaa => "SMAA",
            Technique::Msaa => "4× MSAA",
            Technique::Taa => "TAA",
            Technique::Reference => "the reference",
            Technique::Adaptive(..) => "adaptive supersampling",
        }
    }

    /// The whole id of a technique that comes in one size only, which its id does not spell
    /// as M×M: `fxaa`, `msaa-4x`. `None` for the techniques whose ids name their M.
    pub fn fixed_id(self) -> Option<&'static str> {
        match self {
            Technique::Fxaa => Some("fxaa"),
            Technique::Smaa => Some("smaa"),
            Technique::Msaa => Some("msaa-4x"),
            Technique::Taa => Some("taa"),
            Technique::Deferred | Technique::Reference | Technique::Adaptive(..) => None,
        }
    }

    /// What a mode id that names this technique but not its [`fixed_id`](Self::fixed_id) is
    /// told.
    pub fn fixed_id_rule(self) -> &'static str {
        match self {
            Technique::Msaa => "lavapipe renders 4× MSAA only",
            Technique::Fxaa => "FXAA has no size",
            Technique::Smaa => "SMAA has no size",
            Technique::Taa => "TAA has no size",
            Technique::Deferred | Technique::Reference | Technique::Adaptive(..) => "",
        }
    }

    /// The M (samples per pixel side) it comes in. MSAA's 4 samples are the 2×2 grid's count.
    pub fn sizes(self) -> RangeInclusive<u32> {
        match self {
            Technique::Deferred | Technique::Fxaa | Technique::Smaa | Technique::Taa => 1..=1,
            Technique::Msaa => 2..=2,
            // reference-1x1 exists to check that the supersampling path equals deferred-1x1;
            // no group lists it.
            Technique::Reference => 1..=4,
            Technique::Adaptive(..) => 2..=4,
        }
    }

    /// The technique whose image at the same M this one's is compared with: the reference for
    /// adaptive supersampling and MSAA (which shades as many samples), deferred shading for the
    /// post-processes (whose input it is) and TAA (which blends it over frames).
    pub fn compared_with(self) -> Option<Technique> {
        match self {
            Technique::Adaptive(..) | Technique::Msaa => Some(Technique::Reference),
            Technique::Fxaa | Technique::Smaa | Technique::Taa => Some(Technique::Deferred),
            Technique::Deferred | Technique::Reference => None,
        }
    }

    /// Samples per texel of its G-buffer: MSAA rasterizes w × h with 4, every other technique
    /// M·w × M·h with 1.
    pub fn gbuffer_samples(self) -> u32 {
        if self == Technique::Msaa { gbuffer::MSAA_SAMPLES } else { 1 }
    }

    /// Whether it jitters its samples from frame to frame (TAA): its frames at one camera
    /// differ, so its still is the last of a run of warm-up frames, and its G-buffer writes
    /// motion vectors.
    pub fn is_jittered(self) -> bool {
        self == Technique::Taa
    }

    /// Whether it keeps state from one frame for the next (TAA's history, a `-stable` mode's
    /// sample counts): it has frame uniforms of its own, with the previous frame's camera, and
    /// resources the graph carries into the next frame.
    pub fn carries_history(self) -> bool {
        self.is_jittered() || matches!(self, Technique::Adaptive(_, _, Counts::Stable))
    }
}

pub(crate) type FrameGraph = Graph<Box<dyn Node>>;

/// Adds `node` to the graph under the name it declares.
pub(crate) fn add(graph: &mut FrameGraph, node: impl Node + 'static) -> PassId {
    graph.add(node.decl(), Box::new(node))
}

/// The passes that every shading pass reads from.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Sources {
    pub gbuffer: PassId,
    /// The G-buffer's ports: single- or multisampled.
    pub ports: [&'static str; 4],
    pub shadow: Option<PassId>,
}

impl Sources {
    /// Connects the G-buffer and the shadow cubes to `pass`.
    pub fn feed(self, graph: &mut FrameGraph, pass: PassId) {
        graph.connect_all(self.gbuffer, pass, &self.ports);
        if let Some(shadow) = self.shadow {
            graph.connect(shadow, shadow::CUBES, pass, shadow::CUBES);
        }
    }
}

/// A frame as a technique finds it: the graph with its shadow and G-buffer passes, and what
/// the technique's passes are built from.
#[derive(Debug)]
pub(crate) struct Frame<'a> {
    pub graph: FrameGraph,
    pub sources: Sources,
    /// The shadow cube array of a scene with shadow-casting lights.
    pub cubes: Option<Resource>,
    pub width: u32,
    pub height: u32,
    /// The scene has textures.
    pub textured: bool,
    /// An animation plays: the G-buffer of a mode that carries a history writes motion
    /// vectors, which hold the objects' motion as well as the camera's.
    pub moving: bool,
    pub color: &'a ColorSettings,
    pub adaptive: &'a AdaptiveSettings,
    /// The device's limits, which bound the lists some techniques build.
    pub limits: &'a wgpu::Limits,
}

impl Frame<'_> {
    /// One sample of the G-buffer shaded per texel (deferred shading, the reference's
    /// supersampled image), each texture lookup `footprint` times the texel's.
    pub fn shade_all(&mut self, stalled: bool, footprint: f64) -> PassId {
        let shade = add(&mut self.graph, ShadeNode { stalled, shadows: self.cubes, footprint });
        self.sources.feed(&mut self.graph, shade);
        shade
    }
}

/// The passes from the G-buffer to the HDR image of `technique` at `m`: the pass whose `color`
/// port holds it.
pub(crate) fn add_shading(
    frame: &mut Frame,
    technique: Technique,
    m: u32,
    stalled: bool,
) -> Result<PassId, RenderError> {
    Ok(match technique {
        Technique::Deferred | Technique::Fxaa | Technique::Smaa => frame.shade_all(stalled, 1.0),
        Technique::Reference => reference::add(frame, m, stalled),
        Technique::Msaa => msaa::add(frame, stalled),
        Technique::Taa => taa::add(frame, stalled),
        Technique::Adaptive(metrics, reconstruction, counts) => {
            adaptive::add(frame, adaptive::Variant { metrics, reconstruction, counts }, m, stalled)?
        }
    })
}

/// The passes of `technique` on the display image that `display` wrote: the pass whose
/// `display` port holds the frame's result (`display` itself where the technique has none).
pub(crate) fn add_post_process(frame: &mut Frame, technique: Technique, display: PassId) -> PassId {
    match technique {
        Technique::Fxaa => fxaa::add(frame, display),
        Technique::Smaa => smaa::add(frame, display),
        Technique::Deferred
        | Technique::Msaa
        | Technique::Taa
        | Technique::Reference
        | Technique::Adaptive(..) => display,
    }
}
