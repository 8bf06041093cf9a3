//! Shader modules, bind group layouts and pipelines of one scene, each created once and cached
//! under a typed key.

use std::collections::HashMap;
use std::path::PathBuf;
use std::sync::Arc;

use crate::bindings::Shader;
use crate::error::RenderError;
use crate::scene::DrawClass;
use crate::shaders::{self, Features};

/// Pipeline override constants, by name, in the order given. Values are kept as f64 bits so
/// that keys hash and compare exactly.
#[derive(Debug, Clone, Default, PartialEq, Eq, Hash)]
pub(crate) struct Constants(Vec<(&'static str, u64)>);

impl Constants {
    pub fn new() -> Constants {
        Constants::default()
    }

    pub fn with(mut self, name: &'static str, value: impl Into<f64>) -> Constants {
        self.0.push((name, value.into().to_bits()));
        self
    }

    pub fn flag(self, name: &'static str, value: bool) -> Constants {
        self.with(name, if value { 1.0 } else { 0.0 })
    }

    pub fn extend(mut self, other: &Constants) -> Constants {
        self.0.extend_from_slice(&other.0);
        self
    }

    pub fn pairs(&self) -> Vec<(&'static str, f64)> {
        self.0.iter().map(|&(name, bits)| (name, f64::from_bits(bits))).collect()
    }
}

/// How a render pipeline rasterizes, beyond its shaders: the part of its key that passes add.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub(crate) enum Raster {
    /// No vertex buffers, colour targets of these formats.
    Screen(ScreenTargets),
    /// The scene's vertices into the G-buffer of `samples` per texel, culled as the draw class
    /// says.
    GBuffer { class: DrawClass, samples: u32 },
    /// The scene's vertices into a depth-only target, both faces.
    ShadowDepth,
}

/// A pipeline layout as data: the layout entries of each bind group, by group index.
pub(crate) type LayoutEntries = Vec<Vec<wgpu::BindGroupLayoutEntry>>;

#[derive(Debug, Clone, PartialEq, Eq, Hash)]
pub(crate) struct RenderKey {
    pub shader: &'static str,
    pub vertex: &'static str,
    pub fragment: Option<&'static str>,
    pub constants: Constants,
    pub raster: Raster,
    pub layout: LayoutEntries,
}

#[derive(Debug, Clone, PartialEq, Eq, Hash)]
pub(crate) struct ComputeKey {
    pub shader: &'static str,
    pub entry: &'static str,
    pub constants: Constants,
    pub layout: LayoutEntries,
}

/// Everything compiled on one device. A scene's [`Features`] decide how each shader is
/// composed; modules and pipelines are kept by the text they were compiled from, so a scene
/// reuses whatever an earlier scene compiled from the same text (`render::lend_pipelines`).
#[derive(Debug)]
pub(crate) struct Pipelines {
    device: wgpu::Device,
    /// Uploads the constant textures that passes own.
    queue: wgpu::Queue,
    features: Features,
    /// Where shader files are read from; `None`: `shaders::compose`'s default.
    shader_dir: Option<PathBuf>,
    /// The modules of the current features, by file: a lookup without composing.
    shaders: HashMap<&'static str, Arc<Shader>>,
    /// Every module compiled, by its composed text.
    modules: HashMap<String, Arc<Shader>>,
    group_layouts: HashMap<Vec<wgpu::BindGroupLayoutEntry>, wgpu::BindGroupLayout>,
    render: HashMap<(ModuleId, RenderKey), wgpu::RenderPipeline>,
    compute: HashMap<(ModuleId, ComputeKey), wgpu::ComputePipeline>,
    constant_buffers: HashMap<(&'static str, u32), wgpu::Buffer>,
    texel_sampler: Option<wgpu::Sampler>,
    constant_textures: HashMap<&'static str, wgpu::Texture>,
}

/// A module's identity: the address of its [`Shader`], which the cache keeps for as long as it
/// keeps pipelines made from it.
type ModuleId = usize;

fn module_id(shader: &Arc<Shader>) -> ModuleId {
    Arc::as_ptr(shader) as ModuleId
}

impl Pipelines {
    pub fn new(device: wgpu::Device, queue: wgpu::Queue, features: Features) -> Pipelines {
        Pipelines {
            device,
            queue,
            features,
            shader_dir: None,
            shaders: HashMap::new(),
            modules: HashMap::new(),
            group_layouts: HashMap::new(),
            render: HashMap::new(),
            compute: HashMap::new(),
            constant_buffers: HashMap::new(),
            texel_sampler: None,
            constant_textures: HashMap::new(),
        }
    }

    /// Reads shader files from `dir` from now on, dropping what was compiled from the others.
    pub fn read_shaders_from(&mut self, dir: PathBuf) {
        self.shader_dir = Some(dir);
        self.shaders.clear();
        self.modules.clear();
        self.render.clear();
        self.compute.clear();
    }

    pub fn device(&self) -> &wgpu::Device {
        &self.device
    }

    /// Render and compute pipelines compiled so far, for every scene that held these.
    pub fn compiled(&self) -> usize {
        self.render.len() + self.compute.len()
    }

    /// Composes shaders for `features` from now on (another scene's).
    pub fn set_features(&mut self, features: Features) {
        if features != self.features {
            self.features = features;
            self.shaders.clear();
        }
    }

    /// Whether the shaders are the embedded ones (no [`Pipelines::read_shaders_from`]).
    pub fn reads_embedded_shaders(&self) -> bool {
        self.shader_dir.is_none()
    }

    pub fn shader(&mut self, file: &'static str) -> Result<Arc<Shader>, RenderError> {
        if let Some(shader) = self.shaders.get(file) {
            return Ok(Arc::clone(shader));
        }
        let text = shaders::compose_from(self.shader_dir.as_deref(), file, self.features)?;
        let shader = match self.modules.get(&text) {
            Some(shader) => Arc::clone(shader),
            None => {
                let shader = Arc::new(Shader::new(&self.device, self.shader_dir.as_deref(), file, &text)?);
                self.modules.insert(text, Arc::clone(&shader));
                shader
            }
        };
        self.shaders.insert(file, Arc::clone(&shader));
        Ok(shader)
    }

    pub fn group_layout(&mut self, entries: &[wgpu::BindGroupLayoutEntry]) -> wgpu::BindGroupLayout {
        let device = &self.device;
        self.group_layouts
            .entry(entries.to_vec())
            .or_insert_with(|| {
                device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor { label: None, entries })
            })
            .clone()
    }

    /// A pipeline layout whose group i has `groups[i]`'s entries; empty groups are left out.
    fn pipeline_layout(
        &mut self,
        label: &str,
        groups: &[Vec<wgpu::BindGroupLayoutEntry>],
    ) -> wgpu::PipelineLayout {
        let layouts: Vec<Option<wgpu::BindGroupLayout>> =
            groups.iter().map(|entries| (!entries.is_empty()).then(|| self.group_layout(entries))).collect();
        let refs: Vec<Option<&wgpu::BindGroupLayout>> = layouts.iter().map(Option::as_ref).collect();
        self.device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some(label),
            bind_group_layouts: &refs,
            immediate_size: 0,
        })
    }

    /// The render pipeline of `key`, made by `create` from the layout and module on first use.
    /// `create` must build what the key describes: the key is what the cache trusts.
    pub fn render(
        &mut self,
        key: RenderKey,
        create: impl FnOnce(&wgpu::Device, &wgpu::PipelineLayout, &wgpu::ShaderModule) -> wgpu::RenderPipeline,
    ) -> Result<wgpu::RenderPipeline, RenderError> {
        let shader = self.shader(key.shader)?;
        let key = (module_id(&shader), key);
        if let Some(pipeline) = self.render.get(&key) {
            return Ok(pipeline.clone());
        }
        let layout = self.pipeline_layout(key.1.fragment.unwrap_or(key.1.vertex), &key.1.layout);
        let pipeline = create(&self.device, &layout, &shader.module);
        self.render.insert(key, pipeline.clone());
        Ok(pipeline)
    }

    pub fn compute(&mut self, key: ComputeKey) -> Result<wgpu::ComputePipeline, RenderError> {
        let shader = self.shader(key.shader)?;
        let key = (module_id(&shader), key);
        if let Some(pipeline) = self.compute.get(&key) {
            return Ok(pipeline.clone());
        }
        let compute = &key.1;
        let layout = self.pipeline_layout(compute.entry, &compute.layout);
        let constants = compute.constants.pairs();
        let pipeline = self.device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
            label: Some(compute.entry),
            layout: Some(&layout),
            module: &shader.module,
            entry_point: Some(compute.entry),
            compilation_options: wgpu::PipelineCompilationOptions {
                constants: &constants,
                ..Default::default()
            },
            cache: None,
        });
        self.compute.insert(key, pipeline.clone());
        Ok(pipeline)
    }

    /// A sampler that neither filters nor wraps, for `textureGather`: four texels in one call.
    pub fn texel_sampler(&mut self) -> wgpu::Sampler {
        let device = &self.device;
        self.texel_sampler
            .get_or_insert_with(|| {
                device.create_sampler(&wgpu::SamplerDescriptor {
                    label: Some("texel sampler"),
                    ..Default::default()
                })
            })
            .clone()
    }

    /// A storage buffer of constant data that passes own, created on first use from
    /// `contents` and kept under `key` (a name and a number, e.g. the adaptive window's side).
    pub fn constant_buffer(
        &mut self,
        key: (&'static str, u32),
        contents: impl FnOnce() -> Vec<u8>,
    ) -> wgpu::Buffer {
        use wgpu::util::DeviceExt;
        let device = &self.device;
        self.constant_buffers
            .entry(key)
            .or_insert_with(|| {
                device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                    label: Some(key.0),
                    contents: &contents(),
                    usage: wgpu::BufferUsages::STORAGE,
                })
            })
            .clone()
    }

    /// A constant texture that passes own (SMAA's lookup textures), uploaded on first use and
    /// kept under its name.
    pub fn constant_texture(&mut self, constant: &ConstantTexture) -> wgpu::Texture {
        use wgpu::util::DeviceExt;
        let (device, queue) = (&self.device, &self.queue);
        self.constant_textures
            .entry(constant.name)
            .or_insert_with(|| {
                device.create_texture_with_data(
                    queue,
                    &wgpu::TextureDescriptor {
                        label: Some(constant.name),
                        size: wgpu::Extent3d {
                            width: constant.width,
                            height: constant.height,
                            depth_or_array_layers: 1,
                        },
                        mip_level_count: 1,
                        sample_count: 1,
                        dimension: wgpu::TextureDimension::D2,
                        format: constant.format,
                        usage: wgpu::TextureUsages::TEXTURE_BINDING,
                        view_formats: &[],
                    },
                    wgpu::util::TextureDataOrder::LayerMajor,
                    constant.bytes,
                )
            })
            .clone()
    }
}

/// A precomputed texture that a pass reads (`Pipelines::constant_texture`): rows from the top,
/// no padding.
#[derive(Debug, Clone, Copy)]
pub struct ConstantTexture {
    pub name: &'static str,
    pub width: u32,
    pub height: u32,
    pub format: wgpu::TextureFormat,
    pub bytes: &'static [u8],
}

/// The most colour targets a screen pass writes: a colour and its slope in albedo
/// (`shade_group`), a count and its pixel's surfaces (`evaluate_coverage`).
pub(crate) const MAX_SCREEN_TARGETS: usize = 2;

/// The formats of a screen pass's colour targets, in location order.
pub(crate) type ScreenTargets = [Option<wgpu::TextureFormat>; MAX_SCREEN_TARGETS];

/// A pipeline that runs a fragment entry point over the triangles that a vertex entry point
/// (no vertex buffers) makes, into targets of `formats`.
pub(crate) fn screen_pipeline(
    device: &wgpu::Device,
    layout: &wgpu::PipelineLayout,
    module: &wgpu::ShaderModule,
    key: &RenderKey,
    formats: ScreenTargets,
) -> wgpu::RenderPipeline {
    let constants = key.constants.pairs();
    // Both stages see the same override constants.
    let options = wgpu::PipelineCompilationOptions { constants: &constants, ..Default::default() };
    device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
        label: key.fragment,
        layout: Some(layout),
        vertex: wgpu::VertexState {
            module,
            entry_point: Some(key.vertex),
            compilation_options: options.clone(),
            buffers: &[],
        },
        primitive: wgpu::PrimitiveState::default(),
        depth_stencil: None,
        multisample: wgpu::MultisampleState::default(),
        fragment: Some(wgpu::FragmentState {
            module,
            entry_point: key.fragment,
            compilation_options: options,
            targets: &formats.into_iter().flatten().map(|f| Some(f.into())).collect::<Vec<_>>(),
        }),
        multiview_mask: None,
        cache: None,
    })
}
