//! The G-buffer pass: rasterizes the scene once into M·w × M·h targets, or into w × h targets
//! of 4 samples per pixel for MSAA.

use super::{BuildContext, Bundle, Io, Node, Pass, Program};
use crate::error::RenderError;
use crate::graph::{Access, Extent, PassDecl, Port, Resource};
use crate::pipelines::{Constants, Raster, RenderKey};
use crate::scene::{DrawClass, GpuScene, Vertex};

/// UV. f32: UVs of tiled textures grow large, and their derivatives come from differences.
pub(crate) const UV_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rg32Float;
/// World-space unit normal, material index in w.
pub(crate) const NORMAL_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba16Float;
/// d(uv)/dx, d(uv)/dy per texel, for `textureSampleGrad`.
pub(crate) const UV_GRAD_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba16Float;
/// Reversed depth; shaders recover linear depth from it.
pub(crate) const DEPTH_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Depth32Float;
/// Motion in pixels since the previous frame and the depth it had then (temporal modes). f16
/// holds a motion of up to 32 pixels to 1/64 pixel; a reprojection is asked to land within
/// 1/16.
pub(crate) const MOTION_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba16Float;

/// Material index written where no geometry covers a sample (`BACKGROUND` in WGSL).
pub const BACKGROUND_MATERIAL: i32 = -1;

/// The port names, which are also the names that `lib/gbuffer.wgsl` binds them under.
pub(crate) const UV: &str = "gb_uv";
pub(crate) const NORMAL: &str = "gb_normal";
pub(crate) const UV_GRAD: &str = "gb_uv_grad";
pub(crate) const DEPTH: &str = "gb_depth";
pub(crate) const MOTION: &str = "gb_motion";
pub(crate) const PORTS: [&str; 4] = [UV, NORMAL, UV_GRAD, DEPTH];

/// The same targets multisampled, under the names that `shaders/msaa.wgsl` binds them as.
pub(crate) const MS_NORMAL: &str = "ms_normal";
pub(crate) const MS_DEPTH: &str = "ms_depth";
pub(crate) const MULTISAMPLED_PORTS: [&str; 4] = ["ms_uv", MS_NORMAL, "ms_uv_grad", MS_DEPTH];

/// Samples per pixel of the multisampled G-buffer: lavapipe renders 1 or 4.
pub(crate) const MSAA_SAMPLES: u32 = 4;

/// The port names of a G-buffer of `samples` samples per texel.
pub(crate) fn ports(samples: u32) -> [&'static str; 4] {
    if samples == 1 { PORTS } else { MULTISAMPLED_PORTS }
}

/// What the G-buffer pass writes: at the G-buffer's extent, or multisampled at the output's.
pub(crate) fn outputs(samples: u32) -> [Port; 4] {
    let extent = if samples == 1 { Extent::GBuffer } else { Extent::Output };
    let formats = [UV_FORMAT, NORMAL_FORMAT, UV_GRAD_FORMAT, DEPTH_FORMAT];
    std::array::from_fn(|i| {
        let access = if i == 3 { Access::Depth } else { Access::Attachment };
        Port::new(ports(samples)[i], Resource::multisampled(formats[i], extent, samples), access)
    })
}

#[derive(Debug)]
pub(crate) struct GBufferNode {
    /// Samples per texel: 1, or [`MSAA_SAMPLES`] (hardware coverage at the standard sample
    /// positions; the fragment shader runs once per pixel and triangle, so every sample a
    /// triangle covers holds its attributes at the pixel's centre).
    pub samples: u32,
    /// Whether the pass also writes each sample's motion since the previous frame
    /// ([`MOTION`]): only the graphs that read it have it.
    pub motion: bool,
}

impl Node for GBufferNode {
    fn decl(&self) -> PassDecl {
        let mut ports = outputs(self.samples).to_vec();
        if self.motion {
            let motion = Resource::texture(MOTION_FORMAT, Extent::GBuffer);
            ports.push(Port::new(MOTION, motion, Access::Attachment));
        }
        PassDecl { name: "gbuffer", ports }
    }

    fn build(&self, ctx: &mut BuildContext, io: &mut Io) -> Result<Box<dyn Pass>, RenderError> {
        // Pipelines only for the draw classes the scene has: no alpha test without MASK
        // materials.
        let mut pipelines = Vec::new();
        for class in ctx.scene.draw_classes() {
            let fragment = match (class.masked, self.motion) {
                (false, false) => "gbuffer_opaque",
                // Under 4× MSAA the alpha test decides each sample's coverage.
                (true, false) if self.samples == MSAA_SAMPLES => "gbuffer_masked_samples",
                (true, false) => "gbuffer_masked",
                (false, true) => "gbuffer_opaque_motion",
                (true, true) => "gbuffer_masked_motion",
            };
            let program = Program {
                shader: "gbuffer.wgsl",
                vertex: "vertex",
                fragment: Some(fragment),
                constants: Constants::new(),
            };
            let inputs = VertexInputs { tangents: ctx.scene.has_tangents(), previous: ctx.scene.is_moving() };
            let motion = self.motion;
            let create = |device: &_, layout: &_, module: &_, key: &_| {
                create(device, layout, module, key, inputs, motion)
            };
            let raster = Raster::GBuffer { class, samples: self.samples };
            let bundle = ctx.render_pipeline(io, &program, raster, &[], create)?;
            pipelines.push((class, bundle));
        }
        Ok(Box::new(GBufferPass {
            pipelines,
            scene: ctx.scene.clone(),
            targets: ports(self.samples)[..3]
                .iter()
                .chain(self.motion.then_some(&MOTION))
                .map(|port| io.texture(port))
                .collect::<Result<_, _>>()?,
            depth: io.texture(ports(self.samples)[3])?,
        }))
    }
}

/// The vertex layout of [`Vertex`], shared by every pass that draws the scene.
pub(crate) const VERTEX_ATTRIBUTES: [wgpu::VertexAttribute; 4] = wgpu::vertex_attr_array![
    0 => Float32x3, 1 => Float32x3, 2 => Float32x2, 3 => Uint32
];

pub(crate) fn vertex_layout() -> wgpu::VertexBufferLayout<'static> {
    wgpu::VertexBufferLayout {
        array_stride: size_of::<Vertex>() as u64,
        step_mode: wgpu::VertexStepMode::Vertex,
        attributes: &VERTEX_ATTRIBUTES,
    }
}

/// The second vertex buffer of normal-mapped scenes: a tangent per vertex.
const TANGENT_LAYOUT: wgpu::VertexBufferLayout<'static> = wgpu::VertexBufferLayout {
    array_stride: 16,
    step_mode: wgpu::VertexStepMode::Vertex,
    attributes: &wgpu::vertex_attr_array![4 => Float32x4],
};

/// The last vertex buffer of scenes whose animation plays: each vertex's position in the frame
/// before.
const PREVIOUS_LAYOUT: wgpu::VertexBufferLayout<'static> = wgpu::VertexBufferLayout {
    array_stride: 12,
    step_mode: wgpu::VertexStepMode::Vertex,
    attributes: &wgpu::vertex_attr_array![5 => Float32x3],
};

/// The vertex buffers a scene pipeline reads beside the vertices (`GpuScene::draw` binds them
/// in this order).
#[derive(Debug, Clone, Copy, Default)]
pub(crate) struct VertexInputs {
    /// A tangent per vertex, for normal maps.
    pub tangents: bool,
    /// Each vertex's position in the frame before, for motion vectors of moving objects.
    pub previous: bool,
}

fn create(
    device: &wgpu::Device,
    layout: &wgpu::PipelineLayout,
    module: &wgpu::ShaderModule,
    key: &RenderKey,
    inputs: VertexInputs,
    motion: bool,
) -> wgpu::RenderPipeline {
    let Raster::GBuffer { class, samples } = key.raster else { unreachable!("a G-buffer key") };
    let formats = [UV_FORMAT, NORMAL_FORMAT, UV_GRAD_FORMAT, MOTION_FORMAT];
    let targets: Vec<_> = formats[..if motion { 4 } else { 3 }].iter().map(|&f| Some(f.into())).collect();
    // glTF front faces wind counter-clockwise. Double-sided surfaces keep their back faces
    // (the shader flips their normals towards the viewer); culling the others saves 11% of
    // the 4×4 atrium G-buffer (515 → 458 ms, measured in one process).
    let primitive = wgpu::PrimitiveState {
        front_face: wgpu::FrontFace::Ccw,
        cull_mode: (!class.double_sided).then_some(wgpu::Face::Back),
        ..Default::default()
    };
    let target = Target { depth: DEPTH_FORMAT, colors: &targets, samples };
    scene_pipeline(device, layout, module, key, primitive, target, inputs)
}

/// What a scene pipeline renders into: a depth target, colour targets when the key has a
/// fragment stage, and the samples per texel of all of them.
pub(crate) struct Target<'a> {
    pub depth: wgpu::TextureFormat,
    pub colors: &'a [Option<wgpu::ColorTargetState>],
    pub samples: u32,
}

/// A pipeline that draws the scene's vertices (with the `inputs` beside them) with reversed
/// depth into `target`: what the G-buffer and shadow passes share.
pub(crate) fn scene_pipeline(
    device: &wgpu::Device,
    layout: &wgpu::PipelineLayout,
    module: &wgpu::ShaderModule,
    key: &RenderKey,
    primitive: wgpu::PrimitiveState,
    target: Target,
    inputs: VertexInputs,
) -> wgpu::RenderPipeline {
    let buffers: Vec<_> = [Some(vertex_layout())]
        .into_iter()
        .chain(inputs.tangents.then_some(Some(TANGENT_LAYOUT)))
        .chain(inputs.previous.then_some(Some(PREVIOUS_LAYOUT)))
        .collect();
    device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
        label: key.fragment.or(Some(key.vertex)),
        layout: Some(layout),
        vertex: wgpu::VertexState {
            module,
            entry_point: Some(key.vertex),
            compilation_options: Default::default(),
            buffers: &buffers,
        },
        primitive,
        depth_stencil: Some(reversed_depth_test(target.depth)),
        multisample: wgpu::MultisampleState { count: target.samples, ..Default::default() },
        fragment: key.fragment.map(|entry| wgpu::FragmentState {
            module,
            entry_point: Some(entry),
            compilation_options: Default::default(),
            targets: target.colors,
        }),
        multiview_mask: None,
        cache: None,
    })
}

#[derive(Debug)]
struct GBufferPass {
    pipelines: Vec<(DrawClass, Bundle<wgpu::RenderPipeline>)>,
    scene: GpuScene,
    targets: Vec<wgpu::Texture>,
    depth: wgpu::Texture,
}

impl Pass for GBufferPass {
    fn name(&self) -> &'static str {
        "gbuffer"
    }

    fn encode(&self, encoder: &mut wgpu::CommandEncoder) {
        let views: Vec<wgpu::TextureView> =
            self.targets.iter().map(|t| t.create_view(&Default::default())).collect();
        let background = wgpu::Color { r: 0.0, g: 0.0, b: 0.0, a: f64::from(BACKGROUND_MATERIAL) };
        let clears =
            [wgpu::Color::TRANSPARENT, background, wgpu::Color::TRANSPARENT, wgpu::Color::TRANSPARENT];
        let attachments: Vec<_> = views
            .iter()
            .zip(clears)
            .map(|(view, clear)| {
                Some(wgpu::RenderPassColorAttachment {
                    view,
                    depth_slice: None,
                    resolve_target: None,
                    ops: wgpu::Operations { load: wgpu::LoadOp::Clear(clear), store: wgpu::StoreOp::Store },
                })
            })
            .collect();
        let depth = self.depth.create_view(&Default::default());
        let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("gbuffer"),
            color_attachments: &attachments,
            depth_stencil_attachment: Some(cleared_to_far(&depth)),
            timestamp_writes: None,
            occlusion_query_set: None,
            multiview_mask: None,
        });
        self.scene.draw(&mut pass, |class| lookup(&self.pipelines, class), 0..1);
    }
}

/// The pipeline and bind groups of a draw class.
pub(crate) fn lookup<K: PartialEq>(
    pipelines: &[(K, Bundle<wgpu::RenderPipeline>)],
    key: K,
) -> (&wgpu::RenderPipeline, &[(u32, wgpu::BindGroup)]) {
    let bundle =
        &pipelines.iter().find(|(k, _)| *k == key).expect("a pipeline for every class the scene draws").1;
    (&bundle.pipeline, &bundle.groups)
}

/// Depth testing and writing with reversed depth: nearer is larger.
pub(crate) fn reversed_depth_test(format: wgpu::TextureFormat) -> wgpu::DepthStencilState {
    wgpu::DepthStencilState {
        format,
        depth_write_enabled: Some(true),
        depth_compare: Some(wgpu::CompareFunction::Greater),
        stencil: Default::default(),
        bias: Default::default(),
    }
}

/// A depth attachment cleared to the far plane (0 in reversed depth) and kept.
pub(crate) fn cleared_to_far(view: &wgpu::TextureView) -> wgpu::RenderPassDepthStencilAttachment<'_> {
    wgpu::RenderPassDepthStencilAttachment {
        view,
        depth_ops: Some(wgpu::Operations { load: wgpu::LoadOp::Clear(0.0), store: wgpu::StoreOp::Store }),
        stencil_ops: None,
    }
}
