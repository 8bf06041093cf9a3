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

/// Vertex entry points and their vertex counts: one triangle over the whole target, or a
/// rectangle over the rows of the compact target that hold list entries.
const FULLSCREEN: (&str, u32) = ("fullscreen", 3);
const COMPACT_ROWS: (&str, u32) = ("compact_rows", 6);

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
    let device = r.gpu.device.clone();
    let first = r.target("adaptive.first", width, height, HDR_FORMAT);
    let counts = r.target("adaptive.counts", width, height, COUNT_FORMAT);
    let shared = Shared {
        scene: (r.scene.layout.clone(), r.scene.group.clone()),
        gbuffer: (r.gbuffer_layout.clone(), gbuffer.group.clone()),
        order: device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("sample order"),
            contents: bytemuck::cast_slice(&sample_order(m)),
            usage: wgpu::BufferUsages::STORAGE,
        }),
        counts: view(&counts),
        shading: r.shading_constants(mode.stalled),
        window: [("M", f64::from(m))],
    };
    let mut passes: Vec<Box<dyn Pass>> = Vec::new();

    // S: one sample per pixel.
    let layout = bind_group_layout(&device, "shade_first", &[Slot::StorageRead]);
    let group = bind_group(&device, "shade_first", &layout, &[shared.order.as_entire_binding()]);
    let constants = [&shared.shading[..], &shared.window].concat();
    passes.push(Box::new(shared.pass(r, "shade_first", FULLSCREEN, &constants, (&layout, group), &first)?));

    // The sample count per pixel. Only this pass depends on the metric, so the others are
    // shared by every metric variant (each entry point gets just the constants it reads).
    let layout = bind_group_layout(&device, "evaluate", &[Slot::Texture]);
    let first_view = view(&first);
    let group = bind_group(&device, "evaluate", &layout, &[wgpu::BindingResource::TextureView(&first_view)]);
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
    let constants = [&shared.window[..], &metric].concat();
    passes.push(Box::new(shared.pass(r, "evaluate", FULLSCREEN, &constants, (&layout, group), &counts)?));

    // The average of S and the extra samples. The loop variant shades them in the gather and
    // reads no list, but the bindings stay: a placeholder stands in for the list.
    let list = if loop_shading { None } else { Some(compact_list(r, &shared, m, &mut passes)?) };
    let (pixel_offsets, extra, compact_width) = match list {
        Some(list) => (list.pixel_offsets, list.extra, list.width),
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
            shared.order.as_entire_binding(),
            wgpu::BindingResource::TextureView(&first_view),
            wgpu::BindingResource::TextureView(&shared.counts),
            pixel_offsets.as_entire_binding(),
            wgpu::BindingResource::TextureView(&extra_view),
        ],
    );
    let list_constants = [("LOOP_SHADING", flag(loop_shading)), ("COMPACT_WIDTH", f64::from(compact_width))];
    let constants = [&shared.shading[..], &shared.window, &list_constants].concat();
    passes.push(Box::new(shared.pass(r, "gather", FULLSCREEN, &constants, (&layout, group), hdr)?));

    Ok(AdaptivePasses { passes, sample_counts: counts, first })
}

/// What the adaptive passes share: the scene and G-buffer groups (0 and 1), the sample order,
/// the count map, and the shading and window constants.
struct Shared {
    scene: (wgpu::BindGroupLayout, wgpu::BindGroup),
    gbuffer: (wgpu::BindGroupLayout, wgpu::BindGroup),
    order: wgpu::Buffer,
    counts: wgpu::TextureView,
    shading: Vec<(&'static str, f64)>,
    window: [(&'static str, f64); 1],
}

impl Shared {
    /// The fragment pass named after its entry point `entry` in adaptive.wgsl, run over
    /// `target` with groups 0 and 1 and its own `inputs` as group 2.
    fn pass(
        &self,
        r: &mut SceneRenderer,
        entry: &'static str,
        (vertex, vertices): (&str, u32),
        constants: &[(&str, f64)],
        inputs: (&wgpu::BindGroupLayout, wgpu::BindGroup),
        target: &wgpu::Texture,
    ) -> Result<Screen, RenderError> {
        let groups = [Some(&self.scene.0), Some(&self.gbuffer.0), Some(inputs.0)];
        let pipeline =
            r.screen_pipeline("adaptive.wgsl", vertex, entry, constants, groups, target.format())?;
        Ok(Screen {
            name: entry,
            pipeline,
            groups: vec![(0, self.scene.1.clone()), (1, self.gbuffer.1.clone()), (2, inputs.1)],
            target: view(target),
            vertices,
        })
    }
}

/// The list of samples to shade after S, and its compact target.
struct CompactList {
    pixel_offsets: wgpu::Buffer,
    extra: wgpu::Texture,
    width: u32,
}

/// Adds the `compact` (prefix sums) and `shade_extra` passes.
fn compact_list(
    r: &mut SceneRenderer,
    shared: &Shared,
    m: u32,
    passes: &mut Vec<Box<dyn Pass>>,
) -> Result<CompactList, RenderError> {
    let (width, height) = (r.settings.width, r.settings.height);
    let device = r.gpu.device.clone();
    let limits = device.limits();
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
    let extra = r.target("adaptive.extra", compact_width, compact_height, HDR_FORMAT);
    let row_offsets = r.buffer("adaptive.row_offsets", 4 * u64::from(height));
    let totals = r.buffer("adaptive.totals", 4);
    let pixel_offsets = r.buffer("adaptive.pixel_offsets", 4 * u64::from(width) * u64::from(height));
    let entries = r.buffer("adaptive.entries", entries_bytes);

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
            wgpu::BindingResource::TextureView(&shared.counts),
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
            r.compute_pipeline("adaptive.wgsl", entry, &shared.window, [None, None, Some(&layout)])?;
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
            shared.order.as_entire_binding(),
            wgpu::BindingResource::TextureView(&shared.counts),
            entries.as_entire_binding(),
            totals.as_entire_binding(),
        ],
    );
    let size = [("COMPACT_WIDTH", f64::from(compact_width)), ("COMPACT_HEIGHT", f64::from(compact_height))];
    let constants = [&shared.shading[..], &shared.window, &size].concat();
    passes.push(Box::new(shared.pass(
        r,
        "shade_extra",
        COMPACT_ROWS,
        &constants,
        (&layout, group),
        &extra,
    )?));
    Ok(CompactList { pixel_offsets, extra, width: compact_width })
}

fn flag(value: bool) -> f64 {
    if value { 1.0 } else { 0.0 }
}
