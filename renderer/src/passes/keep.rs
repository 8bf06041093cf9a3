//! A history kept for the next frame: a pass that reads its history while writing the next one
//! cannot write into the texture it reads, so it writes `next`, and this pass copies that into
//! the texture the graph carries into the next frame (TAA's colour history, a `-stable`
//! adaptive mode's counts). A pair of textures swapped every frame would save the copy (under
//! 1 ms at 1024×768 on lavapipe) at the price of two bind groups for every pass that reads
//! either.

use super::{BuildContext, Io, Node, Pass};
use crate::error::RenderError;
use crate::graph::{Access, PassDecl, Port, Resource};

/// Copies port `next` into port `kept`, both `resource`.
#[derive(Debug)]
pub(crate) struct KeepNode {
    pub name: &'static str,
    pub next: &'static str,
    pub kept: &'static str,
    pub resource: Resource,
}

impl Node for KeepNode {
    fn decl(&self) -> PassDecl {
        PassDecl {
            name: self.name,
            ports: vec![
                Port::new(self.next, self.resource, Access::CopySource),
                Port::new(self.kept, self.resource, Access::CopyDestination),
            ],
        }
    }

    fn build(&self, _: &mut BuildContext, io: &mut Io) -> Result<Box<dyn Pass>, RenderError> {
        Ok(Box::new(Copy { name: self.name, from: io.texture(self.next)?, to: io.texture(self.kept)? }))
    }
}

/// A whole-texture copy.
#[derive(Debug)]
struct Copy {
    name: &'static str,
    from: wgpu::Texture,
    to: wgpu::Texture,
}

impl Pass for Copy {
    fn name(&self) -> &'static str {
        self.name
    }

    fn encode(&self, encoder: &mut wgpu::CommandEncoder) {
        encoder.copy_texture_to_texture(self.from.as_image_copy(), self.to.as_image_copy(), self.from.size());
    }
}
