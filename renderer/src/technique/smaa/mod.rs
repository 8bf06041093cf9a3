//! SMAA 1x on the display-encoded image, in three passes (`shaders/smaa.wgsl`): luma edges
//! packed as bits, blending weights from the area and search textures, neighbourhood blending.
//! The preset and the lookup textures are in `lookup.rs`, the textures' provenance and licence
//! in `renderer/data/smaa/`.

mod lookup;

pub use lookup::{LOOKUP_TEXTURES, PRESET_HIGH, SmaaPreset};

use super::Frame;
use crate::bindings::Bound;
use crate::error::RenderError;
use crate::graph::{Access, Extent, PassDecl, PassId, Port, Resource};
use crate::passes::{
    BuildContext, Compute, FULLSCREEN, Io, Node, Pass, Program, display, display_format, pixel_list,
};
use crate::pipelines::Constants;

const SHADER: &str = "smaa.wgsl";

/// Which of SMAA's passes a node is.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum SmaaStep {
    Edges,
    Weights,
    Blend,
}

#[derive(Debug)]
struct SmaaNode {
    step: SmaaStep,
    bits: u32,
    width: u32,
    height: u32,
}

impl SmaaNode {
    /// The pass's name.
    fn name(&self) -> &'static str {
        match self.step {
            SmaaStep::Edges => "smaa_edges",
            SmaaStep::Weights => "smaa_weights",
            SmaaStep::Blend => "smaa_blend",
        }
    }

    /// The edge bits: the image's rows, then its columns, sixteen pixels to a word.
    fn edge_bits(&self) -> Resource {
        let words =
            pixel_list::mark_words(self.width, self.height) + pixel_list::mark_words(self.height, self.width);
        Resource::Buffer { bytes: 4 * u64::from(words) }
    }

    /// The list of edge pixels.
    fn list(&self) -> Resource {
        pixel_list::list(self.width, self.height)
    }

    /// The compact target of the list's weights: room for every pixel.
    fn compact_size(&self) -> (u32, u32) {
        pixel_list::compact_size(self.width, u64::from(self.width) * u64::from(self.height))
    }

    /// The blending weights of each listed pixel's top (red, green) and left (blue, alpha)
    /// edges, stored at 8 bits as the reference stores them.
    fn weights(&self) -> Resource {
        let (width, height) = self.compact_size();
        Resource::texture(wgpu::TextureFormat::Rgba8Unorm, Extent::Fixed { width, height })
    }

    fn constants(&self, ctx: &BuildContext) -> Constants {
        let preset = PRESET_HIGH;
        display::encoding(ctx.color)
            .with("THRESHOLD", preset.threshold)
            .with("LOCAL_CONTRAST_ADAPTATION", preset.local_contrast_adaptation)
            .with("MAX_SEARCH_STEPS", preset.max_search_steps)
            .with("MAX_SEARCH_STEPS_DIAG", preset.max_search_steps_diag)
            .with("CORNER_ROUNDING", preset.corner_rounding)
            .with("WIDTH", self.width)
            .with("HEIGHT", self.height)
            .with("COMPACT_WIDTH", self.compact_size().0)
            .with("COMPACT_HEIGHT", self.compact_size().1)
    }
}

impl Node for SmaaNode {
    fn encodes_color(&self) -> bool {
        true
    }

    fn decl(&self) -> PassDecl {
        let image = Resource::texture(display_format(self.bits), Extent::Output);
        let ports = match self.step {
            SmaaStep::Edges => vec![
                Port::new("encoded", image, Access::Loaded),
                Port::new("edge_words", self.edge_bits(), Access::StorageWrite),
                Port::new("list_words", self.list(), Access::StorageWrite),
            ],
            SmaaStep::Weights => vec![
                Port::new("edges", self.edge_bits(), Access::StorageRead),
                Port::new("list", self.list(), Access::StorageRead),
                Port::new("blend_weights", self.weights(), Access::Attachment),
            ],
            SmaaStep::Blend => vec![
                Port::new("encoded", image, Access::Loaded),
                Port::new("edges", self.edge_bits(), Access::StorageRead),
                Port::new("list", self.list(), Access::StorageRead),
                Port::new("blend_weights", self.weights(), Access::Loaded),
                Port::new("display", image, Access::Attachment),
            ],
        };
        PassDecl { name: self.name(), ports }
    }

    fn build(&self, ctx: &mut BuildContext, io: &mut Io) -> Result<Box<dyn Pass>, RenderError> {
        let constants = self.constants(ctx);
        let name = self.name();
        let fragment = match self.step {
            SmaaStep::Edges => {
                // The rows' words, the columns' from them, then the list of edge pixels.
                let (w, h) = (self.width, self.height);
                let mut steps = Vec::new();
                for (entry, invocations) in [
                    ("smaa_detect", pixel_list::mark_words(w, h)),
                    ("smaa_transpose", pixel_list::mark_words(h, w)),
                ] {
                    let groups = [invocations.div_ceil(64), 1, 1];
                    steps.push(ctx.compute_step(io, SHADER, entry, constants.clone(), groups)?);
                }
                steps.extend(pixel_list::list_steps(ctx, io, SHADER, &constants, w, h)?);
                return Ok(Box::new(Compute { name, steps }));
            }
            SmaaStep::Weights => ("smaa_rows", 12, "smaa_weights", "blend_weights"),
            SmaaStep::Blend => (FULLSCREEN.0, FULLSCREEN.1, "smaa_blend", "display"),
        };
        let (vertex, vertices, entry, target) = fragment;
        let program = Program { shader: SHADER, vertex, fragment: Some(entry), constants };
        let [area, search] = LOOKUP_TEXTURES.map(|lookup| ctx.pipelines.constant_texture(&lookup));
        let lookup = |texture| Bound::Texture { texture, filterable: false, view_format: None };
        let owned = [("smaa_area", lookup(area)), ("smaa_search", lookup(search))];
        Ok(Box::new(ctx.screen(io, name, program, &[target], vertices, &owned)?))
    }
}

/// SMAA's three passes on the display image that `display` wrote.
pub(crate) fn add(frame: &mut Frame, display: PassId) -> PassId {
    let (bits, width, height) = (frame.color.bits, frame.width, frame.height);
    let g = &mut frame.graph;
    let [edges, weights, blend] = [SmaaStep::Edges, SmaaStep::Weights, SmaaStep::Blend]
        .map(|step| super::add(g, SmaaNode { step, bits, width, height }));
    g.connect(display, "display", edges, "encoded");
    g.connect(display, "display", blend, "encoded");
    for pass in [weights, blend] {
        g.connect(edges, "edge_words", pass, "edges");
        g.connect(edges, "list_words", pass, "list");
    }
    g.connect(weights, "blend_weights", blend, "blend_weights");
    blend
}
