//! The recipe of a frame: which passes a (scene, mode) pair runs, how their ports connect, and
//! which outputs are read back. Built from what the scene needs, so a scene without
//! shadow-casting lights has no shadow pass and no cube, and only adaptive modes evaluate.

use crate::adaptive::{Counts, ExtraSamples, Reconstruction};
use crate::graph::{Dims, Graph, Output, PassId, Plan};
use crate::mode::{Mode, Technique};
use crate::passes::Node;
use crate::passes::adaptive::{
    self as adaptive_passes, CompactNode, EvaluateNode, Extra, GatherNode, List, ShadeExtraNode,
    ShadeFirstNode,
};
use crate::passes::display::DisplayNode;
use crate::passes::fxaa::FxaaNode;
use crate::passes::gbuffer::{self, GBufferNode, MSAA_SAMPLES};
use crate::passes::keep::KeepNode;
use crate::passes::msaa::{MsaaNode, MsaaStep};
use crate::passes::shade::{ResolveNode, ShadeNode};
use crate::passes::shadow::{self, ShadowNode};
use crate::passes::smaa::{SmaaNode, SmaaStep};
use crate::passes::taa::{self, TaaNode};
use crate::passes::tonemap::TonemapNode;
use crate::scene::{Lighting, Scene, ShadowCubes};
use crate::shaders::Features;
use crate::{error::RenderError, settings::RenderSettings};

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
        ] {
            f.write_str(if used { what } else { "" })?;
        }
        Ok(())
    }
}

pub(crate) type FrameGraph = Graph<Box<dyn Node>>;

fn add(graph: &mut FrameGraph, node: impl Node + 'static) -> PassId {
    graph.add(node.decl(), Box::new(node))
}

/// The passes that every shading pass reads from.
#[derive(Debug, Clone, Copy)]
struct Sources {
    gbuffer: PassId,
    /// The G-buffer's ports: single- or multisampled.
    ports: [&'static str; 4],
    shadow: Option<PassId>,
}

impl Sources {
    fn feed(self, graph: &mut FrameGraph, pass: PassId) {
        graph.connect_all(self.gbuffer, pass, &self.ports);
        if let Some(shadow) = self.shadow {
            graph.connect(shadow, shadow::CUBES, pass, shadow::CUBES);
        }
    }
}

/// The graph of `mode`'s frame for a scene with `needs`. `limits` bound the adaptive list.
pub(crate) fn frame_graph(
    needs: &SceneNeeds,
    mode: Mode,
    settings: &RenderSettings,
    limits: &wgpu::Limits,
) -> Result<FrameGraph, RenderError> {
    let mut g = FrameGraph::new();
    let cubes = needs.shadows.map(|c| shadow::cubes(c.lights, c.resolution));
    // Shadows first: nothing in the frame depends on the order beyond that, and it keeps the
    // passes that every mode shares at the front.
    let shadow = cubes.map(|cubes| add(&mut g, ShadowNode { cubes }));
    if let Some(shadow) = shadow {
        g.retain(shadow, shadow::CUBES, Output::ShadowCubes);
    }
    let samples = if mode.technique == Technique::Msaa { MSAA_SAMPLES } else { 1 };
    let motion = mode.is_jittered();
    let gbuffer = add(&mut g, GBufferNode { samples, motion });
    if samples == 1 {
        g.retain(gbuffer, gbuffer::NORMAL, Output::GBufferNormal);
        g.retain(gbuffer, gbuffer::DEPTH, Output::GBufferDepth);
    }
    if motion {
        g.retain(gbuffer, gbuffer::MOTION, Output::Motion);
    }
    let sources = Sources { gbuffer, ports: gbuffer::ports(samples), shadow };
    let (m, stalled) = (mode.m, mode.stalled);
    let hdr = match mode.technique {
        Technique::Msaa => {
            let (width, height) = (settings.width, settings.height);
            let [classify, shade_samples, pixels] = [MsaaStep::Classify, MsaaStep::Samples, MsaaStep::Pixels]
                .map(|step| add(&mut g, MsaaNode { step, stalled, shadows: cubes, width, height }));
            for port in [gbuffer::MS_NORMAL, gbuffer::MS_DEPTH] {
                g.connect(gbuffer, port, classify, port);
            }
            for pass in [shade_samples, pixels] {
                sources.feed(&mut g, pass);
                g.connect(classify, "list_words", pass, "list");
            }
            g.connect(classify, "edge_words", pixels, "edges");
            g.connect(shade_samples, "shaded_samples", pixels, "shaded_samples");
            g.retain(pixels, "counts", Output::SampleCounts);
            pixels
        }
        Technique::Deferred | Technique::Fxaa | Technique::Smaa | Technique::Reference | Technique::Taa => {
            let footprint = if mode.is_jittered() { taa::FOOTPRINT } else { 1.0 };
            let shade = add(&mut g, ShadeNode { stalled, shadows: cubes, footprint });
            sources.feed(&mut g, shade);
            match mode.technique {
                Technique::Reference => {
                    let resolve = add(&mut g, ResolveNode { m });
                    g.connect(shade, "color", resolve, "supersampled");
                    resolve
                }
                Technique::Taa => {
                    let taa = add(&mut g, TaaNode);
                    g.connect(shade, "color", taa, "current");
                    g.connect_all(gbuffer, taa, &[gbuffer::MOTION, gbuffer::DEPTH]);
                    let keep = add(&mut g, taa::keep_history());
                    g.connect(taa, "history_next", keep, "history_next");
                    g.carry(keep, "history", taa, "history");
                    taa
                }
                _ => shade,
            }
        }
        Technique::Adaptive(metrics, reconstruction, counts) => {
            let coverage = reconstruction == Reconstruction::Coverage;
            let first = add(&mut g, ShadeFirstNode { m, stalled, reconstruction, shadows: cubes });
            sources.feed(&mut g, first);
            g.retain(first, "first", Output::First);
            let textured = needs.features.textured;
            let evaluate_node = EvaluateNode {
                m,
                metrics,
                textured,
                reconstruction,
                settings: settings.adaptive,
                tonemap: settings.color.tonemap,
                counts,
            };
            let reads = evaluate_node.gbuffer_reads();
            let evaluate = add(&mut g, evaluate_node);
            g.connect_all(gbuffer, evaluate, reads);
            g.connect(first, "first", evaluate, "first");
            g.retain(evaluate, "counts", Output::SampleCounts);
            if counts == Counts::Stable {
                let keep = add(
                    &mut g,
                    KeepNode {
                        name: "count_history",
                        next: "count_history_next",
                        kept: "count_history",
                        resource: adaptive_passes::count_history(),
                    },
                );
                g.connect(evaluate, "count_history_next", keep, "count_history_next");
                g.carry(keep, "count_history", evaluate, "count_history");
            }
            // `-coverage` reads its samples' slopes from the list, which the loop has no room for.
            let extra = match settings.adaptive.extra_samples {
                ExtraSamples::Loop if !coverage => Extra::Loop { stalled, shadows: cubes },
                ExtraSamples::Loop | ExtraSamples::Compact => {
                    Extra::List(List::new(m, settings.width, settings.height, limits)?)
                }
            };
            let list = match extra {
                Extra::List(list) => Some(list),
                Extra::Loop { .. } => None,
            };
            let gather = add(&mut g, GatherNode { m, extra, reconstruction });
            g.connect(first, "first", gather, "first");
            g.connect(evaluate, "counts", gather, "counts");
            match list {
                None => sources.feed(&mut g, gather),
                Some(list) => {
                    let compact = add(&mut g, CompactNode { m, reconstruction, list });
                    g.connect(evaluate, "counts", compact, "counts");
                    let extra =
                        add(&mut g, ShadeExtraNode { m, stalled, reconstruction, list, shadows: cubes });
                    sources.feed(&mut g, extra);
                    g.connect(compact, "entries", extra, "list_entries");
                    g.connect(compact, "totals", extra, "list_totals");
                    g.connect(compact, "pixel_offsets", gather, "list_offsets");
                    g.connect(extra, "extra", gather, "extra_samples");
                    if coverage {
                        for pass in [compact, extra, gather] {
                            g.connect(evaluate, "groups", pass, "groups");
                        }
                        g.connect(first, "first_slope", gather, "first_slope");
                        g.connect(extra, "extra_slope", gather, "extra_slopes");
                        g.connect_all(gbuffer, gather, &gbuffer::PORTS);
                    }
                }
            }
            gather
        }
    };
    g.retain(hdr, "color", Output::Hdr);
    add_display(&mut g, hdr, mode, settings);
    Ok(g)
}

/// The colour end of a frame: the tonemap pass in an HDR scene, the display encoding, and in
/// FXAA and SMAA modes their passes on the encoded image.
fn add_display(g: &mut FrameGraph, hdr: PassId, mode: Mode, settings: &RenderSettings) {
    let color = &settings.color;
    let bits = color.bits;
    let (linear, port) = match color.tonemap {
        Some(tonemap) => {
            let tonemap = add(g, TonemapNode { tonemap });
            g.connect(hdr, "color", tonemap, "hdr");
            (tonemap, "tonemapped")
        }
        None => (hdr, "color"),
    };
    let display = add(g, DisplayNode { expose: color.tonemap.is_none(), bits });
    g.connect(linear, port, display, "linear");
    let last = match mode.technique {
        Technique::Fxaa => {
            let fxaa = add(g, FxaaNode { bits });
            g.connect(display, "display", fxaa, "encoded");
            fxaa
        }
        Technique::Smaa => {
            let (width, height) = (settings.width, settings.height);
            let [edges, weights, blend] = [SmaaStep::Edges, SmaaStep::Weights, SmaaStep::Blend]
                .map(|step| add(g, SmaaNode { step, bits, width, height }));
            g.connect(display, "display", edges, "encoded");
            g.connect(display, "display", blend, "encoded");
            for pass in [weights, blend] {
                g.connect(edges, "edge_words", pass, "edges");
                g.connect(edges, "list_words", pass, "list");
            }
            g.connect(weights, "blend_weights", blend, "blend_weights");
            blend
        }
        _ => display,
    };
    g.retain(last, "display", Output::Display);
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
