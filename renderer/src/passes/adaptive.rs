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
/// Width of the compact target that holds one extra sample per texel.
const COMPACT_WIDTH: u32 = 2048;

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

    // The list holds at most M² samples per pixel (a full window shades rank 0 again).
    let capacity = u64::from(m * m) * u64::from(width) * u64::from(height);
    let limit = r.gpu.device.limits().max_texture_dimension_2d;
    let compact_width = COMPACT_WIDTH.min(limit);
    // Whole 4×4 blocks (see compact_texel in adaptive.wgsl).
    let compact_height = capacity.div_ceil(4 * u64::from(compact_width)).max(1) * 4;
    if compact_height > u64::from(limit) {
        return Err(RenderError::TooLarge { width: compact_width, height: compact_height as u32, limit });
    }
    let compact_height = compact_height as u32;

    let mut constants = r.shading_constants(mode.stalled);
    constants.extend([
        ("M", f64::from(m)),
        ("C_DEPTH", f64::from(settings.c_depth)),
        ("C_NORMAL", f64::from(settings.c_normal)),
        ("C_SHADING", f64::from(settings.c_shading)),
        ("T_MIN", f64::from(settings.t_min)),
        ("T_EDGE", f64::from(settings.t_edge)),
        ("USE_GEOMETRY", flag(metrics != Metrics::Shading)),
        ("USE_SHADING", flag(metrics != Metrics::Geometry)),
        ("FORCE_ALL", flag(settings.force_all_samples)),
        ("LOOP_SHADING", flag(loop_shading)),
        ("COMPACT_WIDTH", f64::from(compact_width)),
        ("COMPACT_HEIGHT", f64::from(compact_height)),
    ]);

    let device = r.gpu.device.clone();
    let order = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
        label: Some("sample order"),
        contents: bytemuck::cast_slice(&sample_order(m)),
        usage: wgpu::BufferUsages::STORAGE,
    });
    let first = r.target("adaptive.first", width, height, HDR_FORMAT);
    let counts = r.target("adaptive.counts", width, height, COUNT_FORMAT);
    let extra = r.target("adaptive.extra", compact_width, compact_height, HDR_FORMAT);
    let row_offsets = r.buffer("adaptive.row_offsets", 4 * u64::from(height));
    let totals = r.buffer("adaptive.totals", 4);
    let pixel_offsets = r.buffer("adaptive.pixel_offsets", 4 * u64::from(width) * u64::from(height));
    let entries = r.buffer("adaptive.entries", 4 * capacity);

    let scene = (r.scene.layout.clone(), r.scene.group.clone());
    let gb = (r.gbuffer_layout.clone(), gbuffer.group.clone());
    let mut passes: Vec<Box<dyn Pass>> = Vec::new();

    // S: one sample per pixel.
    let layout = bind_group_layout(&device, "shade_first", &[Slot::StorageRead]);
    let group = bind_group(&device, "shade_first", &layout, &[order.as_entire_binding()]);
    let pipeline = r.fullscreen_pipeline(
        "adaptive.wgsl",
        "shade_first",
        &constants,
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
        &constants,
        [Some(&scene.0), Some(&gb.0), Some(&layout)],
        COUNT_FORMAT,
    )?;
    passes.push(Box::new(screen("evaluate", pipeline, &scene.1, &gb.1, group, &counts, 3)));

    let counts_view = view(&counts);
    if !loop_shading {
        // The list of extra samples.
        let layout = bind_group_layout(
            &device,
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
            &device,
            "compact",
            &layout,
            &[
                wgpu::BindingResource::TextureView(&counts_view),
                row_offsets.as_entire_binding(),
                totals.as_entire_binding(),
                pixel_offsets.as_entire_binding(),
                entries.as_entire_binding(),
            ],
        );
        let row_groups = height.div_ceil(64);
        let mut steps = Vec::new();
        for (entry, workgroups) in [("scan_rows", row_groups), ("scan_total", 1), ("emit", row_groups)] {
            let pipeline =
                r.compute_pipeline("adaptive.wgsl", entry, &constants, [None, None, Some(&layout)])?;
            steps.push(ComputeStep {
                pipeline,
                groups: vec![(2, group.clone())],
                workgroups: [workgroups, 1, 1],
            });
        }
        passes.push(Box::new(Compute { name: "compact", steps }));

        // One fragment per listed sample.
        let layout = bind_group_layout(
            &device,
            "shade_extra",
            &[Slot::StorageRead, Slot::UintTexture, Slot::StorageRead, Slot::StorageRead],
        );
        let group = bind_group(
            &device,
            "shade_extra",
            &layout,
            &[
                order.as_entire_binding(),
                wgpu::BindingResource::TextureView(&counts_view),
                entries.as_entire_binding(),
                totals.as_entire_binding(),
            ],
        );
        let pipeline = r.screen_pipeline(
            "adaptive.wgsl",
            "compact_rows",
            "shade_extra",
            &constants,
            [Some(&scene.0), Some(&gb.0), Some(&layout)],
            HDR_FORMAT,
        )?;
        passes.push(Box::new(screen("shade_extra", pipeline, &scene.1, &gb.1, group, &extra, 6)));
    }

    // The average of S and the extra samples.
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
    let pipeline = r.fullscreen_pipeline(
        "adaptive.wgsl",
        "gather",
        &constants,
        [Some(&scene.0), Some(&gb.0), Some(&layout)],
        HDR_FORMAT,
    )?;
    passes.push(Box::new(screen("gather", pipeline, &scene.1, &gb.1, group, hdr, 3)));

    Ok(AdaptivePasses { passes, sample_counts: counts, first })
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
