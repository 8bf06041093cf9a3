//! Brute-force shading: every G-buffer sample shaded (deferred 1×1 when the G-buffer is w × h,
//! the reference's supersampled image when it is M·w × M·h).

use super::{BuildContext, FULLSCREEN, HDR_FORMAT, Io, Node, Pass, Program, shading_inputs};
use crate::error::RenderError;
use crate::graph::{Access, Extent, PassDecl, Port, Resource};

/// One fragment per G-buffer sample, into `color` at the G-buffer's extent.
#[derive(Debug)]
pub(crate) struct ShadeNode {
    pub stalled: bool,
    pub shadows: Option<Resource>,
    /// A texture lookup's footprint relative to the G-buffer texel's: 1, or
    /// [`crate::technique::taa::FOOTPRINT`].
    pub footprint: f64,
}

impl Node for ShadeNode {
    fn decl(&self) -> PassDecl {
        let mut ports = shading_inputs(self.shadows);
        ports.push(Port::new("color", Resource::texture(HDR_FORMAT, Extent::GBuffer), Access::Attachment));
        PassDecl { name: "shade", ports }
    }

    fn build(&self, ctx: &mut BuildContext, io: &mut Io) -> Result<Box<dyn Pass>, RenderError> {
        let mut program = Program {
            shader: "shade.wgsl",
            vertex: FULLSCREEN.0,
            fragment: Some("shade_all"),
            constants: ctx.shading_constants(self.stalled),
        };
        // Left at the shader's default where it is 1, so that those pipelines stay as they were.
        if self.footprint != 1.0 {
            program.constants = program.constants.with("FOOTPRINT", self.footprint);
        }
        Ok(Box::new(ctx.screen(io, "shade", program, &["color"], FULLSCREEN.1, &[])?))
    }
}
