//! The shadow pass: every shadow-casting light's depth cube, six render passes per light in one
//! submit (wgpu has no geometry shaders here). It draws the scene through the same vertex
//! buffers, draw classes and alpha test as the G-buffer pass (`lib/geometry.wgsl`); only the
//! projection (one matrix per face, picked by the instance index) and the targets differ.

use super::gbuffer::{cleared_to_far, lookup, scene_pipeline};
use super::{BuildContext, Bundle, Io, Node, Pass, Program};
use crate::error::RenderError;
use crate::graph::{Access, Extent, PassDecl, Port, Resource};
use crate::pipelines::{Constants, Raster, RenderKey};
use crate::scene::GpuScene;

/// The port name, and the name `lib/shadows.wgsl` binds the cube array under.
pub(crate) const CUBES: &str = "shadow_cubes";

pub(crate) const FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Depth32Float;

/// The cube array of `lights` cubes with `resolution`² faces.
pub(crate) fn cubes(lights: u32, resolution: u32) -> Resource {
    Resource::Texture {
        format: FORMAT,
        extent: Extent::Fixed { width: resolution, height: resolution },
        layers: 6 * lights,
        samples: 1,
    }
}

#[derive(Debug)]
pub(crate) struct ShadowNode {
    pub cubes: Resource,
}

impl Node for ShadowNode {
    fn decl(&self) -> PassDecl {
        PassDecl { name: "shadow", ports: vec![Port::new(CUBES, self.cubes, Access::Depth)] }
    }

    fn build(&self, ctx: &mut BuildContext, io: &mut Io) -> Result<Box<dyn Pass>, RenderError> {
        // Masked geometry casts shadows where its alpha test passes; opaque geometry needs no
        // fragment shader at all.
        let mut pipelines = Vec::new();
        for masked in [false, true] {
            if !ctx.scene.draw_classes().any(|c| c.masked == masked) {
                continue;
            }
            let fragment = masked.then_some("shadow_masked");
            let program = Program {
                shader: "shadow.wgsl",
                vertex: "shadow_vertex",
                fragment,
                constants: Constants::new(),
            };
            pipelines.push((masked, ctx.render_pipeline(io, &program, Raster::ShadowDepth, &[], create)?));
        }
        Ok(Box::new(ShadowPass { pipelines, scene: ctx.scene.clone(), cubes: io.texture(CUBES)? }))
    }
}

fn create(
    device: &wgpu::Device,
    layout: &wgpu::PipelineLayout,
    module: &wgpu::ShaderModule,
    key: &RenderKey,
) -> wgpu::RenderPipeline {
    // Faces of a cube map mirror one axis, so winding flips between faces: draw both sides.
    // Depth needs no tangents.
    let target = super::gbuffer::Target { depth: FORMAT, colors: &[], samples: 1 };
    scene_pipeline(device, layout, module, key, wgpu::PrimitiveState::default(), target, Default::default())
}

#[derive(Debug)]
struct ShadowPass {
    pipelines: Vec<(bool, Bundle<wgpu::RenderPipeline>)>,
    scene: GpuScene,
    cubes: wgpu::Texture,
}

impl Pass for ShadowPass {
    fn name(&self) -> &'static str {
        "shadow"
    }

    fn encode(&self, encoder: &mut wgpu::CommandEncoder) {
        for layer in 0..self.cubes.depth_or_array_layers() {
            let view = self.cubes.create_view(&wgpu::TextureViewDescriptor {
                dimension: Some(wgpu::TextureViewDimension::D2),
                base_array_layer: layer,
                array_layer_count: Some(1),
                ..Default::default()
            });
            let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some("shadow"),
                color_attachments: &[],
                // Reversed depth: the far plane is the light's range.
                depth_stencil_attachment: Some(cleared_to_far(&view)),
                timestamp_writes: None,
                occlusion_query_set: None,
                multiview_mask: None,
            });
            // The instance index picks the face's matrix (layer = 6 · light + face).
            self.scene.draw(&mut pass, |class| lookup(&self.pipelines, class.masked), layer..layer + 1);
        }
    }
}
