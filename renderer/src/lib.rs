//! The GPU side of aabench: a Vulkan device (lavapipe on CI machines), scenes imported from
//! glTF, an enlarged G-buffer, deferred shading, brute-force reference supersampling and
//! adaptive supersampling (Holländer, Boubekeur & Eisemann 2013), and the anti-aliasing it is
//! compared with (FXAA, SMAA, 4× MSAA, TAA), each technique in a room of its own
//! (`technique/`).
//!
//! The renderer knows nothing of manifests, baselines or reports: the runner turns those into
//! a [`Scene`](scene::Scene), [`Lighting`](scene::Lighting) and [`RenderSettings`], asks a
//! [`SceneRenderer`] to [`prepare`](SceneRenderer::prepare) each [`Mode`], times its frames and
//! reads back its images.

mod bindings;
pub mod color;
mod error;
pub mod frame;
pub mod gpu;
pub mod graph;
pub mod mode;
mod passes;
mod pipelines;
mod render;
pub mod scene;
mod settings;
pub mod shaders;
pub mod technique;

pub use color::ColorSettings;
pub use error::RenderError;
pub use gpu::{Gpu, PlatformInfo};
pub use mode::Mode;
pub use passes::gbuffer::BACKGROUND_MATERIAL;
pub use render::{
    DisplayImage, FrameImages, FrameTiming, GBufferImages, PassTime, PreparedMode, SceneRenderer,
    ShadowDepths, Truth, truth_in_one_piece,
};
pub use settings::{MAX_STALL_ITERATIONS, RenderSettings, loop_stall_limit};
pub use technique::adaptive::{
    AdaptiveSettings, Counts, ExtraSamples, Metrics, Reconstruction, StableCounts,
};
pub use technique::{Technique, adaptive, smaa, taa};
