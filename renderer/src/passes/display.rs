//! The display pass: display-relative linear light to the code values of the display image
//! (transfer function, dither, quantization; see `lib/color.wgsl`). In an LDR scene it reads
//! the HDR image directly and exposes it first.

use super::{BuildContext, FULLSCREEN, Io, Node, Pass, Program, display_format};
use crate::color::ColorSettings;
use crate::error::RenderError;
use crate::graph::{Access, Extent, PassDecl, Port, Resource};
use crate::pipelines::Constants;

#[derive(Debug)]
pub(crate) struct DisplayNode {
    /// The input is the HDR image (an LDR scene): expose it here.
    pub expose: bool,
    pub bits: u32,
}

impl DisplayNode {
    /// The HDR image in an LDR scene, else the tonemap pass's output.
    fn input_format(&self) -> wgpu::TextureFormat {
        if self.expose { super::HDR_FORMAT } else { super::tonemap::LINEAR_FORMAT }
    }
}

impl Node for DisplayNode {
    fn encodes_color(&self) -> bool {
        true
    }

    fn decl(&self) -> PassDecl {
        PassDecl {
            name: "display",
            ports: vec![
                Port::new("linear", Resource::texture(self.input_format(), Extent::Output), Access::Loaded),
                Port::new(
                    "display",
                    Resource::texture(display_format(self.bits), Extent::Output),
                    Access::Attachment,
                ),
            ],
        }
    }

    fn build(&self, ctx: &mut BuildContext, io: &mut Io) -> Result<Box<dyn Pass>, RenderError> {
        let program = Program {
            shader: "display.wgsl",
            vertex: FULLSCREEN.0,
            fragment: Some("display"),
            constants: encoding(ctx.color).flag("EXPOSE", self.expose),
        };
        Ok(Box::new(ctx.screen(io, "display", program, &["display"], FULLSCREEN.1, &[])?))
    }
}

/// The override constants of the display encoding: transfer function, code values, dither.
pub(crate) fn encoding(color: &ColorSettings) -> Constants {
    let scale = color.dither_scale();
    Constants::new()
        .with("TRANSFER", color.transfer.shader_id())
        .with("PEAK_FRACTION", color.transfer.peak_fraction())
        .with("STEPS", color.max_code())
        .with("DITHER", color.dither.shader_id())
        .with("DITHER_BLACK", scale.black)
        .with("DITHER_BIGGEST", scale.biggest)
        .with("DITHER_TOP", scale.top)
}
