//! Building a mode's passes for one scene, running timed frames and reading back their images.

use std::collections::HashMap;
use std::sync::Arc;

use crate::gpu::Gpu;
use crate::mode::{Mode, Technique};
use crate::passes::gbuffer::{self, GBuffer, GBufferPass, GBufferPipelines};
use crate::passes::{self, Pass, Program, Screen, Slot};
use crate::scene::{Camera, FrameUniforms, GpuScene, Lighting, Scene, Tile};
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

/// The ground truth of a scene: the brute-force reference at `m` × `m` samples per pixel,
/// unstalled, rendered tile by tile (see [`SceneRenderer::render_truth`]).
#[derive(Debug, Clone, PartialEq)]
pub struct Truth {
    /// The display image and HDR image, as a mode's; no sample counts.
    pub images: FrameImages,
    pub m: u32,
    pub tiles: usize,
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
    /// Kept to rewrite the frame uniforms for ground-truth tiles.
    camera: Camera,
    lighting: Lighting,
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
            camera: *camera,
            lighting: lighting.clone(),
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
            clip: (self.camera.near, self.camera.far),
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
            .or_insert_with(|| create_target(device, name, width, height, format))
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

    /// The G-buffer of the M×M modes, shared by all of them.
    fn gbuffer(&mut self, m: u32) -> Result<GBuffer, RenderError> {
        if let Some(gbuffer) = self.gbuffers.get(&m) {
            return Ok(gbuffer.clone());
        }
        let gbuffer = self.gbuffer_targets(m * self.settings.width, m * self.settings.height, true)?;
        self.gbuffers.insert(m, gbuffer.clone());
        Ok(gbuffer)
    }

    /// G-buffer targets of one size: shared through [`Self::target`], or made for one use
    /// (ground-truth tiles) and freed when dropped.
    fn gbuffer_targets(&mut self, width: u32, height: u32, shared: bool) -> Result<GBuffer, RenderError> {
        let limit = self.gpu.device.limits().max_texture_dimension_2d;
        if width > limit || height > limit {
            return Err(RenderError::TooLarge { width, height, limit });
        }
        let mut make = |name, format| {
            if shared {
                self.target(name, width, height, format)
            } else {
                create_target(&self.gpu.device, name, width, height, format)
            }
        };
        let uv = make("gbuffer.uv", gbuffer::UV_FORMAT);
        let normal = make("gbuffer.normal", gbuffer::NORMAL_FORMAT);
        let uv_grad = make("gbuffer.uv_grad", gbuffer::UV_GRAD_FORMAT);
        let depth = make("gbuffer.depth", gbuffer::DEPTH_FORMAT);
        let views = [&uv, &normal, &uv_grad, &depth].map(view);
        let group = passes::bind_group(
            &self.gpu.device,
            "gbuffer",
            &self.gbuffer_layout,
            &views.each_ref().map(wgpu::BindingResource::TextureView),
        );
        Ok(GBuffer { uv, normal, uv_grad, depth, group })
    }

    /// Renders the ground truth: the brute-force reference at `m` × `m` samples per pixel,
    /// unstalled and untimed, with reference-MxM's shaders and texture-footprint rule (UV
    /// derivatives per G-buffer sample), so a single tile at m = M gives reference-MxM's image
    /// bit for bit. Tiles keep each one's targets within `tile_bytes`: at 8×8 a 1024×768
    /// frame needs 1.8 GB of targets at once. The frame uniforms are restored afterwards.
    pub fn render_truth(&mut self, m: u32, tile_bytes: u64) -> Result<Truth, RenderError> {
        let (width, height) = (self.settings.width, self.settings.height);
        let limit = self.gpu.device.limits().max_texture_dimension_2d;
        let tiles = truth_tiles(width, height, m, limit, tile_bytes)?;
        let pixels = width as usize * height as usize;
        let mut images = FrameImages {
            width,
            height,
            display: vec![0; 4 * pixels],
            hdr: vec![0.0; 4 * pixels],
            sample_counts: None,
        };
        let result = tiles.iter().try_for_each(|tile| self.render_truth_tile(m, *tile, &mut images));
        self.write_frame_uniforms(Tile::whole(width, height));
        result?;
        Ok(Truth { images, m, tiles: tiles.len() })
    }

    /// Renders one tile of the truth and copies its images into place in `out`.
    fn render_truth_tile(&mut self, m: u32, tile: Tile, out: &mut FrameImages) -> Result<(), RenderError> {
        self.write_frame_uniforms(tile);
        let gbuffer = self.gbuffer_targets(m * tile.width, m * tile.height, false)?;
        let device = &self.gpu.device;
        let supersampled =
            create_target(device, "truth.supersampled", gbuffer.width(), gbuffer.height(), HDR_FORMAT);
        let hdr = create_target(device, "truth.hdr", tile.width, tile.height, HDR_FORMAT);
        let display = create_target(device, "truth.display", tile.width, tile.height, DISPLAY_FORMAT);
        let passes: [Box<dyn Pass>; 4] = [
            Box::new(GBufferPass {
                pipelines: self.gbuffer_pipelines()?,
                scene: self.scene.clone(),
                targets: gbuffer.clone(),
            }),
            Box::new(self.shade_all(&gbuffer, false, &supersampled)?),
            Box::new(self.resolve(m, &supersampled, &hdr)?),
            Box::new(self.display(&hdr, &display)?),
        ];
        let mut encoder = self.gpu.encoder("truth");
        for pass in &passes {
            pass.encode(&mut encoder);
        }
        self.gpu.submit_timed(encoder)?;
        let tile_display = self.gpu.read_texture(&display)?;
        let tile_hdr: Vec<f32> = half_texels(&self.gpu.read_texture(&hdr)?).into_iter().flatten().collect();
        let row = 4 * tile.width as usize;
        for y in 0..tile.height as usize {
            let at = 4 * ((tile.y as usize + y) * out.width as usize + tile.x as usize);
            out.display[at..at + row].copy_from_slice(&tile_display[y * row..(y + 1) * row]);
            out.hdr[at..at + row].copy_from_slice(&tile_hdr[y * row..(y + 1) * row]);
        }
        Ok(())
    }

    /// Points the frame uniforms at `tile` of the output (the whole frame for every mode).
    fn write_frame_uniforms(&self, tile: Tile) {
        let (width, height) = (self.settings.width, self.settings.height);
        let uniforms = FrameUniforms::for_tile(&self.camera, &self.lighting, width, height, tile);
        self.gpu.queue.write_buffer(&self.scene.frame, 0, bytemuck::bytes_of(&uniforms));
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

/// A 2D render target that passes draw into, sample and copy out of.
fn create_target(
    device: &wgpu::Device,
    name: &str,
    width: u32,
    height: u32,
    format: wgpu::TextureFormat,
) -> wgpu::Texture {
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
}

/// Target bytes per G-buffer sample of a truth tile: the G-buffer (UV 8, normal 8, UV
/// derivatives 8, depth 4) and the supersampled HDR image (8).
const TRUTH_BYTES_PER_SAMPLE: u64 = 36;

/// Splits a `width` × `height` frame into tiles whose m·w × m·h targets fit `max_side` and
/// together take at most `budget` bytes (at least one row of pixels per tile): full-width
/// bands where the width fits, a grid otherwise, sizes as even as the division allows.
fn truth_tiles(
    width: u32,
    height: u32,
    m: u32,
    max_side: u32,
    budget: u64,
) -> Result<Vec<Tile>, RenderError> {
    let max_tile_side = max_side / m.max(1);
    if max_tile_side == 0 {
        return Err(RenderError::TooLarge { width: m, height: m, limit: max_side });
    }
    let tile_width = width.min(max_tile_side);
    let bytes_per_row = u64::from(m * m) * TRUTH_BYTES_PER_SAMPLE * u64::from(tile_width);
    let rows = (budget / bytes_per_row).clamp(1, u64::from(height.min(max_tile_side))) as u32;
    let (columns, bands) = (width.div_ceil(tile_width), height.div_ceil(rows));
    let (tile_width, rows) = (width.div_ceil(columns), height.div_ceil(bands));
    let mut tiles = Vec::new();
    for y in (0..height).step_by(rows as usize) {
        for x in (0..width).step_by(tile_width as usize) {
            tiles.push(Tile { x, y, width: tile_width.min(width - x), height: rows.min(height - y) });
        }
    }
    Ok(tiles)
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

#[cfg(test)]
mod tests {
    use super::*;

    /// Every pixel in exactly one tile, every tile within the limits.
    fn check(width: u32, height: u32, m: u32, max_side: u32, budget: u64) -> Vec<Tile> {
        let tiles = truth_tiles(width, height, m, max_side, budget).unwrap();
        let mut covered = vec![0u8; (width * height) as usize];
        for tile in &tiles {
            assert!(tile.width > 0 && tile.height > 0, "{tile:?}");
            assert!(m * tile.width <= max_side && m * tile.height <= max_side, "{tile:?}");
            for y in tile.y..tile.y + tile.height {
                for x in tile.x..tile.x + tile.width {
                    covered[(y * width + x) as usize] += 1;
                }
            }
        }
        assert!(covered.iter().all(|&c| c == 1), "{width}×{height}: {tiles:?}");
        tiles
    }

    #[test]
    fn truth_tiles_cover_the_frame_once_within_the_limits() {
        // 1024×768 at 8×8 in 512 MiB: four full-width bands of 192 rows.
        let tiles = check(1024, 768, 8, 16384, 512 << 20);
        assert_eq!(tiles.len(), 4);
        assert!(tiles.iter().all(|t| t.width == 1024 && t.height == 192));
        // A budget of one row per tile, odd sizes, a width past the texture limit.
        assert_eq!(check(317, 211, 8, 16384, 1).len(), 211);
        let wide = check(4096, 8, 8, 16384, u64::MAX);
        assert_eq!(wide.len(), 2, "{wide:?}");
        assert_eq!(check(1, 1, 8, 16384, 512 << 20).len(), 1);
        assert!(truth_tiles(4, 4, 8, 4, u64::MAX).is_err(), "one pixel at 8×8 exceeds a 4-texel limit");
    }
}
