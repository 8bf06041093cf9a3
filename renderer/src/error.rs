//! Everything that can go wrong in the renderer, one variant per kind of cause.

use std::path::PathBuf;

use crate::{color, graph};

/// The hint printed when no Vulkan adapter exists. It is the one line a user needs.
pub const INSTALL_HINT: &str = "no Vulkan adapter found: install Mesa's lavapipe \
     (Debian/Ubuntu: `sudo apt-get install mesa-vulkan-drivers`) and run again";

#[derive(Debug, thiserror::Error)]
pub enum RenderError {
    #[error("{INSTALL_HINT}")]
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
    /// A camera the renderer cannot draw through, or cannot move to.
    #[error("camera: {0}")]
    Camera(String),
    /// A pose the renderer cannot take: no animation plays, or a time is not finite.
    #[error("pose: {0}")]
    Pose(String),
    /// A shader's bindings do not match the resources offered for them.
    #[error("bindings: {0}")]
    Binding(String),
    #[error("{}: {source}", path.display())]
    Io { path: PathBuf, source: std::io::Error },
    /// Work given a way to stop (the ground truth's tiles) was asked to stop.
    #[error("stopped on request after {done} of {of} tiles")]
    Stopped { done: usize, of: usize },
}
