//! Brute-force reference supersampling: all M² samples of the M·w × M·h G-buffer shaded, then
//! box-filtered into the pixel (`shaders/resolve.wgsl`).

use super::Frame;
use crate::error::RenderError;
use crate::graph::{Access, Extent, PassDecl, PassId, Port, Resource};
use crate::passes::{BuildContext, FULLSCREEN, HDR_FORMAT, Io, Node, Pass, Program};
use crate::pipelines::Constants;

/// Box-filters the M·w × M·h `supersampled` image into `color`.
#[derive(Debug)]
struct ResolveNode {
    m: u32,
}

impl Node for ResolveNode {
    fn decl(&self) -> PassDecl {
        PassDecl {
            name: "resolve",
            ports: vec![
                Port::new("supersampled", Resource::texture(HDR_FORMAT, Extent::GBuffer), Access::Loaded),
                Port::new("color", Resource::texture(HDR_FORMAT, Extent::Output), Access::Attachment),
            ],
        }
    }

    fn build(&self, ctx: &mut BuildContext, io: &mut Io) -> Result<Box<dyn Pass>, RenderError> {
        let program = Program {
            shader: "resolve.wgsl",
            vertex: FULLSCREEN.0,
            fragment: Some("resolve"),
            constants: Constants::new().with("M", self.m),
        };
        Ok(Box::new(ctx.screen(io, "resolve", program, &["color"], FULLSCREEN.1, &[])?))
    }
}

/// Every sample shaded, then resolved; the pass whose `color` is the HDR image.
pub(crate) fn add(frame: &mut Frame, m: u32, stalled: bool) -> PassId {
    let shade = frame.shade_all(stalled, 1.0);
    let resolve = super::add(&mut frame.graph, ResolveNode { m });
    frame.graph.connect(shade, "color", resolve, "supersampled");
    resolve
}
