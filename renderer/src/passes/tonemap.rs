//! The tonemap pass of an HDR scene: sanitized, exposed linear HDR to display-relative linear
//! light through the curve whose constants [`Tonemap::curve`] solves in f64.

use super::{BuildContext, FULLSCREEN, HDR_FORMAT, Io, Node, Pass, Program};
use crate::color::Tonemap;
use crate::error::RenderError;
use crate::graph::{Access, Extent, PassDecl, Port, Resource};
use crate::pipelines::Constants;

/// Display-relative linear light between the tonemap and display passes. f32: at 10-bit PQ
/// for a 1000-nit display, codes 1–5 lie between 4·10⁻⁸ and 6·10⁻⁷, at or below f16's
/// smallest subnormal.
pub(crate) const LINEAR_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba32Float;

#[derive(Debug)]
pub(crate) struct TonemapNode {
    pub tonemap: Tonemap,
}

impl Node for TonemapNode {
    fn encodes_color(&self) -> bool {
        true
    }

    fn decl(&self) -> PassDecl {
        PassDecl {
            name: "tonemap",
            ports: vec![
                Port::new("hdr", Resource::texture(HDR_FORMAT, Extent::Output), Access::Loaded),
                Port::new("tonemapped", Resource::texture(LINEAR_FORMAT, Extent::Output), Access::Attachment),
            ],
        }
    }

    fn build(&self, ctx: &mut BuildContext, io: &mut Io) -> Result<Box<dyn Pass>, RenderError> {
        let constants = curve_constants(Constants::new(), &self.tonemap)?;
        let program =
            Program { shader: "tonemap.wgsl", vertex: FULLSCREEN.0, fragment: Some("tonemap"), constants };
        Ok(Box::new(ctx.screen(io, "tonemap", program, &["tonemapped"], FULLSCREEN.1, &[])?))
    }
}

/// `constants` with those of `lib/color.wgsl`'s tonemap set to `tonemap`'s curve, for every
/// shader that maps exposed HDR as the display will.
pub(crate) fn curve_constants(constants: Constants, tonemap: &Tonemap) -> Result<Constants, RenderError> {
    let curve = tonemap.curve()?;
    Ok(constants
        .with("CONTRAST", curve.contrast)
        .with("SHOULDER", curve.shoulder)
        .with("CURVE_B", curve.b)
        .with("CURVE_C", curve.c)
        .with("HDR_MAX", tonemap.hdr_max)
        .with("CROSSTALK", tonemap.crosstalk)
        .with("SATURATION", tonemap.saturation)
        .with("CROSS_SATURATION", tonemap.cross_saturation))
}
