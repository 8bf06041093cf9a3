//! The display pass: the linear HDR image encoded for display (exposure, clamp, sRGB) into the
//! 8-bit image that quality metrics are computed on.

use super::{BuildContext, DISPLAY_FORMAT, FULLSCREEN, HDR_FORMAT, Io, Node, Pass, Program};
use crate::RenderError;
use crate::graph::{Access, Extent, PassDecl, Port, Resource};
use crate::pipelines::Constants;

#[derive(Debug)]
pub(crate) struct DisplayNode;

impl Node for DisplayNode {
    fn decl(&self) -> PassDecl {
        PassDecl {
            name: "display",
            ports: vec![
                Port::new("hdr", Resource::texture(HDR_FORMAT, Extent::Output), Access::Loaded),
                Port::new("display", Resource::texture(DISPLAY_FORMAT, Extent::Output), Access::Attachment),
            ],
        }
    }

    fn build(&self, ctx: &mut BuildContext, io: &mut Io) -> Result<Box<dyn Pass>, RenderError> {
        let program = Program {
            shader: "display.wgsl",
            vertex: FULLSCREEN.0,
            fragment: Some("display"),
            constants: Constants::new(),
        };
        Ok(Box::new(ctx.screen(io, "display", program, "display", FULLSCREEN.1, &[])?))
    }
}
