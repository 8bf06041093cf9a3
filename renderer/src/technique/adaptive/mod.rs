//! Adaptive supersampling (Holländer, Boubekeur & Eisemann 2013): the G-buffer at M·w × M·h,
//! one sample per pixel shaded (S), a metric over the G-buffer and S that asks each pixel for
//! 1…M² samples, those shaded, and the pixel reconstructed from them; and the variants beyond
//! the paper (`-area`, `-cells`, `-coverage`, `-stable`) beside it.
//!
//! The algorithm's CPU side is here, device-free: the ordered-dither sample order (`order.rs`),
//! the variants (`variants.rs`), the cells a sample stands for (`cells.rs`), the settings
//! (`settings.rs`) and a CPU twin of the metric that the GPU's `evaluate` pass computes
//! (`metric.rs`), the specification the shader is tested against. The passes are in
//! `passes.rs`, the shaders in `shaders/adaptive.wgsl`.

mod cells;
mod metric;
mod order;
mod passes;
mod settings;
mod variants;

pub use cells::{SampleCell, area_weights, sample_cells};
pub use metric::{
    LumaCross, MetricSet, WindowSample, clamp_count, footprint, geometry_metric, luma_cross, metric_k,
    metric_luma, sample_count, shading_metric,
};
pub use order::{
    DITHER_2, DITHER_3, DITHER_4, LIST_TEXEL_BITS, dither_matrix, packed_dither_matrix, packed_sample_order,
    sample_order,
};
pub use settings::{
    AdaptiveSettings, DEFAULT_C_DEPTH_RELATIVE, DepthMetric, ExtraSamples, MAX_METRIC_CONSTANT,
};
pub use variants::{
    Counts, Reconstruction, STABLE_DECAY, STABLE_DEPTH_TOLERANCE, STABLE_HOLD, SURFACE_COS, SURFACE_GAP,
    StableCounts,
};

use super::Frame;
use crate::error::RenderError;
use crate::graph::{Output, PassId};
use crate::passes::gbuffer;
use crate::passes::keep::KeepNode;
use passes::{CompactNode, EvaluateNode, Extra, GatherNode, List, ShadeExtraNode, ShadeFirstNode};

/// Which of the adaptive metrics decide the sample count (the paper's Fig. 8 ablation).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Metrics {
    /// max(k_d, k_n, k_s): the paper's method.
    Both,
    /// Depth variance and normal cone only.
    Geometry,
    /// Luminance range of the shade-first image only.
    Shading,
}

/// One adaptive mode's choices: its metrics, its reconstruction and where its counts come
/// from. The paper's is `Both`, `Equal`, `PerFrame`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) struct Variant {
    pub metrics: Metrics,
    pub reconstruction: Reconstruction,
    pub counts: Counts,
}

/// The words an adaptive mode id adds after its size for each choice, in id order:
/// `adaptive-2x2-shading-area-stable`.
pub fn id_suffixes(metrics: Metrics, reconstruction: Reconstruction, counts: Counts) -> Vec<&'static str> {
    let metrics = match metrics {
        Metrics::Both => None,
        Metrics::Geometry => Some("geometry"),
        Metrics::Shading => Some("shading"),
    };
    let reconstruction = match reconstruction {
        Reconstruction::Equal => None,
        Reconstruction::Area => Some("area"),
        Reconstruction::Cells => Some("cells"),
        Reconstruction::Coverage => Some("coverage"),
    };
    let counts = (counts == Counts::Stable).then_some("stable");
    [metrics, reconstruction, counts].into_iter().flatten().collect()
}

/// An adaptive mode's id, the one [`crate::Mode`] writes: `adaptive-4x4-cells-stalled`.
pub(crate) fn mode_id(variant: Variant, m: u32, stalled: bool) -> String {
    let Variant { metrics, reconstruction, counts } = variant;
    let words = id_suffixes(metrics, reconstruction, counts).into_iter().chain(stalled.then_some("stalled"));
    std::iter::once(format!("adaptive-{m}x{m}"))
        .chain(words.map(str::to_string))
        .collect::<Vec<_>>()
        .join("-")
}

/// The choices that the words after an adaptive mode id's size name ([`id_suffixes`] read
/// back), or why they name none.
pub fn parse_suffixes(words: &[&str]) -> Result<(Metrics, Reconstruction, Counts), &'static str> {
    let mut rest = words;
    let counts = match rest.split_last() {
        Some((&"stable", before)) => {
            rest = before;
            Counts::Stable
        }
        _ => Counts::PerFrame,
    };
    let reconstruction = match rest.split_last() {
        Some((last, before)) => match *last {
            "area" | "cells" | "coverage" => {
                rest = before;
                match *last {
                    "area" => Reconstruction::Area,
                    "cells" => Reconstruction::Cells,
                    _ => Reconstruction::Coverage,
                }
            }
            _ => Reconstruction::Equal,
        },
        None => Reconstruction::Equal,
    };
    let metrics = match rest {
        [] => Metrics::Both,
        ["geometry"] => Metrics::Geometry,
        ["shading"] => Metrics::Shading,
        _ => return Err("unexpected suffix"),
    };
    if counts == Counts::Stable && reconstruction == Reconstruction::Coverage {
        return Err("`-coverage` picks its samples per surface, not by count: it has no `-stable` variant");
    }
    Ok((metrics, reconstruction, counts))
}

/// An adaptive mode's passes after the G-buffer: S, the metric, the extra samples (listed and
/// shaded, or shaded in gather's loop) and the gather; the pass whose `color` is the HDR image.
pub(crate) fn add(frame: &mut Frame, variant: Variant, m: u32, stalled: bool) -> Result<PassId, RenderError> {
    let Variant { metrics, reconstruction, counts } = variant;
    let (cubes, sources) = (frame.cubes, frame.sources);
    let first = super::add(&mut frame.graph, ShadeFirstNode { m, stalled, reconstruction, shadows: cubes });
    sources.feed(&mut frame.graph, first);
    frame.graph.retain(first, "first", Output::First);
    let evaluate_node = EvaluateNode {
        m,
        metrics,
        textured: frame.textured,
        reconstruction,
        settings: *frame.adaptive,
        tonemap: frame.color.tonemap,
        counts,
        moving: frame.moving,
        shadows: cubes.is_some(),
    };
    let (reads, penumbra) = (evaluate_node.gbuffer_reads(), evaluate_node.reads_penumbra());
    let g = &mut frame.graph;
    let evaluate = super::add(g, evaluate_node);
    g.connect_all(sources.gbuffer, evaluate, reads);
    g.connect(first, "first", evaluate, "first");
    if penumbra {
        g.connect(first, "first_slope", evaluate, "first_slope");
    }
    g.retain(evaluate, "counts", Output::SampleCounts);
    if counts == Counts::Stable {
        if frame.moving {
            frame.graph.connect(sources.gbuffer, gbuffer::MOTION, evaluate, gbuffer::MOTION);
        }
        keep_counts(frame, evaluate);
    }
    // `-coverage` reads its samples' slopes from the list, which the loop has no room for.
    let extra = match frame.adaptive.extra_samples {
        ExtraSamples::Loop if reconstruction != Reconstruction::Coverage => {
            Extra::Loop { stalled, shadows: cubes }
        }
        ExtraSamples::Loop | ExtraSamples::Compact => {
            let id = mode_id(variant, m, stalled);
            Extra::List(List::new(&id, m, [frame.width, frame.height], frame.limits)?)
        }
    };
    let list = match extra {
        Extra::List(list) => Some(list),
        Extra::Loop { .. } => None,
    };
    let gather = super::add(&mut frame.graph, GatherNode { m, extra, reconstruction });
    frame.graph.connect(first, "first", gather, "first");
    frame.graph.connect(evaluate, "counts", gather, "counts");
    match list {
        None => sources.feed(&mut frame.graph, gather),
        Some(list) => add_listed_samples(frame, [first, evaluate, gather], list, variant, m, stalled),
    }
    Ok(gather)
}

/// A `-stable` mode's counts copied into the texture that the next frame's evaluate reads.
fn keep_counts(frame: &mut Frame, evaluate: PassId) {
    let keep = KeepNode {
        name: "count_history",
        next: "count_history_next",
        kept: "count_history",
        resource: passes::count_history(),
    };
    let keep = super::add(&mut frame.graph, keep);
    frame.graph.connect(evaluate, "count_history_next", keep, "count_history_next");
    frame.graph.carry(keep, "count_history", evaluate, "count_history");
}

/// The extra samples listed (compact) and shaded as one dense pass, read by gather.
fn add_listed_samples(
    frame: &mut Frame,
    [first, evaluate, gather]: [PassId; 3],
    list: List,
    variant: Variant,
    m: u32,
    stalled: bool,
) {
    let Variant { reconstruction, .. } = variant;
    let (cubes, sources) = (frame.cubes, frame.sources);
    let g = &mut frame.graph;
    let compact = super::add(g, CompactNode { m, reconstruction, list });
    g.connect(evaluate, "counts", compact, "counts");
    let extra = super::add(g, ShadeExtraNode { m, stalled, reconstruction, list, shadows: cubes });
    sources.feed(g, extra);
    g.connect(compact, "entries", extra, "list_entries");
    g.connect(compact, "totals", extra, "list_totals");
    g.connect(compact, "pixel_offsets", gather, "list_offsets");
    g.connect(extra, "extra", gather, "extra_samples");
    if reconstruction == Reconstruction::Coverage {
        for pass in [compact, extra, gather] {
            g.connect(evaluate, "groups", pass, "groups");
        }
        g.connect(first, "first_slope", gather, "first_slope");
        g.connect(extra, "extra_slope", gather, "extra_slopes");
        g.connect_all(sources.gbuffer, gather, &gbuffer::PORTS);
    }
}
