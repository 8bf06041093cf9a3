//! Building a mode's passes for one scene, running timed frames and reading back their images.

use std::collections::{BTreeMap, HashMap};
use std::sync::{Arc, Mutex, MutexGuard};

use glam::DVec2;

use crate::frame::{self, FrameGraph, GraphSummary, SceneNeeds, frame_graph};
use crate::gpu::Gpu;
use crate::graph::{Dims, Output, Physical, Plan, PortRef, Resolved, Usage};
use crate::mode::{Mode, Technique};
use crate::passes::{Allocated, BuildContext, Io, Pass, taa};
use crate::pipelines::Pipelines;
use crate::scene::{Camera, FrameUniforms, GpuScene, Lighting, Scene, Tile};
use crate::{error::RenderError, settings::RenderSettings};

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
    /// The display image's code values.
    pub display: DisplayImage,
    /// Linear HDR RGBA as f32 (stored on the GPU as f16). Alpha carries the stall result.
    pub hdr: Vec<f32>,
    /// Samples shaded per pixel (1…M²), for adaptive modes.
    pub sample_counts: Option<Vec<u8>>,
}

/// A display image: code values per channel, RGBA, row-major from the top.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct DisplayImage {
    /// Bits per channel of the target: 8, or 10 (alpha then has 2 bits, scaled to 0…1023).
    pub bits: u32,
    pub rgba: Vec<u16>,
}

impl DisplayImage {
    /// From an 8-bit image's bytes.
    pub fn from_rgba8(bytes: &[u8]) -> DisplayImage {
        DisplayImage { bits: 8, rgba: bytes.iter().map(|&b| u16::from(b)).collect() }
    }

    /// From a texture's bytes as read back: Rgba8Unorm or Rgb10a2Unorm.
    fn from_texels(format: wgpu::TextureFormat, bytes: &[u8]) -> DisplayImage {
        match format {
            wgpu::TextureFormat::Rgb10a2Unorm => DisplayImage {
                bits: 10,
                rgba: bytes
                    .chunks_exact(4)
                    .flat_map(|t| {
                        let v = u32::from_le_bytes([t[0], t[1], t[2], t[3]]);
                        let channel = |shift: u32| (v >> shift & 0x3ff) as u16;
                        [channel(0), channel(10), channel(20), (v >> 30) as u16 * 341]
                    })
                    .collect(),
            },
            _ => DisplayImage::from_rgba8(bytes),
        }
    }

    /// The largest code value: 255 or 1023.
    pub fn max_code(&self) -> u16 {
        ((1u32 << self.bits) - 1) as u16
    }

    /// The code values as little-endian bytes, one per channel at 8 bits, two at 10: what
    /// run fingerprints hash.
    pub fn bytes(&self) -> Vec<u8> {
        if self.bits <= 8 {
            self.rgba.iter().map(|&v| v as u8).collect()
        } else {
            self.rgba.iter().flat_map(|v| v.to_le_bytes()).collect()
        }
    }
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
    /// World-space normal and material index ([`crate::passes::gbuffer::BACKGROUND_MATERIAL`]: no geometry),
    /// per sample.
    pub normal_material: Vec<[f32; 4]>,
    /// Linear view depth per sample, recovered from the depth buffer in f64.
    pub depth: Vec<f64>,
}

impl GBufferImages {
    /// The indices of pixel (x, y)'s M×M samples, row by row.
    pub fn window_indices(&self, m: u32, x: u32, y: u32) -> impl Iterator<Item = usize> + use<> {
        let width = self.width;
        (0..m * m).map(move |i| ((y * m + i / m) * width + x * m + i % m) as usize)
    }

    /// The M×M window of samples of pixel (x, y), row by row, as the adaptive metric sees it.
    pub fn window(&self, m: u32, x: u32, y: u32) -> Vec<crate::adaptive::WindowSample> {
        self.window_indices(m, x, y)
            .map(|s| {
                let [nx, ny, nz, material] = self.normal_material[s];
                crate::adaptive::WindowSample {
                    depth: self.depth[s],
                    normal: [nx, ny, nz].map(f64::from),
                    covered: material >= 0.0,
                }
            })
            .collect()
    }
}

/// One scene on the device, with the pipelines that its modes share and a pool of textures
/// and buffers. Modes run one at a time, so allocation `k` of a descriptor and usage in one
/// mode's graph is the same texture as allocation `k` of that descriptor and usage in
/// another's.
#[derive(Debug)]
pub struct SceneRenderer {
    gpu: Arc<Gpu>,
    scene: GpuScene,
    needs: SceneNeeds,
    settings: RenderSettings,
    pipelines: Pipelines,
    pool: Pool,
    /// Bytes the pool may hold in all; `prepare` refuses a mode that would pass it.
    memory_budget: Option<u64>,
    /// Kept to rewrite the frame uniforms for ground-truth tiles, and shared with the temporal
    /// modes, which make their own from it.
    view: Arc<Mutex<View>>,
}

/// What the frame uniforms are made from.
#[derive(Debug, Clone)]
struct View {
    camera: Camera,
    lighting: Lighting,
}

/// What a mode that carries a history keeps between frames: frame uniforms of its own (with
/// the previous frame's camera, and jittered under TAA), the scene's view they are made from,
/// and where its history stands.
#[derive(Debug)]
struct Temporal {
    frame: wgpu::Buffer,
    view: Arc<Mutex<View>>,
    size: [u32; 2],
    /// Whether the frames are jittered (TAA); a `-stable` mode's are not.
    jittered: bool,
    history: Mutex<History>,
}

/// Frames rendered since the history was last reset, and the camera of the last one.
#[derive(Debug, Default)]
struct History {
    frames: u32,
    camera: Option<Camera>,
}

impl Temporal {
    /// Writes the uniforms of the next frame: jittered by the frame's Halton point (TAA), with
    /// the camera of the frame before as the history's (this frame's own after a reset).
    fn next_frame(&self, queue: &wgpu::Queue) {
        let view = lock(&self.view);
        let mut history = lock(&self.history);
        let previous = history.camera.unwrap_or(view.camera);
        let [x, y] = self.jitter(history.frames).unwrap_or_default();
        let uniforms = FrameUniforms::temporal(
            &view.camera,
            &previous,
            &view.lighting,
            self.size,
            DVec2::new(x, y),
            history.frames > 0,
        );
        queue.write_buffer(&self.frame, 0, bytemuck::bytes_of(&uniforms));
        history.frames += 1;
        history.camera = Some(view.camera);
    }

    /// The jitter of frame `index` after a reset, where the frames are jittered.
    fn jitter(&self, index: u32) -> Option<[f64; 2]> {
        self.jittered.then(|| taa::jitter(index))
    }
}

/// A lock that a panic elsewhere does not poison: what it guards is plain data, whole at every
/// step.
fn lock<T>(mutex: &Mutex<T>) -> MutexGuard<'_, T> {
    mutex.lock().unwrap_or_else(|poisoned| poisoned.into_inner())
}

impl SceneRenderer {
    pub fn new(
        gpu: Arc<Gpu>,
        scene: &Scene,
        camera: &Camera,
        lighting: &Lighting,
        settings: RenderSettings,
    ) -> Result<SceneRenderer, RenderError> {
        settings.color.validate()?;
        fits_texture_array(scene, &gpu.device.limits())?;
        let frame = FrameUniforms::new(camera, lighting, settings.width, settings.height);
        let needs = SceneNeeds::of(scene, lighting);
        let gpu_scene = GpuScene::new(&gpu.device, &gpu.queue, scene, lighting, &frame);
        gpu.check()?;
        Ok(SceneRenderer {
            pipelines: Pipelines::new(gpu.device.clone(), gpu.queue.clone(), needs.features),
            gpu,
            scene: gpu_scene,
            needs,
            settings,
            pool: Pool::default(),
            memory_budget: None,
            view: Arc::new(Mutex::new(View { camera: *camera, lighting: lighting.clone() })),
        })
    }

    /// Compiles shaders from the files in `dir` instead of the embedded ones (or
    /// `AABENCH_SHADER_DIR`): two renderers of one scene can A/B two shader trees in one process.
    /// The folder holds a whole tree (`lib/` included) that fits this build's bindings and
    /// override constants. Modes prepared before keep their pipelines.
    pub fn read_shaders_from(&mut self, dir: std::path::PathBuf) {
        self.pipelines.read_shaders_from(dir);
    }

    /// Bytes of the scene's texture array on the device (0 for an untextured scene).
    pub fn texture_bytes(&self) -> u64 {
        self.scene.texture_bytes
    }

    /// What the scene needs its frames to have.
    pub fn needs(&self) -> SceneNeeds {
        self.needs
    }

    /// Bytes of every texture and buffer that the prepared modes allocated, shared between
    /// modes as the pool shares them.
    pub fn target_bytes(&self) -> u64 {
        self.pool.bytes()
    }

    /// Compiles the graph of `mode` and builds its passes. Pipelines and allocations are
    /// created on first use and shared; the history and frame uniforms of a mode that carries
    /// one are its own.
    pub fn prepare(&mut self, mode: Mode) -> Result<PreparedMode, RenderError> {
        let graph = frame_graph(&self.needs, mode, &self.settings, &self.gpu.device.limits())?;
        let plan = graph.compile(frame::dims(&self.settings, mode))?;
        self.check_fits(mode, &plan)?;
        let allocated = self.pool.acquire(&self.gpu.device, &plan, mode)?;
        let temporal = mode.carries_history().then(|| Temporal {
            frame: self.gpu.device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("temporal frame uniforms"),
                size: size_of::<FrameUniforms>() as u64,
                usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            }),
            view: Arc::clone(&self.view),
            size: [self.settings.width, self.settings.height],
            jittered: mode.is_jittered(),
            history: Mutex::default(),
        });
        let scene = match &temporal {
            Some(temporal) => self.scene.with_frame(temporal.frame.clone()),
            None => self.scene.clone(),
        };
        let passes = self.build(&scene, &graph, &plan, &allocated)?;
        self.gpu.check()?;
        let camera = lock(&self.view).camera;
        Ok(PreparedMode {
            gpu: Arc::clone(&self.gpu),
            mode,
            passes,
            outputs: outputs(&plan, &allocated),
            graph: GraphSummary::of(&plan),
            clip: (camera.near, camera.far),
            temporal,
        })
    }

    /// Limits the bytes of render targets and buffers that the scene's modes hold together
    /// (lavapipe's textures are host memory); `None` lifts the limit.
    pub fn set_memory_budget(&mut self, bytes: Option<u64>) {
        self.memory_budget = bytes;
    }

    /// Refuses, before anything is allocated, a mode that cannot run as asked: a stall the loop
    /// strategy cannot honour, targets beyond the device's side limit (naming the largest M
    /// that fits), or new allocations that would take the pool past the memory budget.
    fn check_fits(&self, mode: Mode, plan: &Plan) -> Result<(), RenderError> {
        self.check_stall(mode)?;
        if let Some(oversized) = Oversized::find(plan, self.gpu.device.limits().max_texture_dimension_2d) {
            let side = self.settings.width.max(self.settings.height).max(1);
            let fits = (oversized.limit / side).min(4);
            let largest =
                if fits >= 1 { format!("the largest M that fits is {fits}") } else { "no M fits".into() };
            return Err(RenderError::Limit(format!(
                "{mode} at {}×{}: {oversized}, so {largest}",
                self.settings.width, self.settings.height
            )));
        }
        self.check_samples(mode, plan)?;
        self.check_memory(mode, plan)
    }

    /// Every multisampled target in a format and sample count the device renders.
    fn check_samples(&self, mode: Mode, plan: &Plan) -> Result<(), RenderError> {
        for physical in &plan.allocation.physical {
            if let Resolved::Texture { format, samples, .. } = physical.desc
                && samples > 1
                && !self.gpu.multisamples(format, samples)
            {
                return Err(RenderError::Limit(format!(
                    "{mode}: this device does not render {format:?} targets of {samples} samples per pixel"
                )));
            }
        }
        Ok(())
    }

    /// The loop strategy shades up to M² samples in one invocation, all under lavapipe's loop
    /// limit: a longer stall would silently stop short.
    fn check_stall(&self, mode: Mode) -> Result<(), RenderError> {
        let stall = self.settings.stall_iterations;
        let looped = self.settings.adaptive.extra_samples == crate::adaptive::ExtraSamples::Loop;
        let limit = crate::settings::loop_stall_limit(mode.m);
        if looped && mode.stalled && matches!(mode.technique, Technique::Adaptive(..)) && stall > limit {
            return Err(RenderError::Limit(format!(
                "{mode} with extra samples shaded in a loop honours at most {limit} stall iterations \
                 (lavapipe ends an invocation after 65 535 loop iterations, and the loop shades up to \
                 {} samples in one); {stall} were asked for: shade them compacted instead",
                mode.m * mode.m
            )));
        }
        Ok(())
    }

    fn check_memory(&self, mode: Mode, plan: &Plan) -> Result<(), RenderError> {
        let Some(budget) = self.memory_budget else {
            return Ok(());
        };
        let (held, new) = (self.pool.bytes(), self.pool.missing_bytes(plan, mode));
        if held + new <= budget {
            return Ok(());
        }
        let mib = |bytes: u64| bytes as f64 / f64::from(1u32 << 20);
        Err(RenderError::Limit(format!(
            "{mode} needs an estimated {:.0} MiB of new render targets beside the {:.0} MiB held for \
             earlier modes: {:.0} MiB in all, over the memory limit of {:.0} MiB",
            mib(new),
            mib(held),
            mib(held + new),
            mib(budget)
        )))
    }

    /// Builds every pass of a compiled graph, in order, from its ports' allocations.
    fn build(
        &mut self,
        scene: &GpuScene,
        graph: &FrameGraph,
        plan: &Plan,
        allocated: &[Allocated],
    ) -> Result<Vec<Box<dyn Pass>>, RenderError> {
        let mut ctx = BuildContext { scene, pipelines: &mut self.pipelines, settings: &self.settings };
        plan.order
            .iter()
            .map(|&pass| {
                let decl = graph.decl(pass);
                let ports = decl
                    .ports
                    .iter()
                    .map(|port| {
                        let physical =
                            plan.physical_of(PortRef { pass, port: port.name }).expect("every port compiled");
                        (port.name, (*port, allocated[physical].clone()))
                    })
                    .collect();
                let mut io = Io::new(decl.name, ports);
                let built = graph.node(pass).build(&mut ctx, &mut io)?;
                io.finish()?;
                Ok(built)
            })
            .collect()
    }

    /// Renders the ground truth: the brute-force reference at `m` × `m` samples per pixel,
    /// unstalled and untimed, through reference-MxM's graph with its texture-footprint rule
    /// (UV derivatives per G-buffer sample), so a single tile at m = M gives reference-MxM's
    /// image bit for bit. Tiles keep each one's allocations within `tile_bytes`: at 8×8 a
    /// 1024×768 frame needs 1.8 GB of targets at once. The frame uniforms are restored
    /// afterwards.
    pub fn render_truth(&mut self, m: u32, tile_bytes: u64) -> Result<Truth, RenderError> {
        self.render_truth_until(m, tile_bytes, &|| false)
    }

    /// [`render_truth`](Self::render_truth), asking `stop` before each tile: a truth of many
    /// tiles (a 4096² frame takes 38 s) ends within one tile's time of a signal, with
    /// [`RenderError::Stopped`].
    pub fn render_truth_until(
        &mut self,
        m: u32,
        tile_bytes: u64,
        stop: &dyn Fn() -> bool,
    ) -> Result<Truth, RenderError> {
        let (width, height) = (self.settings.width, self.settings.height);
        let limit = self.gpu.device.limits().max_texture_dimension_2d;
        let tiles = truth_tiles(width, height, m, limit, tile_bytes)?;
        let pixels = width as usize * height as usize;
        let mut images = FrameImages {
            width,
            height,
            display: DisplayImage {
                bits: if self.settings.color.bits <= 8 { 8 } else { 10 },
                rgba: vec![0; 4 * pixels],
            },
            hdr: vec![0.0; 4 * pixels],
            sample_counts: None,
        };
        let result = tiles.iter().enumerate().try_for_each(|(done, tile)| {
            if stop() {
                return Err(RenderError::Stopped { done, of: tiles.len() });
            }
            self.render_truth_tile(m, *tile, &mut images)
        });
        self.write_frame_uniforms(Tile::whole(width, height));
        result?;
        Ok(Truth { images, m, tiles: tiles.len() })
    }

    /// Moves the camera: every frame rendered after, each prepared mode's and the truth's, sees
    /// the scene through `camera`. Its near and far planes must be those the modes were
    /// prepared with (they read depth back through them); a camera path keeps them.
    pub fn set_camera(&mut self, camera: &Camera) -> Result<(), RenderError> {
        camera.validate().map_err(|e| RenderError::Camera(e.to_string()))?;
        let current = lock(&self.view).camera;
        if (camera.near, camera.far) != (current.near, current.far) {
            return Err(RenderError::Camera(format!(
                "near and far planes {} and {} differ from the scene's {} and {}",
                camera.near, camera.far, current.near, current.far
            )));
        }
        lock(&self.view).camera = *camera;
        self.write_frame_uniforms(Tile::whole(self.settings.width, self.settings.height));
        Ok(())
    }

    /// Meters the scene's exposure: renders deferred-1x1 once at exposure 1 and returns the
    /// exposure that maps the log-average luminance of its HDR image to `key`
    /// ([`crate::color::metered_exposure`]), clamped to `range`. Every frame rendered after,
    /// the truth's and each mode's, takes that exposure. On an error the exposure stays 1.
    pub fn meter_exposure(&mut self, key: f64, range: [f32; 2]) -> Result<f32, RenderError> {
        lock(&self.view).lighting.exposure = 1.0;
        let (width, height) = (self.settings.width, self.settings.height);
        let metered = self
            .render_alone(Mode::new(Technique::Deferred, 1, false), Tile::whole(width, height), "metering")
            .and_then(|outputs| Ok(half_texels(&self.gpu.read_texture(&outputs[&Output::Hdr])?)))
            .map(|hdr| crate::color::metered_exposure(&hdr, key, range));
        if let Ok(exposure) = metered {
            lock(&self.view).lighting.exposure = exposure;
        }
        self.write_frame_uniforms(Tile::whole(width, height));
        metered
    }

    /// The exposure frames render at: the scene's, or the metered one.
    pub fn exposure(&self) -> f32 {
        lock(&self.view).lighting.exposure
    }

    /// Renders `mode` once, the frame uniforms pointed at `tile`, into allocations of its own
    /// that are freed once the returned outputs are dropped.
    fn render_alone(
        &mut self,
        mode: Mode,
        tile: Tile,
        label: &str,
    ) -> Result<BTreeMap<Output, wgpu::Texture>, RenderError> {
        self.write_frame_uniforms(tile);
        let graph = frame_graph(&self.needs, mode, &self.settings, &self.gpu.device.limits())?;
        let plan = graph.compile(Dims { width: tile.width, height: tile.height, m: mode.m })?;
        let allocated = Pool::default().acquire(&self.gpu.device, &plan, mode)?;
        let scene = self.scene.clone();
        let passes = self.build(&scene, &graph, &plan, &allocated)?;
        let mut encoder = self.gpu.encoder(label);
        for pass in &passes {
            pass.encode(&mut encoder);
        }
        self.gpu.submit_timed(encoder)?;
        Ok(outputs(&plan, &allocated))
    }

    /// Renders one tile of the truth into allocations of its own, freed afterwards, and copies
    /// its images into place in `out`.
    fn render_truth_tile(&mut self, m: u32, tile: Tile, out: &mut FrameImages) -> Result<(), RenderError> {
        let outputs = self.render_alone(Mode::new(Technique::Reference, m, false), tile, "truth")?;
        let tile_display = read_display(&self.gpu, &outputs[&Output::Display])?.rgba;
        let tile_hdr: Vec<f32> =
            half_texels(&self.gpu.read_texture(&outputs[&Output::Hdr])?).into_iter().flatten().collect();
        let row = 4 * tile.width as usize;
        for y in 0..tile.height as usize {
            let at = 4 * ((tile.y as usize + y) * out.width as usize + tile.x as usize);
            out.display.rgba[at..at + row].copy_from_slice(&tile_display[y * row..(y + 1) * row]);
            out.hdr[at..at + row].copy_from_slice(&tile_hdr[y * row..(y + 1) * row]);
        }
        Ok(())
    }

    /// Points the frame uniforms at `tile` of the output (the whole frame for every mode).
    fn write_frame_uniforms(&self, tile: Tile) {
        let (width, height) = (self.settings.width, self.settings.height);
        let view = lock(&self.view);
        let uniforms = FrameUniforms::for_tile(&view.camera, &view.lighting, width, height, tile);
        self.gpu.queue.write_buffer(&self.scene.frame, 0, bytemuck::bytes_of(&uniforms));
    }
}

/// Refuses a scene whose textures need more layers than the device's texture arrays hold,
/// before anything is created: otherwise the upload fails with a raw validation error.
fn fits_texture_array(scene: &Scene, limits: &wgpu::Limits) -> Result<(), RenderError> {
    if !scene.is_textured() {
        return Ok(());
    }
    let layout = crate::scene::textures::Layout::of(&scene.textures);
    if layout.layers <= limits.max_texture_array_layers {
        return Ok(());
    }
    Err(RenderError::Limit(format!(
        "its {} textures need {} layers of {side}×{side} texels in the scene's texture array, and this device holds \
         at most {} (max_texture_array_layers): use fewer textures, or smaller ones beside a large one (textures \
         smaller than the largest share its layers)",
        scene.textures.len(),
        layout.layers,
        limits.max_texture_array_layers,
        side = layout.side
    )))
}

/// The passes that turn the HDR image into the display image, in the order a frame runs them.
const COLOR_PASSES: [&str; 6] = ["tonemap", "display", "fxaa", "smaa_edges", "smaa_weights", "smaa_blend"];

/// The retained outputs' textures.
fn outputs(plan: &Plan, allocated: &[Allocated]) -> BTreeMap<Output, wgpu::Texture> {
    plan.resources
        .iter()
        .enumerate()
        .filter_map(|(index, resource)| {
            let output = resource.retained?;
            match &allocated[plan.allocation.assignment[index]] {
                Allocated::Texture(texture) => Some((output, texture.clone())),
                Allocated::Buffer(_) => None,
            }
        })
        .collect()
}

/// Textures and buffers keyed by descriptor, usage and ordinal: what graphs that never run
/// at the same time share. An allocation carried into the next frame (a history) is kept for
/// its mode alone: its key names the mode, so a scene holds one prepared instance of a
/// temporal mode at a time (two would share one history).
#[derive(Debug, Default)]
struct Pool {
    entries: HashMap<PoolKey, Allocated>,
}

type PoolKey = (Resolved, Usage, usize, Option<Mode>);

fn pool_key(physical: &Physical, mode: Mode) -> PoolKey {
    (physical.desc, physical.usage, physical.ordinal, physical.carried.then_some(mode))
}

/// A target of a plan wider or taller than the device allows, named by its writing port.
#[derive(Debug)]
struct Oversized {
    port: String,
    width: u32,
    height: u32,
    limit: u32,
}

impl Oversized {
    fn find(plan: &Plan, limit: u32) -> Option<Oversized> {
        plan.allocation.physical.iter().find_map(|physical| match physical.desc {
            Resolved::Texture { width, height, .. } if width.max(height) > limit => {
                let writer = plan.resources[physical.resources[0]].writer;
                let port = format!("{}.{}", plan.names[writer.pass], writer.port);
                Some(Oversized { port, width, height, limit })
            }
            _ => None,
        })
    }
}

impl std::fmt::Display for Oversized {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let Oversized { port, width, height, limit } = self;
        write!(f, "{port}: a {width}×{height} target exceeds the device's limit of {limit} texels per side")
    }
}

impl Pool {
    /// An allocation for each of the plan's, created where the pool has none yet, in the
    /// order the frame first writes them: lavapipe's textures are plain memory, and where they
    /// land relative to each other decides how the loads of one texel from several targets
    /// share the CPU's caches.
    fn acquire(
        &mut self,
        device: &wgpu::Device,
        plan: &Plan,
        mode: Mode,
    ) -> Result<Vec<Allocated>, RenderError> {
        if let Some(oversized) = Oversized::find(plan, device.limits().max_texture_dimension_2d) {
            return Err(RenderError::Limit(oversized.to_string()));
        }
        let physical = &plan.allocation.physical;
        let first_write = |p: usize| physical[p].resources.iter().map(|&r| plan.resources[r].first).min();
        let mut creation: Vec<usize> = (0..physical.len()).collect();
        creation.sort_by_key(|&p| (first_write(p), p));
        let mut allocated = vec![None; physical.len()];
        for p in creation {
            let physical = &physical[p];
            let key = pool_key(physical, mode);
            allocated[p] = Some(self.entries.entry(key).or_insert_with(|| create(device, physical)).clone());
        }
        Ok(allocated.into_iter().map(|a| a.expect("every allocation acquired")).collect())
    }

    fn bytes(&self) -> u64 {
        self.entries.keys().map(|(desc, ..)| desc.bytes()).sum()
    }

    /// Bytes that acquiring `plan` for `mode` would newly allocate.
    fn missing_bytes(&self, plan: &Plan, mode: Mode) -> u64 {
        plan.allocation
            .physical
            .iter()
            .filter(|p| !self.entries.contains_key(&pool_key(p, mode)))
            .map(|p| p.desc.bytes())
            .sum()
    }
}

fn create(device: &wgpu::Device, physical: &Physical) -> Allocated {
    let label = Some(physical.desc.to_string());
    match (physical.desc, physical.usage) {
        (Resolved::Texture { format, width, height, layers, samples }, Usage::Texture(usage)) => {
            Allocated::Texture(device.create_texture(&wgpu::TextureDescriptor {
                label: label.as_deref(),
                size: wgpu::Extent3d { width, height, depth_or_array_layers: layers },
                mip_level_count: 1,
                sample_count: samples,
                dimension: wgpu::TextureDimension::D2,
                format,
                usage,
                view_formats: &[],
            }))
        }
        (Resolved::Buffer { bytes }, Usage::Buffer(usage)) => {
            Allocated::Buffer(device.create_buffer(&wgpu::BufferDescriptor {
                label: label.as_deref(),
                size: bytes,
                usage,
                mapped_at_creation: false,
            }))
        }
        _ => unreachable!("a texture's usage is a texture usage"),
    }
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

/// A mode ready to render: its passes in order and the textures holding its results.
#[derive(Debug)]
pub struct PreparedMode {
    gpu: Arc<Gpu>,
    pub mode: Mode,
    passes: Vec<Box<dyn Pass>>,
    outputs: BTreeMap<Output, wgpu::Texture>,
    graph: GraphSummary,
    clip: (f64, f64),
    temporal: Option<Temporal>,
}

impl PreparedMode {
    /// Renders one frame, one submit per pass, each timed from submit to completion. The frame
    /// of a mode that carries a history is the next of it: TAA's jittered and blended with the
    /// frames before, a `-stable` mode's counts following the frame before's.
    pub fn render(&self) -> Result<FrameTiming, RenderError> {
        if let Some(temporal) = &self.temporal {
            temporal.next_frame(&self.gpu.queue);
        }
        let mut timing = FrameTiming { passes: Vec::with_capacity(self.passes.len()) };
        for pass in &self.passes {
            let mut encoder = self.gpu.encoder(pass.name());
            pass.encode(&mut encoder);
            let elapsed = self.gpu.submit_timed(encoder)?;
            timing.passes.push(PassTime { name: pass.name(), seconds: elapsed.as_secs_f64() });
        }
        Ok(timing)
    }

    /// The jitter of the last frame in pixels, where the mode jitters: its sample of pixel
    /// (x, y) lay at (x + ½ + jitter.x, y + ½ + jitter.y).
    pub fn last_jitter(&self) -> Option<[f64; 2]> {
        let temporal = self.temporal.as_ref()?;
        let frames = lock(&temporal.history).frames;
        temporal.jitter(frames.checked_sub(1)?)
    }

    /// Forgets the history: the next frame starts it again, unjittered by earlier frames.
    pub fn reset_history(&self) {
        if let Some(temporal) = &self.temporal {
            *lock(&temporal.history) = History::default();
        }
    }

    /// The mode's frame at the current camera as a still: for a jittered mode, the last of
    /// [`taa::WARMUP_FRAMES`] frames rendered from a reset; for any other, one frame, from a
    /// reset where the mode carries a history. Returns the last frame's timing.
    pub fn render_still(&self) -> Result<FrameTiming, RenderError> {
        let jittered = self.temporal.as_ref().is_some_and(|temporal| temporal.jittered);
        let frames = if jittered { taa::WARMUP_FRAMES } else { 1 };
        self.reset_history();
        for _ in 1..frames {
            self.render()?;
        }
        self.render()
    }

    /// Encodes a given linear HDR image (RGBA, stored as f16 like every HDR image) through this
    /// mode's colour passes (tonemap, display, FXAA) and reads back the display image: how
    /// tests feed the display end values that no scene shades, NaN and infinities included.
    /// The HDR image of the last frame is overwritten.
    pub fn display_from_hdr(&self, hdr: &[[f32; 4]]) -> Result<DisplayImage, RenderError> {
        let target = self.output(Output::Hdr);
        let (width, height) = (target.width(), target.height());
        if hdr.len() != (width * height) as usize {
            return Err(RenderError::Limit(format!(
                "{} texels given for a {width}×{height} image",
                hdr.len()
            )));
        }
        let texels: Vec<u8> =
            hdr.iter().flatten().flat_map(|&v| half::f16::from_f32(v).to_le_bytes()).collect();
        self.gpu.queue.write_texture(
            target.as_image_copy(),
            &texels,
            wgpu::TexelCopyBufferLayout { offset: 0, bytes_per_row: Some(8 * width), rows_per_image: None },
            target.size(),
        );
        let mut encoder = self.gpu.encoder("display_from_hdr");
        for pass in self.passes.iter().skip_while(|p| !COLOR_PASSES.contains(&p.name())) {
            pass.encode(&mut encoder);
        }
        self.gpu.submit_timed(encoder)?;
        self.read_display()
    }

    /// The compiled graph: passes in order, allocations and their bytes.
    pub fn graph(&self) -> &GraphSummary {
        &self.graph
    }

    fn output(&self, output: Output) -> &wgpu::Texture {
        &self.outputs[&output]
    }

    /// Reads back the display image of the last frame, for determinism checks.
    pub fn read_display(&self) -> Result<DisplayImage, RenderError> {
        read_display(&self.gpu, self.output(Output::Display))
    }

    /// Reads back the HDR image of the last frame: linear RGBA, alpha the stall's result.
    pub fn read_hdr(&self) -> Result<Vec<[f32; 4]>, RenderError> {
        Ok(half_texels(&self.gpu.read_texture(self.output(Output::Hdr))?))
    }

    /// Reads back the sample counts of the last frame (adaptive modes).
    pub fn read_sample_counts(&self) -> Result<Option<Vec<u8>>, RenderError> {
        self.outputs.get(&Output::SampleCounts).map(|t| self.gpu.read_texture(t)).transpose()
    }

    /// Reads back the single-sampled G-buffer of the last frame (every mode but MSAA's, whose
    /// multisampled G-buffer is not kept).
    pub fn read_gbuffer(&self) -> Result<GBufferImages, RenderError> {
        let kept = |output| {
            self.outputs.get(&output).ok_or_else(|| {
                RenderError::Binding("the multisampled G-buffer of msaa-4x is not read back".into())
            })
        };
        let normal = kept(Output::GBufferNormal)?;
        let normal_material = half_texels(&self.gpu.read_texture(normal)?);
        let (near, far) = self.clip;
        let depth = self
            .gpu
            .read_texture(kept(Output::GBufferDepth)?)?
            .chunks_exact(4)
            .map(|b| {
                let d = f64::from(f32::from_le_bytes([b[0], b[1], b[2], b[3]]));
                near * far / (d * (far - near) + near)
            })
            .collect();
        Ok(GBufferImages { width: normal.width(), height: normal.height(), normal_material, depth })
    }

    /// Reads back the motion of the last frame (temporal modes): per pixel, the pixels its
    /// point moved since the frame before (x right, y down) and its linear view depth then.
    pub fn read_motion(&self) -> Result<Option<Vec<[f32; 4]>>, RenderError> {
        self.outputs.get(&Output::Motion).map(|t| Ok(half_texels(&self.gpu.read_texture(t)?))).transpose()
    }

    /// Reads back S, the shade-first image of an adaptive mode (linear RGBA).
    pub fn read_first(&self) -> Result<Option<Vec<[f32; 4]>>, RenderError> {
        self.outputs.get(&Output::First).map(|t| Ok(half_texels(&self.gpu.read_texture(t)?))).transpose()
    }

    /// Reads back the shadow cubes of the last frame, where the scene has shadow lights:
    /// reversed depth per texel, layer after layer (6 per light: +X, −X, +Y, −Y, +Z, −Z), each
    /// `resolution`² from the top row.
    pub fn read_shadow_cubes(&self) -> Result<Option<ShadowDepths>, RenderError> {
        let Some(cubes) = self.outputs.get(&Output::ShadowCubes) else { return Ok(None) };
        let depth = self
            .gpu
            .read_texture(cubes)?
            .chunks_exact(4)
            .map(|b| f32::from_le_bytes([b[0], b[1], b[2], b[3]]))
            .collect();
        Ok(Some(ShadowDepths { resolution: cubes.width(), layers: cubes.depth_or_array_layers(), depth }))
    }

    /// Reads back the images of the last frame. Call it before another mode of the same scene
    /// renders: modes share their allocations.
    pub fn read_images(&self) -> Result<FrameImages, RenderError> {
        let display = self.output(Output::Display);
        let hdr = self.read_hdr()?.into_iter().flatten().collect();
        Ok(FrameImages {
            width: display.width(),
            height: display.height(),
            display: read_display(&self.gpu, display)?,
            hdr,
            sample_counts: self.read_sample_counts()?,
        })
    }
}

fn read_display(gpu: &Gpu, texture: &wgpu::Texture) -> Result<DisplayImage, RenderError> {
    Ok(DisplayImage::from_texels(texture.format(), &gpu.read_texture(texture)?))
}

/// The shadow cubes of a frame, read back.
#[derive(Debug, Clone, PartialEq)]
pub struct ShadowDepths {
    pub resolution: u32,
    pub layers: u32,
    /// Reversed depth (1 at the near plane, 0 at the light's range), layer by layer.
    pub depth: Vec<f32>,
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
