//! The passes of an adaptive mode (see `shaders/adaptive.wgsl` for the algorithm's outline).

use wgpu::util::DeviceExt;

use super::{Compute, ComputeStep, Pass, Screen, Slot, bind_group, bind_group_layout};
use crate::RenderError;
use crate::adaptive::{ExtraSamples, sample_order};
use crate::mode::{Metrics, Mode};
use crate::passes::gbuffer::GBuffer;
use crate::render::{HDR_FORMAT, SceneRenderer, view};

/// Per-pixel sample counts, 1…16.
const COUNT_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::R8Uint;

pub(crate) struct AdaptivePasses {
    pub passes: Vec<Box<dyn Pass>>,
    pub sample_counts: wgpu::Texture,
    /// S, the shade-first image.
    pub first: wgpu::Texture,
}

pub(crate) fn build(
    r: &mut SceneRenderer,
    gbuffer: &GBuffer,
    mode: Mode,
    metrics: Metrics,
    hdr: &wgpu::Texture,
) -> Result<AdaptivePasses, RenderError> {
    let m = mode.m;
    let (width, height) = (r.settings.width, r.settings.height);
    let settings = r.settings.adaptive;
    let loop_shading = settings.extra_samples == ExtraSamples::Loop;

    // Each entry point gets the constants it reads, so pipelines that do not depend on the
    // metric (S, the scans, the extra samples) are shared by every metric variant.
    let shading = r.shading_constants(mode.stalled);
    let window = [("M", f64::from(m))];
    let metric = [
        ("C_DEPTH", f64::from(settings.c_depth)),
        ("C_NORMAL", f64::from(settings.c_normal)),
        ("C_SHADING", f64::from(settings.c_shading)),
        ("T_MIN", f64::from(settings.t_min)),
        ("T_EDGE", f64::from(settings.t_edge)),
        ("USE_GEOMETRY", flag(metrics != Metrics::Shading)),
        ("USE_SHADING", flag(metrics != Metrics::Geometry)),
        ("FORCE_ALL", flag(settings.force_all_samples)),
    ];

    let device = r.gpu.device.clone();
    let order = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
        label: Some("sample order"),
        contents: bytemuck::cast_slice(&sample_order(m)),
        usage: wgpu::BufferUsages::STORAGE,
    });
    let first = r.target("adaptive.first", width, height, HDR_FORMAT);
    let counts = r.target("adaptive.counts", width, height, COUNT_FORMAT);
    let scene = (r.scene.layout.clone(), r.scene.group.clone());
    let gb = (r.gbuffer_layout.clone(), gbuffer.group.clone());
    let mut passes: Vec<Box<dyn Pass>> = Vec::new();

    // S: one sample per pixel.
    let layout = bind_group_layout(&device, "shade_first", &[Slot::StorageRead]);
    let group = bind_group(&device, "shade_first", &layout, &[order.as_entire_binding()]);
    let pipeline = r.fullscreen_pipeline(
        "adaptive.wgsl",
        "shade_first",
        &[&shading[..], &window].concat(),
        [Some(&scene.0), Some(&gb.0), Some(&layout)],
        HDR_FORMAT,
    )?;
    passes.push(Box::new(screen("shade_first", pipeline, &scene.1, &gb.1, group, &first, 3)));

    // The sample count per pixel.
    let layout = bind_group_layout(&device, "evaluate", &[Slot::Texture]);
    let first_view = view(&first);
    let group = bind_group(&device, "evaluate", &layout, &[wgpu::BindingResource::TextureView(&first_view)]);
    let pipeline = r.fullscreen_pipeline(
        "adaptive.wgsl",
        "evaluate",
        &[&window[..], &metric].concat(),
        [Some(&scene.0), Some(&gb.0), Some(&layout)],
        COUNT_FORMAT,
    )?;
    passes.push(Box::new(screen("evaluate", pipeline, &scene.1, &gb.1, group, &counts, 3)));

    let counts_view = view(&counts);
    let list = if loop_shading {
        None
    } else {
        Some(compact_list(r, &device, m, &shading, &window, &order, &counts_view, &scene, &gb, &mut passes)?)
    };

    // The average of S and the extra samples. The loop variant shades them here and reads no
    // list, but the bindings stay: a placeholder stands in for the list's buffers and target.
    let (pixel_offsets, extra, compact_width) = match &list {
        Some(list) => (list.pixel_offsets.clone(), list.extra.clone(), list.width),
        None => (r.buffer("adaptive.placeholder", 4), r.target("adaptive.placeholder", 1, 1, HDR_FORMAT), 4),
    };
    let layout = bind_group_layout(
        &device,
        "gather",
        &[Slot::StorageRead, Slot::Texture, Slot::UintTexture, Slot::StorageRead, Slot::Texture],
    );
    let extra_view = view(&extra);
    let group = bind_group(
        &device,
        "gather",
        &layout,
        &[
            order.as_entire_binding(),
            wgpu::BindingResource::TextureView(&first_view),
            wgpu::BindingResource::TextureView(&counts_view),
            pixel_offsets.as_entire_binding(),
            wgpu::BindingResource::TextureView(&extra_view),
        ],
    );
    let gather_constants = [
        &shading[..],
        &window,
        &[("LOOP_SHADING", flag(loop_shading)), ("COMPACT_WIDTH", f64::from(compact_width))],
    ]
    .concat();
    let pipeline = r.fullscreen_pipeline(
        "adaptive.wgsl",
        "gather",
        &gather_constants,
        [Some(&scene.0), Some(&gb.0), Some(&layout)],
        HDR_FORMAT,
    )?;
    passes.push(Box::new(screen("gather", pipeline, &scene.1, &gb.1, group, hdr, 3)));

    Ok(AdaptivePasses { passes, sample_counts: counts, first })
}

/// The list of samples to shade after S, and its compact target.
struct CompactList {
    pixel_offsets: wgpu::Buffer,
    extra: wgpu::Texture,
    width: u32,
}

/// Adds the `compact` (prefix sums) and `shade_extra` passes.
#[allow(clippy::too_many_arguments)]
fn compact_list(
    r: &mut SceneRenderer,
    device: &wgpu::Device,
    m: u32,
    shading: &[(&'static str, f64)],
    window: &[(&'static str, f64)],
    order: &wgpu::Buffer,
    counts_view: &wgpu::TextureView,
    scene: &(wgpu::BindGroupLayout, wgpu::BindGroup),
    gb: &(wgpu::BindGroupLayout, wgpu::BindGroup),
    passes: &mut Vec<Box<dyn Pass>>,
) -> Result<CompactList, RenderError> {
    let (width, height) = (r.settings.width, r.settings.height);
    let limits = r.gpu.device.limits();
    // At most M² entries per pixel (a full window shades rank 0 again), in 4×4 blocks of a
    // target as wide as the device allows.
    let capacity = u64::from(m * m) * u64::from(width) * u64::from(height);
    let compact_width = limits.max_texture_dimension_2d / 4 * 4;
    let compact_height = capacity.div_ceil(4 * u64::from(compact_width)).max(1) * 4;
    let entries_bytes = 4 * capacity;
    let max_binding = limits.max_storage_buffer_binding_size.min(limits.max_buffer_size);
    if compact_height > u64::from(limits.max_texture_dimension_2d) || entries_bytes > max_binding {
        return Err(RenderError::Limit(format!(
            "adaptive-{m}x{m} at {width}×{height} lists up to {capacity} samples ({entries_bytes} bytes), \
             more than this device holds in one buffer ({max_binding} bytes) or target; lower the resolution"
        )));
    }
    let compact_height = compact_height as u32;
    let compact =
        [("COMPACT_WIDTH", f64::from(compact_width)), ("COMPACT_HEIGHT", f64::from(compact_height))];
    let extra = r.target("adaptive.extra", compact_width, compact_height, HDR_FORMAT);
    let row_offsets = r.buffer("adaptive.row_offsets", 4 * u64::from(height));
    let totals = r.buffer("adaptive.totals", 4);
    let pixel_offsets = r.buffer("adaptive.pixel_offsets", 4 * u64::from(width) * u64::from(height));
    let entries = r.buffer("adaptive.entries", entries_bytes);

    let layout = bind_group_layout(
        device,
        "compact",
        &[
            Slot::UintTexture,
            Slot::StorageReadWrite,
            Slot::StorageReadWrite,
            Slot::StorageReadWrite,
            Slot::StorageReadWrite,
        ],
    );
    let group = bind_group(
        device,
        "compact",
        &layout,
        &[
            wgpu::BindingResource::TextureView(counts_view),
            row_offsets.as_entire_binding(),
            totals.as_entire_binding(),
            pixel_offsets.as_entire_binding(),
            entries.as_entire_binding(),
        ],
    );
    let row_groups = height.div_ceil(64);
    let mut steps = Vec::new();
    for (entry, workgroups) in [("scan_rows", row_groups), ("scan_total", 1), ("emit", row_groups)] {
        let pipeline = r.compute_pipeline("adaptive.wgsl", entry, window, [None, None, Some(&layout)])?;
        steps.push(ComputeStep {
            pipeline,
            groups: vec![(2, group.clone())],
            workgroups: [workgroups, 1, 1],
        });
    }
    passes.push(Box::new(Compute { name: "compact", steps }));

    // One fragment per listed sample.
    let layout = bind_group_layout(
        device,
        "shade_extra",
        &[Slot::StorageRead, Slot::UintTexture, Slot::StorageRead, Slot::StorageRead],
    );
    let group = bind_group(
        device,
        "shade_extra",
        &layout,
        &[
            order.as_entire_binding(),
            wgpu::BindingResource::TextureView(counts_view),
            entries.as_entire_binding(),
            totals.as_entire_binding(),
        ],
    );
    let pipeline = r.screen_pipeline(
        "adaptive.wgsl",
        "compact_rows",
        "shade_extra",
        &[shading, window, &compact].concat(),
        [Some(&scene.0), Some(&gb.0), Some(&layout)],
        HDR_FORMAT,
    )?;
    passes.push(Box::new(screen("shade_extra", pipeline, &scene.1, &gb.1, group, &extra, 6)));
    Ok(CompactList { pixel_offsets, extra, width: compact_width })
}

fn flag(value: bool) -> f64 {
    if value { 1.0 } else { 0.0 }
}

fn screen(
    name: &'static str,
    pipeline: wgpu::RenderPipeline,
    scene: &wgpu::BindGroup,
    gbuffer: &wgpu::BindGroup,
    inputs: wgpu::BindGroup,
    target: &wgpu::Texture,
    vertices: u32,
) -> Screen {
    Screen {
        name,
        pipeline,
        groups: vec![(0, scene.clone()), (1, gbuffer.clone()), (2, inputs)],
        target: view(target),
        vertices,
    }
}
