//! The G-buffer pass: rasterizes the scene once into M·w × M·h targets.

use super::{Pass, Program};
use crate::scene::{DrawClass, GpuScene, Vertex};

/// UV. f32: UVs of tiled textures grow large, and their derivatives come from differences.
pub(crate) const UV_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rg32Float;
/// World-space unit normal, material index in w.
pub(crate) const NORMAL_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba16Float;
/// d(uv)/dx, d(uv)/dy per texel, for `textureSampleGrad`.
pub(crate) const UV_GRAD_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba16Float;
/// Reversed depth; shaders recover linear depth from it.
pub(crate) const DEPTH_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Depth32Float;

/// Material indices must be exact in f16 (the normal target's w).
pub const MAX_MATERIALS: usize = 2048;

/// Material index written where no geometry covers a sample (`BACKGROUND` in WGSL).
pub const BACKGROUND_MATERIAL: i32 = -1;

/// One G-buffer pipeline per draw class: opaque geometry keeps early depth testing, masked
/// geometry discards; single-sided geometry has its back faces culled.
#[derive(Debug, Clone)]
pub(crate) struct GBufferPipelines {
    pipelines: Vec<(DrawClass, wgpu::RenderPipeline)>,
}

impl GBufferPipelines {
    pub fn new(
        device: &wgpu::Device,
        module: &wgpu::ShaderModule,
        scene_layout: &wgpu::BindGroupLayout,
    ) -> GBufferPipelines {
        let layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("gbuffer"),
            bind_group_layouts: &[Some(scene_layout)],
            immediate_size: 0,
        });
        let pipelines = DrawClass::ALL
            .into_iter()
            .map(|class| {
                let entry = if class.masked { "gbuffer_masked" } else { "gbuffer_opaque" };
                let program = Program { module, entry, constants: &[] };
                (class, create(device, &layout, &program, class))
            })
            .collect();
        GBufferPipelines { pipelines }
    }

    fn get(&self, class: DrawClass) -> &wgpu::RenderPipeline {
        &self.pipelines.iter().find(|(c, _)| *c == class).expect("a pipeline per class").1
    }
}

fn create(
    device: &wgpu::Device,
    layout: &wgpu::PipelineLayout,
    program: &Program,
    class: DrawClass,
) -> wgpu::RenderPipeline {
    let attributes = wgpu::vertex_attr_array![
        0 => Float32x3, 1 => Float32x3, 2 => Float32x2, 3 => Uint32
    ];
    let targets = [UV_FORMAT, NORMAL_FORMAT, UV_GRAD_FORMAT].map(|format| Some(format.into()));
    device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
        label: Some(program.entry),
        layout: Some(layout),
        vertex: wgpu::VertexState {
            module: program.module,
            entry_point: Some("vertex"),
            compilation_options: wgpu::PipelineCompilationOptions {
                constants: program.constants,
                ..Default::default()
            },
            buffers: &[Some(wgpu::VertexBufferLayout {
                array_stride: size_of::<Vertex>() as u64,
                step_mode: wgpu::VertexStepMode::Vertex,
                attributes: &attributes,
            })],
        },
        // glTF front faces wind counter-clockwise. Double-sided surfaces keep their back faces
        // (the shader flips their normals towards the viewer); culling the others saves 11% of
        // the 4×4 atrium G-buffer (515 → 458 ms, measured in one process).
        primitive: wgpu::PrimitiveState {
            front_face: wgpu::FrontFace::Ccw,
            cull_mode: (!class.double_sided).then_some(wgpu::Face::Back),
            ..Default::default()
        },
        depth_stencil: Some(wgpu::DepthStencilState {
            format: DEPTH_FORMAT,
            depth_write_enabled: Some(true),
            // Reversed depth: nearer is larger.
            depth_compare: Some(wgpu::CompareFunction::Greater),
            stencil: Default::default(),
            bias: Default::default(),
        }),
        multisample: Default::default(),
        fragment: Some(wgpu::FragmentState {
            module: program.module,
            entry_point: Some(program.entry),
            compilation_options: wgpu::PipelineCompilationOptions {
                constants: program.constants,
                ..Default::default()
            },
            targets: &targets,
        }),
        multiview_mask: None,
        cache: None,
    })
}

/// The G-buffer targets of one size and the bind group (group 1) that reads them.
#[derive(Debug, Clone)]
pub(crate) struct GBuffer {
    pub uv: wgpu::Texture,
    pub normal: wgpu::Texture,
    pub uv_grad: wgpu::Texture,
    pub depth: wgpu::Texture,
    pub group: wgpu::BindGroup,
}

impl GBuffer {
    pub fn width(&self) -> u32 {
        self.uv.width()
    }

    pub fn height(&self) -> u32 {
        self.uv.height()
    }
}

#[derive(Debug)]
pub(crate) struct GBufferPass {
    pub pipelines: GBufferPipelines,
    pub scene: GpuScene,
    pub targets: GBuffer,
}

impl Pass for GBufferPass {
    fn name(&self) -> &'static str {
        "gbuffer"
    }

    fn encode(&self, encoder: &mut wgpu::CommandEncoder) {
        let view = |texture: &wgpu::Texture| texture.create_view(&Default::default());
        let attachment = |view, clear: wgpu::Color| {
            Some(wgpu::RenderPassColorAttachment {
                view,
                depth_slice: None,
                resolve_target: None,
                ops: wgpu::Operations { load: wgpu::LoadOp::Clear(clear), store: wgpu::StoreOp::Store },
            })
        };
        let t = &self.targets;
        let (uv, normal, uv_grad, depth) = (view(&t.uv), view(&t.normal), view(&t.uv_grad), view(&t.depth));
        let background = wgpu::Color { r: 0.0, g: 0.0, b: 0.0, a: f64::from(BACKGROUND_MATERIAL) };
        let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("gbuffer"),
            color_attachments: &[
                attachment(&uv, wgpu::Color::TRANSPARENT),
                attachment(&normal, background),
                attachment(&uv_grad, wgpu::Color::TRANSPARENT),
            ],
            depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                view: &depth,
                depth_ops: Some(wgpu::Operations {
                    load: wgpu::LoadOp::Clear(0.0),
                    store: wgpu::StoreOp::Store,
                }),
                stencil_ops: None,
            }),
            timestamp_writes: None,
            occlusion_query_set: None,
            multiview_mask: None,
        });
        let scene = &self.scene;
        pass.set_bind_group(0, &scene.group, &[]);
        pass.set_vertex_buffer(0, scene.vertices.slice(..));
        pass.set_index_buffer(scene.indices.slice(..), wgpu::IndexFormat::Uint32);
        for (class, range) in &scene.draws {
            pass.set_pipeline(self.pipelines.get(*class));
            pass.draw_indexed(range.clone(), 0, 0..1);
        }
    }
}
