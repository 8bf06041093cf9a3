//! Building a mode's passes for one scene, running timed frames and reading back their images:
//! the scene on the device (`SceneRenderer`, here), a mode ready to render (`prepared.rs`), the
//! allocations its modes share (`pool.rs`), the ground truth (`truth.rs`) and what a frame
//! gives back (`images.rs`).

mod images;
mod pool;
mod prepared;
mod truth;

pub use images::{DisplayImage, FrameImages, FrameTiming, GBufferImages, PassTime, ShadowDepths};
pub use prepared::PreparedMode;
pub use truth::{Truth, truth_in_one_piece};

use std::collections::BTreeMap;
use std::sync::{Arc, Mutex};

use crate::error::RenderError;
use crate::frame::{self, GraphSummary, SceneNeeds, frame_graph};
use crate::gpu::Gpu;
use crate::graph::{Dims, Output, Plan, PortRef, Resolved};
use crate::mode::Mode;
use crate::passes::{Allocated, BuildContext, Io, Pass};
use crate::pipelines::Pipelines;
use crate::scene::pose::Poser;
use crate::scene::{Camera, FrameUniforms, GpuScene, Lighting, Scene, Tile};
use crate::settings::RenderSettings;
use crate::technique::{FrameGraph, Technique};
use images::half_texels;
use pool::{Oversized, Pool, outputs};
use prepared::{Temporal, lock};

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
    /// What poses the scene, where an animation plays.
    poser: Option<Poser>,
}

/// What the frame uniforms are made from.
#[derive(Debug, Clone)]
struct View {
    camera: Camera,
    lighting: Lighting,
}

/// The pipelines that earlier scenes compiled on `gpu`, to compose shaders for `features` (while
/// one scene holds them, another gets its own): a scene compiles only the shaders whose text no
/// scene before it compiled (lavapipe spends about half a second a scene creating them all).
fn lend_pipelines(gpu: &Gpu, features: crate::shaders::Features) -> Pipelines {
    match gpu.take_kept().and_then(|kept| kept.downcast::<Pipelines>().ok()) {
        Some(mut kept) => {
            kept.set_features(features);
            *kept
        }
        None => Pipelines::new(gpu.device.clone(), gpu.queue.clone(), features),
    }
}

/// The scene's pipelines outlive it on the device, for the next scene, unless they were
/// compiled from another shader tree than the embedded one.
impl Drop for SceneRenderer {
    fn drop(&mut self) {
        if self.pipelines.reads_embedded_shaders() {
            let empty = Pipelines::new(self.gpu.device.clone(), self.gpu.queue.clone(), self.needs.features);
            self.gpu.keep(Box::new(std::mem::replace(&mut self.pipelines, empty)));
        }
    }
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
        // A playing animation starts at its time 0, not in the file's rest pose.
        let poser = Poser::of(scene);
        if let Some(poser) = &poser {
            gpu_scene.write_pose(&gpu.queue, poser, 0.0, 0.0);
        }
        gpu.check()?;
        Ok(SceneRenderer {
            pipelines: lend_pipelines(&gpu, needs.features),
            gpu,
            scene: gpu_scene,
            needs,
            settings,
            pool: Pool::default(),
            memory_budget: None,
            view: Arc::new(Mutex::new(View { camera: *camera, lighting: lighting.clone() })),
            poser,
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

    /// Pipelines compiled on the device so far, by this scene and the scenes before it whose
    /// pipelines it reuses.
    pub fn compiled_pipelines(&self) -> usize {
        self.pipelines.compiled()
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
        let history = mode.carries_history().then_some(mode.is_jittered());
        self.prepare_graph(mode, &graph, history)
    }

    /// Prepares the scene's geometry probe: the G-buffer alone, unjittered, with each pixel's
    /// motion since the frame the probe rendered before (`read_motion`) and its depth
    /// (`read_gbuffer`). It keeps the camera of its last frame, as a temporal mode does; its
    /// first frame after a reset has no motion. A sequence follows the truth's pixels along it.
    pub fn prepare_geometry(&mut self) -> Result<PreparedMode, RenderError> {
        let probe = Mode::new(Technique::Deferred, 1, false);
        self.prepare_graph(probe, &frame::geometry_graph(), Some(false))
    }

    /// Compiles `graph` for `mode`, allocates it and builds its passes; `history`, where the
    /// mode carries one, says whether its frames are jittered.
    fn prepare_graph(
        &mut self,
        mode: Mode,
        graph: &FrameGraph,
        history: Option<bool>,
    ) -> Result<PreparedMode, RenderError> {
        let plan = graph.compile(frame::dims(&self.settings, mode))?;
        self.check_fits(mode, &plan)?;
        let allocated = self.pool.acquire(&self.gpu.device, &plan, mode)?;
        let temporal = history.map(|jittered| Temporal {
            frame: self.gpu.device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("temporal frame uniforms"),
                size: size_of::<FrameUniforms>() as u64,
                usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            }),
            view: Arc::clone(&self.view),
            size: [self.settings.width, self.settings.height],
            jittered,
            reprojected: true,
            history: Mutex::default(),
        });
        let scene = match &temporal {
            Some(temporal) => self.scene.with_frame(temporal.frame.clone()),
            None => self.scene.clone(),
        };
        let (passes, color_end) = self.build(&scene, graph, &plan, &allocated)?;
        self.gpu.check()?;
        let camera = lock(&self.view).camera;
        Ok(PreparedMode {
            gpu: Arc::clone(&self.gpu),
            mode,
            passes,
            color_end,
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

    /// Builds every pass of a compiled graph, in order, from its ports' allocations, and says
    /// where the colour end begins: the first pass that encodes colour.
    fn build(
        &mut self,
        scene: &GpuScene,
        graph: &FrameGraph,
        plan: &Plan,
        allocated: &[Allocated],
    ) -> Result<(Vec<Box<dyn Pass>>, usize), RenderError> {
        let color_end = plan.order.iter().position(|&pass| graph.node(pass).encodes_color());
        let mut ctx = BuildContext {
            scene,
            pipelines: &mut self.pipelines,
            color: &self.settings.color,
            stall_iterations: self.settings.stall_iterations,
        };
        let passes = plan
            .order
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
            .collect::<Result<Vec<_>, RenderError>>()?;
        let color_end = color_end.unwrap_or(passes.len());
        Ok((passes, color_end))
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

    /// Poses the scene: every frame rendered after sees the objects its animation moves where
    /// they lie `now` seconds into it, and their motion vectors hold the motion since `then` (the
    /// time of the frame before; `then == now` for a still). A scene without a playing
    /// animation refuses.
    pub fn pose(&mut self, now: f64, then: f64) -> Result<(), RenderError> {
        let Some(poser) = &self.poser else {
            return Err(RenderError::Pose("no animation plays in this scene".into()));
        };
        if !(now.is_finite() && then.is_finite()) {
            return Err(RenderError::Pose(format!("times {now} and {then} must be finite")));
        }
        self.scene.write_pose(&self.gpu.queue, poser, now, then);
        self.gpu.check()
    }

    /// Whether an animation plays: frames are posed ([`SceneRenderer::pose`]).
    pub fn is_moving(&self) -> bool {
        self.poser.is_some()
    }

    /// Meters the scene's exposure: renders deferred-1x1 once at exposure 1 and returns the
    /// exposure ([`crate::color::metered_exposure`]) that maps the log-average luminance of the
    /// pixels that show the scene (not the background) to `key`, keeps all but a fiftieth of
    /// them below white, and stays within `range`. Every frame rendered after, the truth's and
    /// each mode's, takes that exposure. A scene whose light reaches the HDR target's limit
    /// is an error ([`RenderError::Limit`]); on an error the exposure stays 1.
    pub fn meter_exposure(&mut self, key: f64, range: [f32; 2]) -> Result<f32, RenderError> {
        lock(&self.view).lighting.exposure = 1.0;
        let white = self.white();
        let metered = self.scene_radiance("metering").and_then(|(hdr, scene)| {
            crate::color::metered_exposure(&hdr, Some(&scene), key, white, range).map_err(RenderError::Limit)
        });
        if let Ok(exposure) = metered {
            lock(&self.view).lighting.exposure = exposure;
        }
        self.write_frame_uniforms(Tile::whole(self.settings.width, self.settings.height));
        metered
    }

    /// Checks a scene's own exposure against its light: renders deferred-1x1 once and fails
    /// ([`RenderError::Limit`]) where the scene's radiance reaches the HDR target's limit on
    /// more than a hundredth of its pixels and the exposure shows that limit below white, so
    /// that the light lost above it would show ([`crate::color::headroom`]).
    pub fn check_headroom(&mut self) -> Result<(), RenderError> {
        let (exposure, white) = (f64::from(self.exposure()), self.white());
        let checked = self.scene_radiance("headroom").and_then(|(hdr, scene)| {
            crate::color::headroom(&hdr, Some(&scene), exposure, white).map_err(RenderError::Limit)
        });
        self.write_frame_uniforms(Tile::whole(self.settings.width, self.settings.height));
        checked
    }

    /// The HDR value that displays white: the tonemap's `hdr_max`, or 1 where the image is
    /// exposed and clamped.
    fn white(&self) -> f64 {
        self.settings.color.tonemap.map_or(1.0, |tonemap| tonemap.hdr_max)
    }

    /// Deferred-1x1's HDR radiance, rendered alone, and which of its pixels show the scene (not
    /// the background). The frame uniforms are left pointing at the whole frame's tile.
    fn scene_radiance(&mut self, label: &str) -> Result<(Vec<[f32; 4]>, Vec<bool>), RenderError> {
        let (width, height) = (self.settings.width, self.settings.height);
        let outputs =
            self.render_alone(Mode::new(Technique::Deferred, 1, false), Tile::whole(width, height), label)?;
        let hdr = half_texels(&self.gpu.read_texture(&outputs[&Output::Hdr])?);
        let depth = self.gpu.read_texture(&outputs[&Output::GBufferDepth])?;
        // Reversed depth: the background keeps the cleared far plane, 0.
        let scene: Vec<bool> = depth.chunks_exact(4).map(|d| d != [0; 4]).collect();
        Ok((hdr, scene))
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
        let (passes, _) = self.build(&scene, &graph, &plan, &allocated)?;
        let mut encoder = self.gpu.encoder(label);
        for pass in &passes {
            pass.encode(&mut encoder);
        }
        self.gpu.submit_timed(encoder)?;
        Ok(outputs(&plan, &allocated))
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
