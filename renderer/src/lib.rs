//! The GPU side of aabench: a Vulkan device (lavapipe on CI machines), scenes imported from
//! glTF, an enlarged G-buffer, deferred shading, brute-force reference supersampling and
//! adaptive supersampling (Holländer, Boubekeur & Eisemann 2013).
//!
//! The renderer knows nothing of manifests, baselines or reports: the runner turns those into
//! a [`Scene`](scene::Scene), [`Lighting`](scene::Lighting) and [`RenderSettings`], asks a
//! [`SceneRenderer`] to [`prepare`](SceneRenderer::prepare) each [`Mode`], times its frames and
//! reads back its images.

pub mod adaptive;
mod bindings;
pub mod color;
pub mod frame;
pub mod gpu;
pub mod graph;
pub mod mode;
mod passes;
mod pipelines;
mod render;
pub mod scene;
pub mod shaders;

pub use adaptive::{AdaptiveSettings, ExtraSamples, Reconstruction};
pub use color::ColorSettings;
pub use gpu::{Gpu, PlatformInfo};
pub use mode::{Metrics, Mode, Technique};
pub use passes::gbuffer::BACKGROUND_MATERIAL;
pub use render::{
    DisplayImage, FrameImages, FrameTiming, GBufferImages, PassTime, PreparedMode, SceneRenderer,
    ShadowDepths, Truth,
};

use std::path::PathBuf;

/// What a scene is rendered with, besides its geometry and lights.
#[derive(Debug, Clone, PartialEq)]
pub struct RenderSettings {
    /// Output resolution; the G-buffer of an M×M mode is M·width × M·height.
    pub width: u32,
    pub height: u32,
    /// Dependent ALU iterations per shaded sample in `-stalled` modes.
    pub stall_iterations: u32,
    pub adaptive: AdaptiveSettings,
    /// From linear HDR to the display image: tonemap (HDR scenes), transfer, dither, bits.
    pub color: ColorSettings,
}

/// The longest stall honoured: lavapipe ends a shader invocation's loops after 65 535
/// iterations in all, and the stall loop takes 16 steps per iteration (plus up to 15 single
/// steps), which leaves room for the shader's light and shadow loops.
pub const MAX_STALL_ITERATIONS: u32 = 1_000_000;

/// The longest stall that `ExtraSamples::Loop` honours at M×M: its gather shades up to M²
/// samples in one invocation, and lavapipe's limit covers all their loops together (allowing
/// each sample 320 iterations of light and shadow loops beside the stall's). 54 880 at 4×4.
pub fn loop_stall_limit(m: u32) -> u32 {
    16 * (60_000 / (m * m).max(1)).saturating_sub(320)
}

#[derive(Debug, thiserror::Error)]
pub enum RenderError {
    #[error("{}", gpu::INSTALL_HINT)]
    NoAdapter,
    #[error("device error: {0}")]
    Device(String),
    #[error("GPU validation error: {0}")]
    Validation(String),
    #[error("{0}")]
    Shader(String),
    #[error("{}: {message}", path.display())]
    Scene { path: PathBuf, message: String },
    #[error("a {width}×{height} target exceeds the device's limit of {limit} texels per side")]
    TooLarge { width: u32, height: u32, limit: u32 },
    #[error("{0}")]
    Limit(String),
    /// A frame's pass graph does not compile.
    #[error("pass graph: {0}")]
    Graph(#[from] graph::GraphError),
    /// A colour-pipeline parameter that cannot make a display image.
    #[error("colour pipeline: {0}")]
    Color(#[from] color::ColorError),
    /// A shader's bindings do not match the resources offered for them.
    #[error("bindings: {0}")]
    Binding(String),
    #[error("{}: {source}", path.display())]
    Io { path: PathBuf, source: std::io::Error },
    /// Work given a way to stop (the ground truth's tiles) was asked to stop.
    #[error("stopped on request after {done} of {of} tiles")]
    Stopped { done: usize, of: usize },
}
