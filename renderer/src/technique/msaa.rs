//! MSAA-based deferred shading on the 4× G-buffer (`shaders/msaa.wgsl`): the pixels whose
//! samples lie on more than one surface marked and listed, their samples shaded one by one,
//! every other pixel shaded once, then the resolve.
//!
//! The edge test's thresholds: samples lie on one surface when they share a material, their
//! normals' cosine is at least [`EDGE_COS`] (Lauritzen's 0.99, about 8°) and each lies within
//! [`EDGE_GAP`] of the view depth from the tangent plane of the pixel's first sample: a step
//! in depth of more than 1 % is an edge, a slanted plane is not (where the stored normal is
//! the plane's; a shading normal that tilts away may list a steep pixel, which costs time only).

use super::Frame;
use super::adaptive::SURFACE_GAP;
use crate::error::RenderError;
use crate::graph::{Access, Extent, Output, PassDecl, PassId, Port, Resource};
use crate::passes::gbuffer::{MS_DEPTH, MS_NORMAL, MSAA_SAMPLES};
use crate::passes::{
    BuildContext, COUNT_FORMAT, Compute, FULLSCREEN, HDR_FORMAT, Io, Node, Pass, Program, pixel_list,
    shading_inputs_of,
};
use crate::pipelines::Constants;

const SHADER: &str = "msaa.wgsl";

/// The least cosine between the normals of one surface's samples.
pub const EDGE_COS: f32 = 0.99;

/// The largest distance of a sample from the first sample's tangent plane, as a fraction of
/// its view depth, on one surface: the `-coverage` variant's tolerance.
pub const EDGE_GAP: f32 = SURFACE_GAP;

/// Which of the passes after the G-buffer a node is.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum MsaaStep {
    Classify,
    Samples,
    Pixels,
}

#[derive(Debug)]
struct MsaaNode {
    step: MsaaStep,
    stalled: bool,
    shadows: Option<Resource>,
    width: u32,
    height: u32,
}

impl MsaaNode {
    fn name(&self) -> &'static str {
        match self.step {
            MsaaStep::Classify => "msaa_classify",
            MsaaStep::Samples => "msaa_samples",
            MsaaStep::Pixels => "msaa_pixels",
        }
    }

    /// The marks: two bits a pixel, sixteen pixels to a word.
    fn marks(&self) -> Resource {
        Resource::Buffer { bytes: 4 * u64::from(pixel_list::mark_words(self.width, self.height)) }
    }

    /// The compact target of the listed pixels' samples: room for every sample of every pixel.
    fn compact_size(&self) -> (u32, u32) {
        let samples = u64::from(MSAA_SAMPLES) * u64::from(self.width) * u64::from(self.height);
        pixel_list::compact_size(self.width, samples)
    }

    fn samples(&self) -> Resource {
        let (width, height) = self.compact_size();
        Resource::texture(HDR_FORMAT, Extent::Fixed { width, height })
    }

    fn constants(&self) -> Constants {
        let (compact_width, compact_height) = self.compact_size();
        Constants::new()
            .with("WIDTH", self.width)
            .with("HEIGHT", self.height)
            .with("COMPACT_WIDTH", compact_width)
            .with("COMPACT_HEIGHT", compact_height)
            .with("EDGE_COS", EDGE_COS)
            .with("EDGE_GAP", EDGE_GAP)
    }
}

impl Node for MsaaNode {
    fn decl(&self) -> PassDecl {
        let list = pixel_list::list(self.width, self.height);
        let ports = match self.step {
            MsaaStep::Classify => {
                let mut ports: Vec<Port> = shading_inputs_of(MSAA_SAMPLES, None)
                    .into_iter()
                    .filter(|p| [MS_NORMAL, MS_DEPTH].contains(&p.name))
                    .collect();
                ports.extend([
                    Port::new("edge_words", self.marks(), Access::StorageWrite),
                    Port::new("list_words", list, Access::StorageWrite),
                ]);
                ports
            }
            MsaaStep::Samples => {
                let mut ports = shading_inputs_of(MSAA_SAMPLES, self.shadows);
                ports.extend([
                    Port::new("list", list, Access::StorageRead),
                    Port::new("shaded_samples", self.samples(), Access::Attachment),
                ]);
                ports
            }
            MsaaStep::Pixels => {
                let mut ports = shading_inputs_of(MSAA_SAMPLES, self.shadows);
                ports.extend([
                    Port::new("edges", self.marks(), Access::StorageRead),
                    Port::new("list", list, Access::StorageRead),
                    Port::new("shaded_samples", self.samples(), Access::Loaded),
                    Port::new("color", Resource::texture(HDR_FORMAT, Extent::Output), Access::Attachment),
                    Port::new("counts", Resource::texture(COUNT_FORMAT, Extent::Output), Access::Attachment),
                ]);
                ports
            }
        };
        PassDecl { name: self.name(), ports }
    }

    fn build(&self, ctx: &mut BuildContext, io: &mut Io) -> Result<Box<dyn Pass>, RenderError> {
        let name = self.name();
        let (vertex, vertices, fragment, targets): (_, _, _, &[&str]) = match self.step {
            MsaaStep::Classify => {
                let (w, h) = (self.width, self.height);
                let constants = self.constants();
                let words = pixel_list::mark_words(w, h);
                let mut steps = vec![ctx.compute_step(
                    io,
                    SHADER,
                    "msaa_mark",
                    constants.clone(),
                    [words.div_ceil(64), 1, 1],
                )?];
                steps.extend(pixel_list::list_steps(ctx, io, SHADER, &constants, w, h)?);
                return Ok(Box::new(Compute { name, steps }));
            }
            MsaaStep::Samples => ("msaa_rows", 12, "msaa_samples", &["shaded_samples"]),
            MsaaStep::Pixels => (FULLSCREEN.0, FULLSCREEN.1, "msaa_pixels", &["color", "counts"]),
        };
        let constants = ctx.shading_constants(self.stalled).extend(&self.constants());
        let program = Program { shader: SHADER, vertex, fragment: Some(fragment), constants };
        Ok(Box::new(ctx.screen(io, name, program, targets, vertices, &[])?))
    }
}

/// MSAA-based deferred shading after the 4× G-buffer: the pixels an edge crosses classified and
/// listed, their samples shaded, then every pixel; the pass whose `color` is the HDR image.
pub(crate) fn add(frame: &mut Frame, stalled: bool) -> PassId {
    let (shadows, width, height, sources) = (frame.cubes, frame.width, frame.height, frame.sources);
    let g = &mut frame.graph;
    let [classify, shade_samples, pixels] = [MsaaStep::Classify, MsaaStep::Samples, MsaaStep::Pixels]
        .map(|step| super::add(g, MsaaNode { step, stalled, shadows, width, height }));
    for port in [MS_NORMAL, MS_DEPTH] {
        g.connect(sources.gbuffer, port, classify, port);
    }
    for pass in [shade_samples, pixels] {
        sources.feed(g, pass);
        g.connect(classify, "list_words", pass, "list");
    }
    g.connect(classify, "edge_words", pixels, "edges");
    g.connect(shade_samples, "shaded_samples", pixels, "shaded_samples");
    g.retain(pixels, "counts", Output::SampleCounts);
    pixels
}
