//! Passes: units of GPU work that are submitted and timed one at a time.
//!
//! Bind group conventions shared by all WGSL files: group 0 is the scene (frame uniform,
//! materials, lights, texture array, sampler), group 1 the G-buffer, group 2 the pass's own
//! inputs and outputs. A pipeline layout leaves out the groups its shader does not use.

pub(crate) mod adaptive;
pub(crate) mod gbuffer;

/// One measured unit of work.
pub(crate) trait Pass: Send + Sync {
    fn name(&self) -> &'static str;
    fn encode(&self, encoder: &mut wgpu::CommandEncoder);
}

/// What a binding slot holds. Slots are numbered in the order given, from 0.
#[derive(Debug, Clone, Copy)]
pub(crate) enum Slot {
    Uniform,
    StorageRead,
    StorageReadWrite,
    /// A 2D float texture read with `textureLoad` (no filtering, any float format).
    Texture,
    /// A 2D unsigned-integer texture.
    UintTexture,
    /// A filterable 2D array texture.
    TextureArray,
    /// A 2D depth texture read with `textureLoad`.
    Depth,
    Sampler,
}

pub(crate) fn bind_group_layout(device: &wgpu::Device, label: &str, slots: &[Slot]) -> wgpu::BindGroupLayout {
    let entries: Vec<_> = slots
        .iter()
        .enumerate()
        .map(|(binding, slot)| {
            let texture = |sample_type, view_dimension| wgpu::BindingType::Texture {
                sample_type,
                view_dimension,
                multisampled: false,
            };
            let storage = |read_only| wgpu::BindingType::Buffer {
                ty: wgpu::BufferBindingType::Storage { read_only },
                has_dynamic_offset: false,
                min_binding_size: None,
            };
            let ty = match slot {
                Slot::Uniform => wgpu::BindingType::Buffer {
                    ty: wgpu::BufferBindingType::Uniform,
                    has_dynamic_offset: false,
                    min_binding_size: None,
                },
                Slot::StorageRead => storage(true),
                Slot::StorageReadWrite => storage(false),
                Slot::Texture => texture(
                    wgpu::TextureSampleType::Float { filterable: false },
                    wgpu::TextureViewDimension::D2,
                ),
                Slot::UintTexture => texture(wgpu::TextureSampleType::Uint, wgpu::TextureViewDimension::D2),
                Slot::TextureArray => texture(
                    wgpu::TextureSampleType::Float { filterable: true },
                    wgpu::TextureViewDimension::D2Array,
                ),
                Slot::Depth => texture(wgpu::TextureSampleType::Depth, wgpu::TextureViewDimension::D2),
                Slot::Sampler => wgpu::BindingType::Sampler(wgpu::SamplerBindingType::Filtering),
            };
            // Vertex shaders may not write storage buffers.
            let visibility = match slot {
                Slot::StorageReadWrite => wgpu::ShaderStages::FRAGMENT | wgpu::ShaderStages::COMPUTE,
                _ => wgpu::ShaderStages::VERTEX_FRAGMENT | wgpu::ShaderStages::COMPUTE,
            };
            wgpu::BindGroupLayoutEntry { binding: binding as u32, visibility, ty, count: None }
        })
        .collect();
    device
        .create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor { label: Some(label), entries: &entries })
}

/// A bind group whose resources are bound to slots 0, 1, 2, … in order.
pub(crate) fn bind_group(
    device: &wgpu::Device,
    label: &str,
    layout: &wgpu::BindGroupLayout,
    resources: &[wgpu::BindingResource],
) -> wgpu::BindGroup {
    let entries: Vec<_> = resources
        .iter()
        .enumerate()
        .map(|(binding, resource)| wgpu::BindGroupEntry {
            binding: binding as u32,
            resource: resource.clone(),
        })
        .collect();
    device.create_bind_group(&wgpu::BindGroupDescriptor { label: Some(label), layout, entries: &entries })
}

/// Which shader entry point, with which override constants, makes a pipeline.
#[derive(Debug, Clone)]
pub(crate) struct Program<'a> {
    pub module: &'a wgpu::ShaderModule,
    pub entry: &'a str,
    pub constants: &'a [(&'a str, f64)],
}

fn pipeline_layout(
    device: &wgpu::Device,
    label: &str,
    groups: &[Option<&wgpu::BindGroupLayout>],
) -> wgpu::PipelineLayout {
    device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
        label: Some(label),
        bind_group_layouts: groups,
        immediate_size: 0,
    })
}

/// A pipeline that runs `program` on the pixels that the vertex entry point `vertex` (no
/// vertex buffers) covers in a `format` target.
pub(crate) fn screen_pipeline(
    device: &wgpu::Device,
    label: &str,
    vertex: &str,
    program: &Program,
    groups: &[Option<&wgpu::BindGroupLayout>],
    format: wgpu::TextureFormat,
) -> wgpu::RenderPipeline {
    let layout = pipeline_layout(device, label, groups);
    device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
        label: Some(label),
        layout: Some(&layout),
        vertex: wgpu::VertexState {
            module: program.module,
            entry_point: Some(vertex),
            // Both stages see the same override constants.
            compilation_options: wgpu::PipelineCompilationOptions {
                constants: program.constants,
                ..Default::default()
            },
            buffers: &[],
        },
        primitive: wgpu::PrimitiveState::default(),
        depth_stencil: None,
        multisample: wgpu::MultisampleState::default(),
        fragment: Some(wgpu::FragmentState {
            module: program.module,
            entry_point: Some(program.entry),
            compilation_options: wgpu::PipelineCompilationOptions {
                constants: program.constants,
                ..Default::default()
            },
            targets: &[Some(format.into())],
        }),
        multiview_mask: None,
        cache: None,
    })
}

pub(crate) fn compute_pipeline(
    device: &wgpu::Device,
    label: &str,
    program: &Program,
    groups: &[Option<&wgpu::BindGroupLayout>],
) -> wgpu::ComputePipeline {
    let layout = pipeline_layout(device, label, groups);
    device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
        label: Some(label),
        layout: Some(&layout),
        module: program.module,
        entry_point: Some(program.entry),
        compilation_options: wgpu::PipelineCompilationOptions {
            constants: program.constants,
            ..Default::default()
        },
        cache: None,
    })
}

fn set_groups<P: SetBindGroup>(pass: &mut P, groups: &[(u32, wgpu::BindGroup)]) {
    for (index, group) in groups {
        pass.set(*index, group);
    }
}

/// The one method render and compute passes share, so [`set_groups`] serves both.
trait SetBindGroup {
    fn set(&mut self, index: u32, group: &wgpu::BindGroup);
}

impl SetBindGroup for wgpu::RenderPass<'_> {
    fn set(&mut self, index: u32, group: &wgpu::BindGroup) {
        self.set_bind_group(index, group, &[]);
    }
}

impl SetBindGroup for wgpu::ComputePass<'_> {
    fn set(&mut self, index: u32, group: &wgpu::BindGroup) {
        self.set_bind_group(index, group, &[]);
    }
}

/// A fragment shader run on `target` over the triangles of `vertices` vertices that the
/// pipeline's vertex shader makes: 3 for the fullscreen triangle. Whatever it covers it
/// overwrites, and the rest is never read.
#[derive(Debug)]
pub(crate) struct Screen {
    pub name: &'static str,
    pub pipeline: wgpu::RenderPipeline,
    pub groups: Vec<(u32, wgpu::BindGroup)>,
    pub target: wgpu::TextureView,
    pub vertices: u32,
}

impl Pass for Screen {
    fn name(&self) -> &'static str {
        self.name
    }

    fn encode(&self, encoder: &mut wgpu::CommandEncoder) {
        let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some(self.name),
            color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                view: &self.target,
                depth_slice: None,
                resolve_target: None,
                // Old contents are never read: `Load` costs nothing on lavapipe where `Clear`
                // would fill the whole target first.
                ops: wgpu::Operations { load: wgpu::LoadOp::Load, store: wgpu::StoreOp::Store },
            })],
            depth_stencil_attachment: None,
            timestamp_writes: None,
            occlusion_query_set: None,
            multiview_mask: None,
        });
        pass.set_pipeline(&self.pipeline);
        set_groups(&mut pass, &self.groups);
        pass.draw(0..self.vertices, 0..1);
    }
}

/// A compute dispatch, or several in sequence sharing one submit.
#[derive(Debug)]
pub(crate) struct Compute {
    pub name: &'static str,
    pub steps: Vec<ComputeStep>,
}

#[derive(Debug)]
pub(crate) struct ComputeStep {
    pub pipeline: wgpu::ComputePipeline,
    pub groups: Vec<(u32, wgpu::BindGroup)>,
    pub workgroups: [u32; 3],
}

impl Pass for Compute {
    fn name(&self) -> &'static str {
        self.name
    }

    fn encode(&self, encoder: &mut wgpu::CommandEncoder) {
        for step in &self.steps {
            let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
                label: Some(self.name),
                timestamp_writes: None,
            });
            pass.set_pipeline(&step.pipeline);
            set_groups(&mut pass, &step.groups);
            let [x, y, z] = step.workgroups;
            pass.dispatch_workgroups(x, y, z);
        }
    }
}
