//! The passes of an adaptive mode (see `shaders/adaptive.wgsl` for the algorithm's outline).

use super::{
    AdaptiveSettings, Counts, DepthMetric, LIST_TEXEL_BITS, Metrics, Reconstruction, STABLE_DEPTH_TOLERANCE,
    SURFACE_COS, SURFACE_GAP, packed_dither_matrix, packed_sample_order, sample_cells,
};
use crate::bindings::Bound;
use crate::color::Tonemap;
use crate::error::RenderError;
use crate::graph::{Access, Extent, PassDecl, Port, Resource};
use crate::passes::tonemap::curve_constants;
use crate::passes::{
    BuildContext, COUNT_FORMAT, Compute, FULLSCREEN, HDR_FORMAT, Io, Node, Pass, Program, gbuffer,
    shading_inputs,
};
use crate::pipelines::Constants;

/// Two rectangles over the blocks of the compact target that hold list entries.
const COMPACT_ROWS: (&str, u32) = ("compact_rows", 12);

const SHADER: &str = "adaptive.wgsl";

fn first() -> Resource {
    Resource::texture(HDR_FORMAT, Extent::Output)
}

fn counts() -> Resource {
    Resource::texture(COUNT_FORMAT, Extent::Output)
}

/// A `-stable` mode's counts kept for the next frame: each pixel's count and the depth of its
/// window's deepest sample (`shaders/adaptive.wgsl`: count_history).
pub(crate) fn count_history() -> Resource {
    Resource::texture(wgpu::TextureFormat::Rg32Float, Extent::Output)
}

/// The `-coverage` variant's map of each pixel's shaded samples and the cells they stand for
/// (`shaders/adaptive.wgsl`: groups).
fn groups() -> Resource {
    Resource::texture(wgpu::TextureFormat::Rgba32Uint, Extent::Output)
}

/// The slope in albedo of the colour beside it (`lib/shading.wgsl`: Lit).
fn first_slope() -> Resource {
    Resource::texture(HDR_FORMAT, Extent::Output)
}

/// The window's side and its dither order.
fn window(m: u32) -> Constants {
    // The dither matrices, and evaluate's depth gathers (two blocks a row), stop at 4.
    debug_assert!((2..=4).contains(&m), "adaptive M = {m}");
    let [low, high] = packed_sample_order(m);
    Constants::new().with("M", m).with("ORDER_LOW", low).with("ORDER_HIGH", high)
}

/// The table of cells that the `-area` and `-cells` variants read: constant data, owned by the
/// pass rather than a frame resource. The passes that can read it bind it in every mode.
fn cells_table(ctx: &mut BuildContext, m: u32) -> [(&'static str, Bound); 1] {
    let cells = || bytemuck::cast_slice(&sample_cells(m)).to_vec();
    [("sample_cells", Bound::Buffer(ctx.pipelines.constant_buffer(("sample cells", m), cells)))]
}

/// Which variant's reading of the list the passes that read it follow: each sample standing
/// for its cell (`-cells`) or for the samples of its surface (`-coverage`).
fn variant_flags(reconstruction: Reconstruction) -> Constants {
    Constants::new()
        .flag("CELLS", reconstruction == Reconstruction::Cells)
        .flag("COVERAGE", reconstruction == Reconstruction::Coverage)
}

/// The list of extra samples: at most M² entries per pixel (a full window shades rank 0
/// again), stored in 4×4 blocks of a target as wide as the device allows.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) struct List {
    pub capacity: u64,
    pub width: u32,
    pub height: u32,
}

impl List {
    /// The list of mode `mode` (its id, for errors) at M = `m` and `[width, height]`, or why
    /// this device cannot hold it.
    pub fn new(
        mode: &str,
        m: u32,
        [width, height]: [u32; 2],
        limits: &wgpu::Limits,
    ) -> Result<List, RenderError> {
        let largest_side = 1u32 << LIST_TEXEL_BITS;
        let side = width.max(height).max(1);
        if u64::from(m) * u64::from(side) > u64::from(largest_side) {
            let fits = (largest_side / side).min(4);
            let largest =
                if fits >= 2 { format!("the largest M that fits is {fits}") } else { "no M fits".into() };
            return Err(RenderError::Limit(format!(
                "{mode} at {width}×{height}: list entries address G-buffer sides up to \
                 {largest_side} texels, so {largest}"
            )));
        }
        let capacity = u64::from(m * m) * u64::from(width) * u64::from(height);
        let compact_width = limits.max_texture_dimension_2d / 4 * 4;
        let compact_height = capacity.div_ceil(4 * u64::from(compact_width)).max(1) * 4;
        let entries_bytes = 4 * capacity;
        let max_binding = limits.max_storage_buffer_binding_size.min(limits.max_buffer_size);
        if compact_height > u64::from(limits.max_texture_dimension_2d) || entries_bytes > max_binding {
            return Err(RenderError::Limit(format!(
                "{mode} at {width}×{height} lists up to {capacity} samples ({entries_bytes} bytes), \
                 more than this device holds in one buffer ({max_binding} bytes) or target; lower the resolution"
            )));
        }
        Ok(List { capacity, width: compact_width, height: compact_height as u32 })
    }

    fn extra(&self) -> Resource {
        Resource::texture(HDR_FORMAT, Extent::Fixed { width: self.width, height: self.height })
    }

    fn constants(&self) -> Constants {
        Constants::new().with("COMPACT_WIDTH", self.width).with("COMPACT_HEIGHT", self.height)
    }
}

fn buffer(bytes: u64) -> Resource {
    // Zero-sized bindings are invalid.
    Resource::Buffer { bytes: bytes.max(16) }
}

/// S: one sample per pixel, at dither rank 0.
#[derive(Debug)]
pub(crate) struct ShadeFirstNode {
    pub m: u32,
    pub stalled: bool,
    /// Under `Cells` and `Coverage`, S at the pixel's centre with the pixel's footprint;
    /// under `Coverage` also its slope in albedo.
    pub reconstruction: Reconstruction,
    pub shadows: Option<Resource>,
}

impl Node for ShadeFirstNode {
    fn decl(&self) -> PassDecl {
        let mut ports = shading_inputs(self.shadows);
        ports.push(Port::new("first", first(), Access::Attachment));
        if self.reconstruction == Reconstruction::Coverage {
            ports.push(Port::new("first_slope", first_slope(), Access::Attachment));
        }
        PassDecl { name: "shade_first", ports }
    }

    fn build(&self, ctx: &mut BuildContext, io: &mut Io) -> Result<Box<dyn Pass>, RenderError> {
        let constants = ctx
            .shading_constants(self.stalled)
            .extend(&window(self.m))
            .extend(&variant_flags(self.reconstruction));
        let (fragment, targets): (_, &[&str]) = match self.reconstruction {
            Reconstruction::Coverage => ("shade_first_coverage", &["first", "first_slope"]),
            _ => ("shade_first", &["first"]),
        };
        let program = Program { shader: SHADER, vertex: FULLSCREEN.0, fragment: Some(fragment), constants };
        let owned = cells_table(ctx, self.m);
        Ok(Box::new(ctx.screen(io, "shade_first", program, targets, FULLSCREEN.1, &owned)?))
    }
}

/// The sample count per pixel. Only this pass depends on the metric, so the others are shared
/// by every metric variant (each entry point gets just the constants it reads).
#[derive(Debug)]
pub(crate) struct EvaluateNode {
    pub m: u32,
    pub metrics: Metrics,
    /// The scene has textures: the shader then reads the G-buffer's UVs (for the texture
    /// detail below, even where it is off).
    pub textured: bool,
    pub reconstruction: Reconstruction,
    pub settings: AdaptiveSettings,
    /// The scene's tonemap, through which the light-aware term reads highlights as the display
    /// will show them (None: exposed and clamped to [0, 1]).
    pub tonemap: Option<Tonemap>,
    /// Under `Stable`, the pass also reads the frame before's counts and writes this frame's.
    pub counts: Counts,
    /// Objects move: under `Stable`, the pass follows each window's nearest sample back by the
    /// G-buffer's motion vectors.
    pub moving: bool,
    /// Lights cast shadows: under `Coverage`, the shading metric also reads S's penumbra.
    pub shadows: bool,
}

impl EvaluateNode {
    /// Whether the shading metric bounds specular highlights from the lights (`-cells` and
    /// `-coverage`).
    fn light_detail(&self) -> bool {
        matches!(self.reconstruction, Reconstruction::Cells | Reconstruction::Coverage)
            && self.metrics != Metrics::Geometry
    }

    /// Whether the pass reads the penumbra rate that S's shading wrote beside its slope
    /// (`-coverage`, in a scene with shadows; the term is compiled in there, though a metric
    /// without shading switches it off).
    pub fn reads_penumbra(&self) -> bool {
        self.reconstruction == Reconstruction::Coverage && self.shadows
    }

    /// Whether the shading metric asks for samples in the penumbrae that S lies in.
    fn shadow_detail(&self) -> bool {
        self.reads_penumbra() && self.metrics != Metrics::Geometry
    }

    /// The G-buffer ports the pass reads: normals and depths; the UVs in a textured scene (for
    /// the texture detail), else at least the UV target's size (`view_ray`, in the light-aware
    /// term and `-coverage`'s grouping). A term switched off by its constant still binds what
    /// it would read.
    pub fn gbuffer_reads(&self) -> &'static [&'static str] {
        if self.textured { &gbuffer::PORTS } else { &[gbuffer::UV, gbuffer::NORMAL, gbuffer::DEPTH] }
    }
}

impl Node for EvaluateNode {
    fn decl(&self) -> PassDecl {
        let mut ports: Vec<Port> = gbuffer::outputs(1)
            .into_iter()
            .filter(|port| self.gbuffer_reads().contains(&port.name))
            .map(|port| Port { access: Access::Loaded, ..port })
            .collect();
        ports.extend([
            Port::new("first", first(), Access::Loaded),
            Port::new("counts", counts(), Access::Attachment),
        ]);
        if self.reconstruction == Reconstruction::Coverage {
            ports.push(Port::new("groups", groups(), Access::Attachment));
        }
        if self.reads_penumbra() {
            ports.push(Port::new("first_slope", first_slope(), Access::Loaded));
        }
        if self.counts == Counts::Stable {
            ports.extend([
                Port::new("count_history", count_history(), Access::Loaded),
                Port::new("count_history_next", count_history(), Access::Attachment),
            ]);
            if self.moving {
                let motion = Resource::texture(gbuffer::MOTION_FORMAT, Extent::GBuffer);
                ports.push(Port::new(gbuffer::MOTION, motion, Access::Loaded));
            }
        }
        PassDecl { name: "evaluate", ports }
    }

    fn build(&self, ctx: &mut BuildContext, io: &mut Io) -> Result<Box<dyn Pass>, RenderError> {
        let s = self.settings;
        let constants = window(self.m)
            .with("C_DEPTH", s.c_depth)
            .flag("RELATIVE_DEPTH", s.depth_metric == DepthMetric::Relative)
            .with("C_NORMAL", s.c_normal)
            .with("C_SHADING", s.c_shading)
            .with("C_SHADOW", s.c_shadow)
            .with("T_MIN", s.t_min)
            .with("T_EDGE", s.t_edge)
            .flag("USE_GEOMETRY", self.metrics != Metrics::Shading)
            .flag("USE_SHADING", self.metrics != Metrics::Geometry)
            .flag("FORCE_ALL", s.force_all_samples)
            // The shading metric counts texture contrast below the pixel's scale under `-cells`;
            // `-coverage` filters textures at the reference's rate instead.
            .flag(
                "TEXTURE_DETAIL",
                self.reconstruction == Reconstruction::Cells && self.metrics != Metrics::Geometry,
            )
            // Both variants also bound specular highlights inside the pixel from the lights.
            .flag("LIGHT_DETAIL", self.light_detail())
            .flag("SHADOW_DETAIL", self.shadow_detail())
            .with("SURFACE_COS", SURFACE_COS)
            .with("SURFACE_GAP", SURFACE_GAP);
        let constants = match self.counts {
            Counts::PerFrame => constants,
            Counts::Stable => constants
                .with("STABLE_HOLD", s.stable.hold_samples(self.m))
                .with("STABLE_DECAY", s.stable.decay)
                .with("STABLE_DEPTH_TOLERANCE", STABLE_DEPTH_TOLERANCE),
        };
        // The light-aware term loops over the lights and maps highlights through the tonemap.
        let constants = match &self.tonemap {
            _ if !self.light_detail() => constants,
            Some(tonemap) => curve_constants(constants.extend(&ctx.shading_constants(false)), tonemap)?,
            None => constants.extend(&ctx.shading_constants(false)),
        };
        let (fragment, targets): (_, &[&str]) = match (self.reconstruction, self.counts) {
            (Reconstruction::Coverage, _) => ("evaluate_coverage", &["counts", "groups"]),
            (_, Counts::Stable) => ("evaluate_stable", &["counts", "count_history_next"]),
            (_, Counts::PerFrame) => ("evaluate", &["counts"]),
        };
        let program = Program { shader: SHADER, vertex: FULLSCREEN.0, fragment: Some(fragment), constants };
        let owned =
            [("texel_sampler", Bound::Sampler { sampler: ctx.pipelines.texel_sampler(), filtering: false })];
        Ok(Box::new(ctx.screen(io, "evaluate", program, targets, FULLSCREEN.1, &owned)?))
    }
}

/// Prefix sums over the counts list every (pixel, rank) still to shade, densely.
#[derive(Debug)]
pub(crate) struct CompactNode {
    pub m: u32,
    /// Under `Cells` and `Coverage`, pixels of more than one sample list their first sample
    /// too; under `Coverage` the listed samples are a pixel's `groups`.
    pub reconstruction: Reconstruction,
    pub list: List,
}

impl Node for CompactNode {
    fn decl(&self) -> PassDecl {
        // Rows and pixels are bounded by the list's capacity over M².
        let pixels = self.list.capacity / u64::from(self.m * self.m);
        let mut ports = vec![
            Port::new("counts", counts(), Access::Loaded),
            // Scratch: each row's offset, read by nothing after this pass.
            Port::new("row_offsets", buffer(4 * pixels), Access::StorageWrite),
            Port::new("totals", buffer(4), Access::StorageWrite),
            Port::new("pixel_offsets", buffer(4 * pixels), Access::StorageWrite),
            Port::new("entries", buffer(4 * self.list.capacity), Access::StorageWrite),
        ];
        if self.reconstruction == Reconstruction::Coverage {
            ports.push(Port::new("groups", groups(), Access::Loaded));
        }
        PassDecl { name: "compact", ports }
    }

    fn build(&self, ctx: &mut BuildContext, io: &mut Io) -> Result<Box<dyn Pass>, RenderError> {
        let rows = io.texture("counts")?.height();
        let row_groups = rows.div_ceil(64);
        let mut steps = Vec::new();
        let emit = if self.reconstruction == Reconstruction::Coverage { "emit_groups" } else { "emit" };
        for (entry, workgroups) in [("scan_rows", row_groups), ("scan_total", 1), (emit, row_groups)] {
            let constants = window(self.m).extend(&variant_flags(self.reconstruction));
            steps.push(ctx.compute_step(io, SHADER, entry, constants, [workgroups, 1, 1])?);
        }
        Ok(Box::new(Compute { name: "compact", steps }))
    }
}

/// One fragment per listed sample, into the compact target.
#[derive(Debug)]
pub(crate) struct ShadeExtraNode {
    pub m: u32,
    pub stalled: bool,
    /// Each sample shaded for its cell (`Cells`) or for the samples it stands for, with its
    /// slope in albedo (`Coverage`).
    pub reconstruction: Reconstruction,
    pub list: List,
    pub shadows: Option<Resource>,
}

impl Node for ShadeExtraNode {
    fn decl(&self) -> PassDecl {
        let mut ports = shading_inputs(self.shadows);
        ports.extend([
            Port::new("list_entries", buffer(4 * self.list.capacity), Access::StorageRead),
            Port::new("list_totals", buffer(4), Access::StorageRead),
            Port::new("extra", self.list.extra(), Access::Attachment),
        ]);
        if self.reconstruction == Reconstruction::Coverage {
            ports.extend([
                Port::new("groups", groups(), Access::Loaded),
                Port::new("extra_slope", self.list.extra(), Access::Attachment),
            ]);
        }
        PassDecl { name: "shade_extra", ports }
    }

    fn build(&self, ctx: &mut BuildContext, io: &mut Io) -> Result<Box<dyn Pass>, RenderError> {
        let [low, high] = packed_dither_matrix(self.m);
        let constants = ctx
            .shading_constants(self.stalled)
            .extend(&window(self.m))
            .extend(&self.list.constants())
            .extend(&variant_flags(self.reconstruction))
            .with("RANK_LOW", low)
            .with("RANK_HIGH", high);
        let (fragment, targets): (_, &[&str]) = match self.reconstruction {
            Reconstruction::Coverage => ("shade_group", &["extra", "extra_slope"]),
            _ => ("shade_extra", &["extra"]),
        };
        let program = Program { shader: SHADER, vertex: COMPACT_ROWS.0, fragment: Some(fragment), constants };
        let owned = cells_table(ctx, self.m);
        Ok(Box::new(ctx.screen(io, "shade_extra", program, targets, COMPACT_ROWS.1, &owned)?))
    }
}

/// Where gather finds a pixel's extra samples.
#[derive(Debug)]
pub(crate) enum Extra {
    /// In the compact target that shade_extra wrote.
    List(List),
    /// Nowhere: gather shades them itself in a loop (the paper's simplest variant).
    Loop { stalled: bool, shadows: Option<Resource> },
}

/// The average of S and the extra samples.
#[derive(Debug)]
pub(crate) struct GatherNode {
    pub m: u32,
    pub extra: Extra,
    pub reconstruction: Reconstruction,
}

impl Node for GatherNode {
    fn decl(&self) -> PassDecl {
        let mut ports =
            vec![Port::new("first", first(), Access::Loaded), Port::new("counts", counts(), Access::Loaded)];
        match &self.extra {
            Extra::List(list) => ports.extend([
                Port::new(
                    "list_offsets",
                    buffer(list.capacity / u64::from(self.m * self.m) * 4),
                    Access::StorageRead,
                ),
                Port::new("extra_samples", list.extra(), Access::Loaded),
            ]),
            Extra::Loop { shadows, .. } => ports.extend(shading_inputs(*shadows)),
        }
        if let (Reconstruction::Coverage, Extra::List(list)) = (self.reconstruction, &self.extra) {
            // The G-buffer for the albedos that a shaded sample's light is carried to.
            ports.extend(shading_inputs(None));
            ports.extend([
                Port::new("groups", groups(), Access::Loaded),
                Port::new("first_slope", first_slope(), Access::Loaded),
                Port::new("extra_slopes", list.extra(), Access::Loaded),
            ]);
        }
        ports.push(Port::new("color", Resource::texture(HDR_FORMAT, Extent::Output), Access::Attachment));
        PassDecl { name: "gather", ports }
    }

    fn build(&self, ctx: &mut BuildContext, io: &mut Io) -> Result<Box<dyn Pass>, RenderError> {
        let (entry, constants) = match &self.extra {
            Extra::List(list) if self.reconstruction == Reconstruction::Coverage => {
                ("gather_coverage", window(self.m).extend(&list.constants()))
            }
            Extra::List(list) => ("gather", window(self.m).extend(&list.constants())),
            Extra::Loop { stalled, .. } => {
                ("gather_loop", ctx.shading_constants(*stalled).extend(&window(self.m)))
            }
        };
        let constants = constants
            .flag("WEIGHTED", self.reconstruction != Reconstruction::Equal)
            .extend(&variant_flags(self.reconstruction));
        let program = Program { shader: SHADER, vertex: FULLSCREEN.0, fragment: Some(entry), constants };
        let owned = cells_table(ctx, self.m);
        Ok(Box::new(ctx.screen(io, "gather", program, &["color"], FULLSCREEN.1, &owned)?))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn list_entries_address_sides_up_to_the_texel_bits() {
        // A device whose targets and buffers are larger than any G-buffer a list can address.
        let limits = wgpu::Limits {
            max_texture_dimension_2d: 1 << 16,
            max_storage_buffer_binding_size: u64::MAX,
            max_buffer_size: u64::MAX,
            ..wgpu::Limits::default()
        };
        assert!(List::new("adaptive-4x4", 4, [4096, 16], &limits).is_ok());
        assert!(List::new("adaptive-2x2", 2, [16, 8192], &limits).is_ok());
        let error = List::new("adaptive-4x4-cells", 4, [4097, 16], &limits).unwrap_err().to_string();
        assert!(error.contains("16384 texels, so the largest M that fits is 3"), "{error}");
        assert!(error.starts_with("adaptive-4x4-cells at 4097×16"), "the mode by its own name: {error}");
        let error = List::new("adaptive-2x2", 2, [16, 8193], &limits).unwrap_err().to_string();
        assert!(error.contains("16384 texels, so no M fits"), "{error}");
        // A list larger than the device's largest buffer names the mode too.
        let small = wgpu::Limits { max_storage_buffer_binding_size: 1 << 27, ..limits };
        let error =
            List::new("adaptive-4x4-coverage-stalled", 4, [4096, 4096], &small).unwrap_err().to_string();
        assert!(error.starts_with("adaptive-4x4-coverage-stalled at 4096×4096 lists up to"), "{error}");
    }
}
