//! The metric's constants, per scene, and how the extra samples are shaded.

use super::variants::StableCounts;

/// How the extra samples are shaded.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ExtraSamples {
    /// List every (pixel, rank) pair that needs shading with a prefix sum, then shade the list
    /// as one dense fragment per sample and gather per pixel. Costs scale with the samples
    /// shaded, without idle SIMD lanes. The default: fastest on lavapipe (see `docs/design-notes.md`).
    Compact,
    /// Shade a pixel's extra samples in a loop inside its gather invocation, as the paper's
    /// simplest variant does. Neighbours with different counts leave SIMD lanes idle.
    Loop,
}

/// The depth statistic of the geometry metric.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum DepthMetric {
    /// The variance relative to the squared mean depth, `Var(d) / E[d]²`: free of the scene's
    /// unit, so a scene and its copy scaled ×1000 take the same samples. The default.
    Relative,
    /// The variance in view-space units², the paper's literal metric: the same geometry
    /// modelled in millimetres takes 10⁶ times the metric of its copy in metres.
    World,
}

impl DepthMetric {
    /// The default `c_depth` of each: tuned so that the generated metre-scale scenes take
    /// about the samples they took under the world-unit metric (`docs/design-notes.md`).
    pub fn default_c_depth(self) -> f32 {
        match self {
            DepthMetric::Relative => DEFAULT_C_DEPTH_RELATIVE,
            DepthMetric::World => 100.0,
        }
    }
}

/// The relative metric's `c_depth` default (see [`DepthMetric::default_c_depth`]).
pub const DEFAULT_C_DEPTH_RELATIVE: f32 = 10_000.0;

/// The largest metric constant accepted: with depths ≤ 1e12 (the far plane's bound) every
/// product the shader forms stays finite in f32.
pub const MAX_METRIC_CONSTANT: f32 = 1e12;

/// The metric constants (per scene, in the manifest) and test knobs.
///
/// The paper writes k = c · metric with one c per scene. Here the metric is also scaled by the
/// window's sample count: k = c · M² · metric. One set of constants then serves 2×2, 3×3 and
/// 4×4 alike (the paper's c is this c times M²).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct AdaptiveSettings {
    /// Which depth variance the geometry metric takes.
    pub depth_metric: DepthMetric,
    /// Scales the depth variance (relative, or in view-space units²).
    pub c_depth: f32,
    /// Scales the normal cone sqrt(1 − min |n̄·n|).
    pub c_normal: f32,
    /// Scales the luminance range r of the shade-first image.
    pub c_shading: f32,
    /// Scales the luma range by which a penumbra can change S's light inside the pixel
    /// (`-coverage` in scenes with shadows); not held to the thresholds below.
    pub c_shadow: f32,
    /// The range r counts only above max(t_min, l_max · t_edge) (FXAA's two thresholds).
    pub t_min: f32,
    pub t_edge: f32,
    /// Test knob: every pixel gets all M² samples, whatever the metrics say.
    pub force_all_samples: bool,
    pub extra_samples: ExtraSamples,
    /// How `-stable` modes carry counts from frame to frame.
    pub stable: StableCounts,
}

impl Default for AdaptiveSettings {
    fn default() -> Self {
        AdaptiveSettings {
            // Tuned on the generated scenes at 1024×768 (`docs/design-notes.md`).
            depth_metric: DepthMetric::Relative,
            c_depth: DepthMetric::Relative.default_c_depth(),
            c_normal: 1.0,
            c_shading: 2.0,
            c_shadow: 24.0,
            t_min: 1.0 / 32.0,
            t_edge: 1.0 / 8.0,
            force_all_samples: false,
            extra_samples: ExtraSamples::Compact,
            stable: StableCounts::default(),
        }
    }
}
