//! The recipe of a frame: which passes a (scene, mode) pair runs, how their ports connect, and
//! which outputs are read back. Built from what the scene needs, so a scene without
//! shadow-casting lights has no shadow pass and no cube; each technique adds its own passes
//! (`technique/`).

use crate::color::ColorSettings;
use crate::error::RenderError;
use crate::graph::{Dims, Output, PassId, Plan};
use crate::mode::Mode;
use crate::passes::display::DisplayNode;
use crate::passes::gbuffer::{self, GBufferNode};
use crate::passes::shadow::{self, ShadowNode};
use crate::passes::tonemap::TonemapNode;
use crate::scene::{Lighting, Scene, ShadowCubes};
use crate::settings::RenderSettings;
use crate::shaders::Features;
use crate::technique::{self, Frame, FrameGraph, Sources, Technique, add};

/// What a scene asks of its frames, besides its mode.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct SceneNeeds {
    /// How the scene's shaders are composed: only what its materials, textures and lights use.
    pub features: Features,
    /// Shadow-casting lights: the shadow pass and its cube array exist.
    pub shadows: Option<ShadowCubes>,
}

impl SceneNeeds {
    pub fn of(scene: &Scene, lighting: &Lighting) -> SceneNeeds {
        let lights = &lighting.lights[..lighting.lights.len().min(crate::scene::MAX_LIGHTS)];
        let shadows = ShadowCubes::of(lights);
        let any = |test: &dyn Fn(&crate::scene::Material) -> bool| scene.materials.iter().any(test);
        let features = Features {
            textured: scene.is_textured(),
            shadows: shadows.is_some(),
            light_kinds: lights.iter().any(|l| l.kind != crate::scene::LightKind::Point),
            normal_maps: !scene.tangents.is_empty() && any(&|m| m.normal_texture.is_some()),
            emissive: any(&|m| m.emissive.iter().any(|&c| c > 0.0)),
            occlusion: any(&|m| m.occlusion_texture.is_some()),
            metallic_roughness: any(&|m| m.metallic_roughness_texture.is_some()),
            texture_transform: any(&|m| m.textures().any(|t| !t.transform.is_identity())),
            texture_pages: scene.is_textured()
                && crate::scene::textures::Layout::of(&scene.textures).is_packed(),
            moving: scene.playing_tracks().is_some(),
        };
        SceneNeeds { features, shadows }
    }
}

impl std::fmt::Display for SceneNeeds {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let features = self.features;
        f.write_str(if features.textured { "textured" } else { "untextured" })?;
        match self.shadows {
            Some(c) => write!(f, ", {} shadow cube(s) of {}²", c.lights, c.resolution),
            None => f.write_str(", no shadow-casting light"),
        }?;
        for (used, what) in [
            (features.light_kinds, ", spot or directional lights"),
            (features.normal_maps, ", normal maps"),
            (features.emissive, ", emission"),
            (features.occlusion, ", occlusion"),
            (features.texture_transform, ", texture transforms"),
            (features.texture_pages, ", textures packed in pages"),
            (features.metallic_roughness, ", metallic-roughness textures"),
            (features.moving, ", moving objects"),
        ] {
            f.write_str(if used { what } else { "" })?;
        }
        Ok(())
    }
}

/// The graph of `mode`'s frame for a scene with `needs`: the shadow cubes (where the scene has
/// shadow-casting lights), the G-buffer, the technique's passes to the HDR image, the colour
/// end, and the technique's passes on the display image. `limits` bound the lists that some
/// techniques build.
pub(crate) fn frame_graph(
    needs: &SceneNeeds,
    mode: Mode,
    settings: &RenderSettings,
    limits: &wgpu::Limits,
) -> Result<FrameGraph, RenderError> {
    let mut frame = begin(needs, mode.technique, settings, limits);
    let hdr = technique::add_shading(&mut frame, mode.technique, mode.m, mode.stalled)?;
    frame.graph.retain(hdr, "color", Output::Hdr);
    let display = add_color_end(&mut frame.graph, hdr, &settings.color);
    let last = technique::add_post_process(&mut frame, mode.technique, display);
    frame.graph.retain(last, "display", Output::Display);
    Ok(frame.graph)
}

/// The graph of the scene's geometry probe: the G-buffer alone, one unjittered sample per pixel
/// with the motion of each sample's point since the frame before. The truth has no G-buffer of
/// its own at the display's resolution; a sequence follows the truth's pixels along this one.
pub(crate) fn geometry_graph() -> FrameGraph {
    let mut g = FrameGraph::new();
    let gbuffer = add(&mut g, GBufferNode { samples: 1, motion: true });
    g.retain(gbuffer, gbuffer::NORMAL, Output::GBufferNormal);
    g.retain(gbuffer, gbuffer::DEPTH, Output::GBufferDepth);
    g.retain(gbuffer, gbuffer::MOTION, Output::Motion);
    g
}

/// A frame's first passes, which every technique shares: the shadow cubes and the G-buffer
/// (multisampled for MSAA, with motion vectors under TAA).
fn begin<'a>(
    needs: &SceneNeeds,
    technique: Technique,
    settings: &'a RenderSettings,
    limits: &'a wgpu::Limits,
) -> Frame<'a> {
    let mut g = FrameGraph::new();
    let cubes = needs.shadows.map(|c| shadow::cubes(c.lights, c.resolution));
    // Shadows first: nothing in the frame depends on the order beyond that, and it keeps the
    // passes that every mode shares at the front.
    let shadow = cubes.map(|cubes| add(&mut g, ShadowNode { cubes }));
    if let Some(shadow) = shadow {
        g.retain(shadow, shadow::CUBES, Output::ShadowCubes);
    }
    // TAA reprojects by motion vectors always; a `-stable` mode where objects move (a camera's
    // motion alone it follows through the frame uniforms).
    let moving = needs.features.moving;
    let motion = technique.is_jittered() || (moving && technique.carries_history());
    let samples = technique.gbuffer_samples();
    let gbuffer = add(&mut g, GBufferNode { samples, motion });
    if samples == 1 {
        g.retain(gbuffer, gbuffer::NORMAL, Output::GBufferNormal);
        g.retain(gbuffer, gbuffer::DEPTH, Output::GBufferDepth);
    }
    if motion {
        g.retain(gbuffer, gbuffer::MOTION, Output::Motion);
    }
    Frame {
        graph: g,
        sources: Sources { gbuffer, ports: gbuffer::ports(samples), shadow },
        cubes,
        width: settings.width,
        height: settings.height,
        textured: needs.features.textured,
        moving,
        color: &settings.color,
        adaptive: &settings.adaptive,
        limits,
    }
}

/// The colour end of a frame: the tonemap pass in an HDR scene, then the display encoding.
fn add_color_end(g: &mut FrameGraph, hdr: PassId, color: &ColorSettings) -> PassId {
    let (linear, port) = match color.tonemap {
        Some(tonemap) => {
            let tonemap = add(g, TonemapNode { tonemap });
            g.connect(hdr, "color", tonemap, "hdr");
            (tonemap, "tonemapped")
        }
        None => (hdr, "color"),
    };
    let display = add(g, DisplayNode { expose: color.tonemap.is_none(), bits: color.bits });
    g.connect(linear, port, display, "linear");
    display
}

/// The dimensions a mode's graph resolves against.
pub(crate) fn dims(settings: &RenderSettings, mode: Mode) -> Dims {
    Dims { width: settings.width, height: settings.height, m: mode.m }
}

/// A compiled graph as the runner records it: the passes in order and the allocations, with
/// their bytes against one allocation per output and against the lower bound.
#[derive(Debug, Clone, PartialEq)]
pub struct GraphSummary {
    pub passes: Vec<String>,
    pub allocations: Vec<AllocationSummary>,
    pub allocated_bytes: u64,
    pub one_per_output_bytes: u64,
    pub lower_bound_bytes: u64,
}

#[derive(Debug, Clone, PartialEq)]
pub struct AllocationSummary {
    /// Format and size, e.g. `Rgba16Float 512×384`, or `buffer 16 B`.
    pub descriptor: String,
    pub bytes: u64,
    /// The ports whose resources it holds, in order: `pass.port`.
    pub holds: Vec<String>,
}

impl GraphSummary {
    pub(crate) fn of(plan: &Plan) -> GraphSummary {
        let allocations = plan
            .allocation
            .physical
            .iter()
            .map(|p| AllocationSummary {
                descriptor: p.desc.to_string(),
                bytes: p.desc.bytes(),
                holds: p
                    .resources
                    .iter()
                    .map(|&r| {
                        let writer = plan.resources[r].writer;
                        format!("{}.{}", plan.names[writer.pass], writer.port)
                    })
                    .collect(),
            })
            .collect();
        GraphSummary {
            passes: plan.pass_names().iter().map(|s| s.to_string()).collect(),
            allocations,
            allocated_bytes: plan.allocated_bytes(),
            one_per_output_bytes: plan.one_per_output_bytes(),
            lower_bound_bytes: plan.lower_bound_bytes(),
        }
    }
}

/// `mode`'s graph for a scene with `needs`, compiled and printed: the text table, or Graphviz
/// when `dot`. Needs no device beyond its limits.
pub fn describe(
    needs: &SceneNeeds,
    mode: Mode,
    settings: &RenderSettings,
    limits: &wgpu::Limits,
    dot: bool,
) -> Result<String, RenderError> {
    let graph = frame_graph(needs, mode, settings, limits)?;
    let plan = graph.compile(dims(settings, mode))?;
    Ok(if dot { graph.dot(&plan) } else { graph.describe(&plan) })
}
