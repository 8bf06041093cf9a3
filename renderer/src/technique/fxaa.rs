//! FXAA 3.11's quality path (its default preset, 12) on the display-encoded image: `shaders/fxaa.wgsl`.

use super::Frame;
use crate::error::RenderError;
use crate::graph::{Access, Extent, PassDecl, PassId, Port, Resource};
use crate::passes::{BuildContext, FULLSCREEN, Io, Node, Pass, Program, display, display_format};

/// FXAA's defaults, as the shader's override constants: sub-pixel removal, edge threshold,
/// edge threshold minimum.
pub const SUBPIX: f64 = 0.75;
pub const EDGE_THRESHOLD: f64 = 0.166;
pub const EDGE_THRESHOLD_MIN: f64 = 0.0833;

#[derive(Debug)]
pub(crate) struct FxaaNode {
    pub bits: u32,
}

impl Node for FxaaNode {
    fn encodes_color(&self) -> bool {
        true
    }

    fn decl(&self) -> PassDecl {
        let image = Resource::texture(display_format(self.bits), Extent::Output);
        PassDecl {
            name: "fxaa",
            ports: vec![
                Port::new("encoded", image, Access::Loaded),
                Port::new("display", image, Access::Attachment),
            ],
        }
    }

    fn build(&self, ctx: &mut BuildContext, io: &mut Io) -> Result<Box<dyn Pass>, RenderError> {
        let constants = display::encoding(ctx.color)
            .with("SUBPIX", SUBPIX)
            .with("EDGE_THRESHOLD", EDGE_THRESHOLD)
            .with("EDGE_THRESHOLD_MIN", EDGE_THRESHOLD_MIN);
        let program =
            Program { shader: "fxaa.wgsl", vertex: FULLSCREEN.0, fragment: Some("fxaa"), constants };
        Ok(Box::new(ctx.screen(io, "fxaa", program, &["display"], FULLSCREEN.1, &[])?))
    }
}

/// FXAA on the display image that `display` wrote.
pub(crate) fn add(frame: &mut Frame, display: PassId) -> PassId {
    let fxaa = super::add(&mut frame.graph, FxaaNode { bits: frame.color.bits });
    frame.graph.connect(display, "display", fxaa, "encoded");
    fxaa
}
