//! Passes: units of GPU work that are submitted and timed one at a time, and the ones every
//! technique shares (the G-buffer, shadows, deferred shading, the colour end, a kept history,
//! lists of marked pixels). Each technique's own passes are in its room under `technique/`.
//!
//! A [`Node`] declares a pass's ports (device-free, for the graph's compile step) and builds
//! the pass from a small [`BuildContext`] and the resources its ports were given ([`Io`]).
//! Bindings are matched by name: a port, a constant the pass owns or a scene resource named
//! like the WGSL variable (see `bindings.rs`). Every port a pass declares for binding must be
//! bound by one of its shaders, or building it fails: a declaration cannot drift from the WGSL.

pub(crate) mod display;
pub(crate) mod gbuffer;
pub(crate) mod keep;
pub(crate) mod pixel_list;
pub(crate) mod shade;
pub(crate) mod shadow;
pub(crate) mod tonemap;

use std::collections::{BTreeSet, HashMap};

use crate::bindings::{self, Bound, Stages};
use crate::color::ColorSettings;
use crate::error::RenderError;
use crate::graph::{Access, PassDecl, Port, Resource};
use crate::pipelines::{
    ComputeKey, Constants, LayoutEntries, MAX_SCREEN_TARGETS, Pipelines, Raster, RenderKey, ScreenTargets,
};
use crate::scene::GpuScene;

/// Linear HDR radiance.
pub(crate) const HDR_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba16Float;

/// Per-pixel sample counts, 1…16 (adaptive modes, MSAA).
pub(crate) const COUNT_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::R8Uint;

/// The target of display code values: 8-bit unorm up to 8 bits per channel, else 10-bit.
pub(crate) fn display_format(bits: u32) -> wgpu::TextureFormat {
    if bits <= 8 { wgpu::TextureFormat::Rgba8Unorm } else { wgpu::TextureFormat::Rgb10a2Unorm }
}

/// The fullscreen triangle's vertex entry point (`lib/common.wgsl`) and its vertex count.
pub(crate) const FULLSCREEN: (&str, u32) = ("fullscreen", 3);

/// One measured unit of work.
pub(crate) trait Pass: Send + Sync {
    fn name(&self) -> &'static str;
    fn encode(&self, encoder: &mut wgpu::CommandEncoder);
}

impl std::fmt::Debug for dyn Pass {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

/// A pass as the graph sees it: its ports, and how to build it once they have resources.
pub(crate) trait Node: std::fmt::Debug + Send + Sync {
    fn decl(&self) -> PassDecl;
    fn build(&self, ctx: &mut BuildContext, io: &mut Io) -> Result<Box<dyn Pass>, RenderError>;

    /// Whether the pass belongs to the frame's colour end, which turns the HDR image into the
    /// display image (tonemap, display, a post-process on the display image): where a given
    /// HDR image is encoded from (`PreparedMode::display_from_hdr`).
    fn encodes_color(&self) -> bool {
        false
    }
}

/// What a pass is built from: never the whole renderer.
#[derive(Debug)]
pub(crate) struct BuildContext<'a> {
    pub scene: &'a GpuScene,
    pub pipelines: &'a mut Pipelines,
    /// From linear HDR to the display image.
    pub color: &'a ColorSettings,
    /// Dependent ALU iterations per shaded sample of a stalled mode.
    pub stall_iterations: u32,
}

/// A texture or buffer given to a port.
#[derive(Debug, Clone)]
pub(crate) enum Allocated {
    Texture(wgpu::Texture),
    Buffer(wgpu::Buffer),
}

/// The resources of one pass's ports, and the names its shaders bound so far.
#[derive(Debug)]
pub(crate) struct Io {
    pass: &'static str,
    ports: HashMap<&'static str, (Port, Allocated)>,
    bound: BTreeSet<String>,
}

impl Io {
    pub fn new(pass: &'static str, ports: HashMap<&'static str, (Port, Allocated)>) -> Io {
        Io { pass, ports, bound: BTreeSet::new() }
    }

    /// The texture of a port.
    pub fn texture(&self, port: &str) -> Result<wgpu::Texture, RenderError> {
        match self.ports.get(port) {
            Some((_, Allocated::Texture(texture))) => Ok(texture.clone()),
            _ => Err(RenderError::Binding(format!("{}: no texture port {port}", self.pass))),
        }
    }

    /// What a binding named `name` is bound to: the pass's port of that name, else a resource
    /// the pass owns (constant data such as `gather`'s area weights), else the scene's.
    fn lookup(&self, name: &str, scene: &GpuScene, owned: &[(&str, Bound)]) -> Option<Bound> {
        if let Some((port, allocated)) = self.ports.get(name) {
            return port.access.is_binding().then(|| match allocated {
                Allocated::Buffer(buffer) => Bound::Buffer(buffer.clone()),
                Allocated::Texture(texture) => Bound::Texture {
                    texture: texture.clone(),
                    filterable: port.access == Access::Sampled,
                    view_format: None,
                },
            });
        }
        owned.iter().find(|(n, _)| *n == name).map(|(_, b)| b.clone()).or_else(|| scene.binding(name))
    }

    /// Fails when a port declared for binding was bound by none of the pass's shaders.
    pub fn finish(&self) -> Result<(), RenderError> {
        let mut unbound: Vec<&str> = self
            .ports
            .values()
            .filter(|(port, _)| port.access.is_binding() && !self.bound.contains(port.name))
            .map(|(port, _)| port.name)
            .collect();
        unbound.sort_unstable();
        if unbound.is_empty() {
            Ok(())
        } else {
            Err(RenderError::Binding(format!(
                "{}: the ports {} are declared but no shader of the pass binds them",
                self.pass,
                unbound.join(", ")
            )))
        }
    }
}

/// Which shader entry points, with which override constants, make a pipeline.
#[derive(Debug, Clone)]
pub(crate) struct Program {
    pub shader: &'static str,
    pub vertex: &'static str,
    pub fragment: Option<&'static str>,
    pub constants: Constants,
}

/// Bind groups by group index.
pub(crate) type Groups = Vec<(u32, wgpu::BindGroup)>;

/// A pipeline and the bind groups that its shaders' bindings resolved to.
#[derive(Debug, Clone)]
pub(crate) struct Bundle<P> {
    pub pipeline: P,
    pub groups: Groups,
}

impl BuildContext<'_> {
    /// Reflects the entry points' bindings, resolves them by name and creates their groups.
    fn resolve(
        &mut self,
        io: &mut Io,
        shader: &'static str,
        entries: &[&str],
        stages: Stages,
        owned: &[(&str, Bound)],
    ) -> Result<(LayoutEntries, Groups), RenderError> {
        let bindings = self.pipelines.shader(shader)?.bindings(entries)?;
        let scene = self.scene;
        let lookup = |name: &str| io.lookup(name, scene, owned);
        let mut bound = BTreeSet::new();
        let resolved = bindings::resolve(io.pass, &bindings, stages, &lookup, &mut bound)?;
        io.bound.extend(bound);
        let layout = bindings::group_entries(&resolved);
        let mut groups = Vec::new();
        for (index, entries) in layout.iter().enumerate().filter(|(_, e)| !e.is_empty()) {
            let group_layout = self.pipelines.group_layout(entries);
            let resources: Vec<wgpu::BindGroupEntry> = resolved
                .iter()
                .filter(|r| r.group == index as u32)
                .map(|r| wgpu::BindGroupEntry { binding: r.entry.binding, resource: r.resource.as_binding() })
                .collect();
            let group = self.pipelines.device().create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some(io.pass),
                layout: &group_layout,
                entries: &resources,
            });
            groups.push((index as u32, group));
        }
        Ok((layout, groups))
    }

    /// A render pipeline for `program`; `create` builds it when the cache does not hold it.
    pub fn render_pipeline(
        &mut self,
        io: &mut Io,
        program: &Program,
        raster: Raster,
        owned: &[(&str, Bound)],
        create: impl FnOnce(
            &wgpu::Device,
            &wgpu::PipelineLayout,
            &wgpu::ShaderModule,
            &RenderKey,
        ) -> wgpu::RenderPipeline,
    ) -> Result<Bundle<wgpu::RenderPipeline>, RenderError> {
        let entries: Vec<&str> = std::iter::once(program.vertex).chain(program.fragment).collect();
        let (layout, groups) = self.resolve(io, program.shader, &entries, Stages::Render, owned)?;
        let key = RenderKey {
            shader: program.shader,
            vertex: program.vertex,
            fragment: program.fragment,
            constants: program.constants.clone(),
            raster,
            layout,
        };
        let pipeline = self
            .pipelines
            .render(key.clone(), |device, layout, module| create(device, layout, module, &key))?;
        Ok(Bundle { pipeline, groups })
    }

    /// A fragment pass of `program` over the textures of the output ports `targets` (at most
    /// [`MAX_SCREEN_TARGETS`], in location order); `owned` are the pass's own bindings, beside
    /// its ports and the scene's.
    pub fn screen(
        &mut self,
        io: &mut Io,
        name: &'static str,
        program: Program,
        targets: &[&str],
        vertices: u32,
        owned: &[(&str, Bound)],
    ) -> Result<Screen, RenderError> {
        let mut formats: ScreenTargets = [None; MAX_SCREEN_TARGETS];
        let mut views = Vec::with_capacity(targets.len());
        for (i, target) in targets.iter().enumerate() {
            let texture = io.texture(target)?;
            *formats.get_mut(i).ok_or_else(|| {
                RenderError::Binding(format!("{name}: more than {MAX_SCREEN_TARGETS} colour targets"))
            })? = Some(texture.format());
            views.push(texture.create_view(&Default::default()));
        }
        let bound = self.render_pipeline(
            io,
            &program,
            Raster::Screen(formats),
            owned,
            |device, layout, module, key| {
                crate::pipelines::screen_pipeline(device, layout, module, key, formats)
            },
        )?;
        Ok(Screen { name, pipeline: bound.pipeline, groups: bound.groups, targets: views, vertices })
    }

    /// One compute dispatch step of `entry`.
    pub fn compute_step(
        &mut self,
        io: &mut Io,
        shader: &'static str,
        entry: &'static str,
        constants: Constants,
        workgroups: [u32; 3],
    ) -> Result<ComputeStep, RenderError> {
        let (layout, groups) = self.resolve(io, shader, &[entry], Stages::Compute, &[])?;
        let pipeline = self.pipelines.compute(ComputeKey { shader, entry, constants, layout })?;
        Ok(ComputeStep { pipeline, groups, workgroups })
    }

    /// Override constants of the shading code: light count and stall.
    pub fn shading_constants(&self, stalled: bool) -> Constants {
        let stall = if stalled { self.stall_iterations } else { 0 };
        Constants::new().with("LIGHT_COUNT", self.scene.light_count).with("STALL_ITERATIONS", stall)
    }
}

/// The ports through which shading reads a frame: the G-buffer and, in scenes with
/// shadow-casting lights, the shadow cubes. `lib/gbuffer.wgsl` and `lib/shadows.wgsl` bind them.
pub(crate) fn shading_inputs(shadows: Option<Resource>) -> Vec<Port> {
    shading_inputs_of(1, shadows)
}

/// [`shading_inputs`] with the G-buffer of `samples` per texel (`shaders/msaa.wgsl` binds the
/// multisampled one).
pub(crate) fn shading_inputs_of(samples: u32, shadows: Option<Resource>) -> Vec<Port> {
    let mut ports: Vec<Port> =
        gbuffer::outputs(samples).into_iter().map(|p| Port { access: Access::Loaded, ..p }).collect();
    ports.extend(shadows.map(|resource| Port::new(shadow::CUBES, resource, Access::Loaded)));
    ports
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

/// A fragment shader run on `targets` over the triangles of `vertices` vertices that the
/// pipeline's vertex shader makes: 3 for the fullscreen triangle. Whatever it covers it
/// overwrites, and the rest is never read.
#[derive(Debug)]
pub(crate) struct Screen {
    pub name: &'static str,
    pub pipeline: wgpu::RenderPipeline,
    pub groups: Vec<(u32, wgpu::BindGroup)>,
    pub targets: Vec<wgpu::TextureView>,
    pub vertices: u32,
}

impl Pass for Screen {
    fn name(&self) -> &'static str {
        self.name
    }

    fn encode(&self, encoder: &mut wgpu::CommandEncoder) {
        // A fixed array rather than a vector: this runs for every pass of every frame.
        let attachments: [Option<wgpu::RenderPassColorAttachment>; MAX_SCREEN_TARGETS] =
            std::array::from_fn(|i| {
                self.targets.get(i).map(|view| wgpu::RenderPassColorAttachment {
                    view,
                    depth_slice: None,
                    resolve_target: None,
                    // Old contents are never read: `Load` costs nothing on lavapipe where
                    // `Clear` would fill the whole target first.
                    ops: wgpu::Operations { load: wgpu::LoadOp::Load, store: wgpu::StoreOp::Store },
                })
            });
        let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some(self.name),
            color_attachments: &attachments[..self.targets.len()],
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
