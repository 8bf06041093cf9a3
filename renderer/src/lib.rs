//! The GPU side of aabench: a Vulkan device (lavapipe on CI machines), scenes imported from
//! glTF, an enlarged G-buffer, deferred shading, brute-force reference supersampling and
//! adaptive supersampling (Holländer, Boubekeur & Eisemann 2013).
//!
//! The renderer knows nothing of manifests, baselines or reports: the runner turns those into
//! a [`Scene`](scene::Scene), [`Lighting`](scene::Lighting) and [`RenderSettings`], asks a
//! [`SceneRenderer`] to [`prepare`](SceneRenderer::prepare) each [`Mode`], times its frames and
//! reads back its images.

pub mod adaptive;
pub mod gpu;
pub mod mode;
mod passes;
mod render;
pub mod scene;
pub mod shaders;

pub use adaptive::{AdaptiveSettings, ExtraSamples};
pub use gpu::{Gpu, PlatformInfo};
pub use mode::{Metrics, Mode, Technique};
pub use passes::gbuffer::BACKGROUND_MATERIAL;
pub use render::{
    FrameImages, FrameTiming, GBufferImages, PassTime, PreparedMode, RenderSettings, SceneRenderer, Truth,
};

use std::path::PathBuf;

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
    #[error("{}: {source}", path.display())]
    Io { path: PathBuf, source: std::io::Error },
}
