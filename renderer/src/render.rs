//! Building a mode's passes for one scene, running timed frames and reading back their images.

use std::collections::HashMap;
use std::sync::Arc;

use crate::gpu::Gpu;
use crate::mode::{Mode, Technique};
use crate::passes::gbuffer::{self, GBuffer, GBufferPass, GBufferPipelines};
use crate::passes::{self, Pass, Program, Screen, Slot};
use crate::scene::{Camera, FrameUniforms, GpuScene, Lighting, Scene};
use crate::{AdaptiveSettings, RenderError, shaders};

/// Linear HDR radiance.
pub(crate) const HDR_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba16Float;
/// Display-encoded 8-bit colour.
pub(crate) const DISPLAY_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba8Unorm;

/// What a scene is rendered with, besides its geometry and lights.
#[derive(Debug, Clone, PartialEq)]
pub struct RenderSettings {
    /// Output resolution; the G-buffer of an M×M mode is M·width × M·height.
    pub width: u32,
    pub height: u32,
    /// Dependent ALU iterations per shaded sample in `-stalled` modes.
    pub stall_iterations: u32,
    pub adaptive: AdaptiveSettings,
}

/// Wall-clock time of one pass of one frame.
#[derive(Debug, Clone, PartialEq)]
pub struct PassTime {
    pub name: &'static str,
    pub seconds: f64,
}

/// The passes of one frame, in submission order.
#[derive(Debug, Clone, PartialEq)]
pub struct FrameTiming {
    pub passes: Vec<PassTime>,
}

impl FrameTiming {
    /// The frame's time: the sum of its passes, each measured from submit to completion.
    pub fn seconds(&self) -> f64 {
        self.passes.iter().map(|p| p.seconds).sum()
    }
}

/// The images of a frame, read back after it was timed.
#[derive(Debug, Clone, PartialEq)]
pub struct FrameImages {
    pub width: u32,
    pub height: u32,
    /// Display-encoded RGBA8, row-major from the top.
    pub display: Vec<u8>,
    /// Linear HDR RGBA as f32 (stored on the GPU as f16). Alpha carries the stall result.
    pub hdr: Vec<f32>,
    /// Samples shaded per pixel (1…M²), for adaptive modes.
    pub sample_counts: Option<Vec<u8>>,
}

/// A G-buffer read back for checks: what the adaptive metric sees.
#[derive(Debug, Clone, PartialEq)]
pub struct GBufferImages {
    pub width: u32,
    pub height: u32,
    /// World-space normal and material index ([`crate::BACKGROUND_MATERIAL`]: no geometry),
    /// per sample.
    pub normal_material: Vec<[f32; 4]>,
    /// Linear view depth per sample, recovered from the depth buffer in f64.
    pub depth: Vec<f64>,
}

/// One scene on the device, with the targets and pipelines that its modes share. Modes run one
/// at a time, so modes of the same M share one G-buffer.
#[derive(Debug)]
pub struct SceneRenderer {
    pub(crate) gpu: Arc<Gpu>,
    pub(crate) scene: GpuScene,
    pub(crate) settings: RenderSettings,
    modules: HashMap<&'static str, wgpu::ShaderModule>,
    pub(crate) gbuffer_layout: wgpu::BindGroupLayout,
    pub(crate) texture_layout: wgpu::BindGroupLayout,
    gbuffer_pipelines: Option<GBufferPipelines>,
    pipelines: HashMap<String, wgpu::RenderPipeline>,
    compute_pipelines: HashMap<String, wgpu::ComputePipeline>,
    targets: HashMap<(&'static str, u32, u32), wgpu::Texture>,
    buffers: HashMap<(&'static str, u64), wgpu::Buffer>,
    gbuffers: HashMap<u32, GBuffer>,
    /// The camera's near and far planes, for reading depth back.
    clip: (f64, f64),
}

impl SceneRenderer {
    pub fn new(
        gpu: Arc<Gpu>,
        scene: &Scene,
        camera: &Camera,
        lighting: &Lighting,
        settings: RenderSettings,
    ) -> Result<SceneRenderer, RenderError> {
        let frame = FrameUniforms::new(camera, lighting, settings.width, settings.height);
        let scene = GpuScene::new(&gpu.device, &gpu.queue, scene, lighting, &frame);
        let device = &gpu.device;
        let gbuffer_layout = passes::bind_group_layout(
            device,
            "gbuffer",
            &[Slot::Texture, Slot::Texture, Slot::Texture, Slot::Depth],
        );
        let texture_layout = passes::bind_group_layout(device, "input", &[Slot::Texture]);
        gpu.check()?;
        Ok(SceneRenderer {
            gpu,
            scene,
            settings,
            modules: HashMap::new(),
            gbuffer_layout,
            texture_layout,
            gbuffer_pipelines: None,
            pipelines: HashMap::new(),
            compute_pipelines: HashMap::new(),
            targets: HashMap::new(),
            buffers: HashMap::new(),
            gbuffers: HashMap::new(),
            clip: (camera.near, camera.far),
        })
    }

    /// Bytes of the scene's texture array on the device.
    pub fn texture_bytes(&self) -> u64 {
        self.scene.texture_bytes
    }

    /// Builds the passes of `mode`. Pipelines and targets are created on first use and shared.
    pub fn prepare(&mut self, mode: Mode) -> Result<PreparedMode, RenderError> {
        let (width, height) = (self.settings.width, self.settings.height);
        let gbuffer = self.gbuffer(mode.m)?;
        let mut passes: Vec<Box<dyn Pass>> = vec![Box::new(GBufferPass {
            pipelines: self.gbuffer_pipelines()?,
            scene: self.scene.clone(),
            targets: gbuffer.clone(),
        })];
        let hdr = self.target("hdr", width, height, HDR_FORMAT);
        let mut sample_counts = None;
        let mut first = None;
        match mode.technique {
            Technique::Deferred => passes.push(Box::new(self.shade_all(&gbuffer, mode.stalled, &hdr)?)),
            Technique::Reference => {
                let supersampled = self.target("supersampled", gbuffer.width(), gbuffer.height(), HDR_FORMAT);
                passes.push(Box::new(self.shade_all(&gbuffer, mode.stalled, &supersampled)?));
                passes.push(Box::new(self.resolve(mode.m, &supersampled, &hdr)?));
            }
            Technique::Adaptive(metrics) => {
                let adaptive = crate::passes::adaptive::build(self, &gbuffer, mode, metrics, &hdr)?;
                sample_counts = Some(adaptive.sample_counts);
                first = Some(adaptive.first);
                passes.extend(adaptive.passes);
            }
        }
        let display = self.target("display", width, height, DISPLAY_FORMAT);
        passes.push(Box::new(self.display(&hdr, &display)?));
        self.gpu.check()?;
        Ok(PreparedMode {
            gpu: Arc::clone(&self.gpu),
            mode,
            passes,
            hdr,
            display,
            sample_counts,
            gbuffer,
            first,
            clip: self.clip,
        })
    }

    pub(crate) fn module(&mut self, file: &'static str) -> Result<wgpu::ShaderModule, RenderError> {
        if let Some(module) = self.modules.get(file) {
            return Ok(module.clone());
        }
        let module = shaders::module(&self.gpu.device, file)?;
        self.modules.insert(file, module.clone());
        Ok(module)
    }

    /// A render target shared by every mode that asks for the same name and size.
    pub(crate) fn target(
        &mut self,
        name: &'static str,
        width: u32,
        height: u32,
        format: wgpu::TextureFormat,
    ) -> wgpu::Texture {
        let device = &self.gpu.device;
        self.targets
            .entry((name, width, height))
            .or_insert_with(|| {
                device.create_texture(&wgpu::TextureDescriptor {
                    label: Some(name),
                    size: wgpu::Extent3d { width, height, depth_or_array_layers: 1 },
                    mip_level_count: 1,
                    sample_count: 1,
                    dimension: wgpu::TextureDimension::D2,
                    format,
                    usage: wgpu::TextureUsages::RENDER_ATTACHMENT
                        | wgpu::TextureUsages::TEXTURE_BINDING
                        | wgpu::TextureUsages::COPY_SRC,
                    view_formats: &[],
                })
            })
            .clone()
    }

    /// Bytes of all render targets allocated so far.
    pub fn target_bytes(&self) -> u64 {
        self.targets
            .values()
            .map(|t| {
                let texel = t.format().block_copy_size(Some(wgpu::TextureAspect::All)).unwrap_or(4);
                u64::from(t.width()) * u64::from(t.height()) * u64::from(texel)
            })
            .sum()
    }

    fn gbuffer(&mut self, m: u32) -> Result<GBuffer, RenderError> {
        if let Some(gbuffer) = self.gbuffers.get(&m) {
            return Ok(gbuffer.clone());
        }
        let (width, height) = (m * self.settings.width, m * self.settings.height);
        let limit = self.gpu.device.limits().max_texture_dimension_2d;
        if width > limit || height > limit {
            return Err(RenderError::TooLarge { width, height, limit });
        }
        let uv = self.target("gbuffer.uv", width, height, gbuffer::UV_FORMAT);
        let normal = self.target("gbuffer.normal", width, height, gbuffer::NORMAL_FORMAT);
        let uv_grad = self.target("gbuffer.uv_grad", width, height, gbuffer::UV_GRAD_FORMAT);
        let depth = self.target("gbuffer.depth", width, height, gbuffer::DEPTH_FORMAT);
        let views = [&uv, &normal, &uv_grad, &depth].map(view);
        let group = passes::bind_group(
            &self.gpu.device,
            "gbuffer",
            &self.gbuffer_layout,
            &views.each_ref().map(wgpu::BindingResource::TextureView),
        );
        let gbuffer = GBuffer { uv, normal, uv_grad, depth, group };
        self.gbuffers.insert(m, gbuffer.clone());
        Ok(gbuffer)
    }

    fn gbuffer_pipelines(&mut self) -> Result<GBufferPipelines, RenderError> {
        if let Some(pipelines) = &self.gbuffer_pipelines {
            return Ok(pipelines.clone());
        }
        let module = self.module("gbuffer.wgsl")?;
        let pipelines = GBufferPipelines::new(&self.gpu.device, &module, &self.scene.layout);
        self.gbuffer_pipelines = Some(pipelines.clone());
        Ok(pipelines)
    }

    /// Override constants of the shading code: light count and stall.
    pub(crate) fn shading_constants(&self, stalled: bool) -> Vec<(&'static str, f64)> {
        let stall = if stalled { self.settings.stall_iterations } else { 0 };
        vec![("LIGHT_COUNT", f64::from(self.scene.light_count)), ("STALL_ITERATIONS", f64::from(stall))]
    }

    /// A fullscreen pipeline (see [`Self::screen_pipeline`]).
    pub(crate) fn fullscreen_pipeline(
        &mut self,
        file: &'static str,
        entry: &str,
        constants: &[(&str, f64)],
        groups: [Option<&wgpu::BindGroupLayout>; 3],
        format: wgpu::TextureFormat,
    ) -> Result<wgpu::RenderPipeline, RenderError> {
        self.screen_pipeline(file, "fullscreen", entry, constants, groups, format)
    }

    /// A render pipeline without vertex buffers, cached by file, entry points, constants and
    /// format. Groups are given by index; `None` leaves a group out of the layout.
    pub(crate) fn screen_pipeline(
        &mut self,
        file: &'static str,
        vertex: &str,
        entry: &str,
        constants: &[(&str, f64)],
        groups: [Option<&wgpu::BindGroupLayout>; 3],
        format: wgpu::TextureFormat,
    ) -> Result<wgpu::RenderPipeline, RenderError> {
        let key = format!("{file}/{vertex}/{entry}/{constants:?}/{format:?}");
        if let Some(pipeline) = self.pipelines.get(&key) {
            return Ok(pipeline.clone());
        }
        let module = self.module(file)?;
        let program = Program { module: &module, entry, constants };
        let pipeline =
            passes::screen_pipeline(&self.gpu.device, entry, vertex, &program, &trim(&groups), format);
        self.pipelines.insert(key, pipeline.clone());
        Ok(pipeline)
    }

    /// A storage buffer shared by every mode that asks for the same name and size.
    pub(crate) fn buffer(&mut self, name: &'static str, size: u64) -> wgpu::Buffer {
        let device = &self.gpu.device;
        self.buffers
            .entry((name, size))
            .or_insert_with(|| {
                device.create_buffer(&wgpu::BufferDescriptor {
                    label: Some(name),
                    size: size.max(16),
                    usage: wgpu::BufferUsages::STORAGE
                        | wgpu::BufferUsages::COPY_DST
                        | wgpu::BufferUsages::COPY_SRC,
                    mapped_at_creation: false,
                })
            })
            .clone()
    }

    /// A compute pipeline, cached like [`Self::fullscreen_pipeline`].
    pub(crate) fn compute_pipeline(
        &mut self,
        file: &'static str,
        entry: &str,
        constants: &[(&str, f64)],
        groups: [Option<&wgpu::BindGroupLayout>; 3],
    ) -> Result<wgpu::ComputePipeline, RenderError> {
        let key = format!("{file}/{entry}/{constants:?}");
        if let Some(pipeline) = self.compute_pipelines.get(&key) {
            return Ok(pipeline.clone());
        }
        let module = self.module(file)?;
        let program = Program { module: &module, entry, constants };
        let pipeline = passes::compute_pipeline(&self.gpu.device, entry, &program, &trim(&groups));
        self.compute_pipelines.insert(key, pipeline.clone());
        Ok(pipeline)
    }

    pub(crate) fn texture_group(&self, texture: &wgpu::Texture) -> wgpu::BindGroup {
        passes::bind_group(
            &self.gpu.device,
            "input",
            &self.texture_layout,
            &[wgpu::BindingResource::TextureView(&view(texture))],
        )
    }

    /// Shades every G-buffer texel into `target` (same size as the G-buffer).
    fn shade_all(
        &mut self,
        gbuffer: &GBuffer,
        stalled: bool,
        target: &wgpu::Texture,
    ) -> Result<Screen, RenderError> {
        let constants = self.shading_constants(stalled);
        let (scene, gb) = (self.scene.layout.clone(), self.gbuffer_layout.clone());
        let pipeline = self.fullscreen_pipeline(
            "shade.wgsl",
            "shade_all",
            &constants,
            [Some(&scene), Some(&gb), None],
            HDR_FORMAT,
        )?;
        Ok(Screen {
            name: "shade",
            pipeline,
            groups: vec![(0, self.scene.group.clone()), (1, gbuffer.group.clone())],
            target: view(target),
            vertices: 3,
        })
    }

    /// Box-filters an M·w × M·h image into `target`.
    fn resolve(
        &mut self,
        m: u32,
        supersampled: &wgpu::Texture,
        target: &wgpu::Texture,
    ) -> Result<Screen, RenderError> {
        let input = self.texture_layout.clone();
        let pipeline = self.fullscreen_pipeline(
            "resolve.wgsl",
            "resolve",
            &[("M", f64::from(m))],
            [None, None, Some(&input)],
            HDR_FORMAT,
        )?;
        Ok(Screen {
            name: "resolve",
            pipeline,
            groups: vec![(2, self.texture_group(supersampled))],
            target: view(target),
            vertices: 3,
        })
    }

    fn display(&mut self, hdr: &wgpu::Texture, target: &wgpu::Texture) -> Result<Screen, RenderError> {
        let (scene, input) = (self.scene.layout.clone(), self.texture_layout.clone());
        let pipeline = self.fullscreen_pipeline(
            "display.wgsl",
            "display",
            &[],
            [Some(&scene), None, Some(&input)],
            DISPLAY_FORMAT,
        )?;
        Ok(Screen {
            name: "display",
            pipeline,
            groups: vec![(0, self.scene.group.clone()), (2, self.texture_group(hdr))],
            target: view(target),
            vertices: 3,
        })
    }
}

/// Pipeline layouts list groups up to the last one used; unused ones in between stay empty.
fn trim<'a>(groups: &[Option<&'a wgpu::BindGroupLayout>; 3]) -> Vec<Option<&'a wgpu::BindGroupLayout>> {
    let used = groups.iter().rposition(Option::is_some).map_or(0, |i| i + 1);
    groups[..used].to_vec()
}

pub(crate) fn view(texture: &wgpu::Texture) -> wgpu::TextureView {
    texture.create_view(&Default::default())
}

/// A mode ready to render: its passes in order and the targets holding its results.
#[derive(Debug)]
pub struct PreparedMode {
    gpu: Arc<Gpu>,
    pub mode: Mode,
    passes: Vec<Box<dyn Pass>>,
    hdr: wgpu::Texture,
    display: wgpu::Texture,
    sample_counts: Option<wgpu::Texture>,
    gbuffer: GBuffer,
    /// S, the shade-first image of adaptive modes.
    first: Option<wgpu::Texture>,
    clip: (f64, f64),
}

impl std::fmt::Debug for dyn Pass {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

impl PreparedMode {
    /// Renders one frame, one submit per pass, each timed from submit to completion.
    pub fn render(&self) -> Result<FrameTiming, RenderError> {
        let mut timing = FrameTiming { passes: Vec::with_capacity(self.passes.len()) };
        for pass in &self.passes {
            let mut encoder = self.gpu.encoder(pass.name());
            pass.encode(&mut encoder);
            let elapsed = self.gpu.submit_timed(encoder)?;
            timing.passes.push(PassTime { name: pass.name(), seconds: elapsed.as_secs_f64() });
        }
        Ok(timing)
    }

    /// Reads back the display image of the last frame (RGBA8), for determinism checks.
    pub fn read_display(&self) -> Result<Vec<u8>, RenderError> {
        self.gpu.read_texture(&self.display)
    }

    /// Reads back the sample counts of the last frame (adaptive modes).
    pub fn read_sample_counts(&self) -> Result<Option<Vec<u8>>, RenderError> {
        self.sample_counts.as_ref().map(|t| self.gpu.read_texture(t)).transpose()
    }

    /// Reads back the G-buffer of the last frame.
    pub fn read_gbuffer(&self) -> Result<GBufferImages, RenderError> {
        let normal_material = half_texels(&self.gpu.read_texture(&self.gbuffer.normal)?);
        let (near, far) = self.clip;
        let depth = self
            .gpu
            .read_texture(&self.gbuffer.depth)?
            .chunks_exact(4)
            .map(|b| {
                let d = f64::from(f32::from_le_bytes([b[0], b[1], b[2], b[3]]));
                near * far / (d * (far - near) + near)
            })
            .collect();
        Ok(GBufferImages {
            width: self.gbuffer.width(),
            height: self.gbuffer.height(),
            normal_material,
            depth,
        })
    }

    /// Reads back S, the shade-first image of an adaptive mode (linear RGBA).
    pub fn read_first(&self) -> Result<Option<Vec<[f32; 4]>>, RenderError> {
        self.first.as_ref().map(|t| Ok(half_texels(&self.gpu.read_texture(t)?))).transpose()
    }

    /// Reads back the images of the last frame. Call it before another mode of the same scene
    /// renders: modes share their targets.
    pub fn read_images(&self) -> Result<FrameImages, RenderError> {
        let display = self.gpu.read_texture(&self.display)?;
        let hdr = half_texels(&self.gpu.read_texture(&self.hdr)?).into_iter().flatten().collect();
        let sample_counts = self.read_sample_counts()?;
        Ok(FrameImages {
            width: self.display.width(),
            height: self.display.height(),
            display,
            hdr,
            sample_counts,
        })
    }
}

/// RGBA f16 texels as f32.
fn half_texels(bytes: &[u8]) -> Vec<[f32; 4]> {
    bytes
        .chunks_exact(8)
        .map(|t| std::array::from_fn(|c| half::f16::from_le_bytes([t[2 * c], t[2 * c + 1]]).to_f32()))
        .collect()
}
