//! What the metric refuses, each by a variant that names the cause.

/// What the metric refuses.
#[derive(Debug, thiserror::Error, PartialEq)]
pub enum Error {
    #[error("unknown display model `{0}` (the reference's display_models.json names them)")]
    UnknownDisplay(String),
    #[error("display model `{name}`: {feature} is not supported")]
    UnsupportedDisplay { name: String, feature: String },
    #[error("a frame of {width}×{height} needs {expected} RGB values, got {got}")]
    FrameSize { width: usize, height: usize, expected: usize, got: usize },
    #[error("an image of {width}×{height} is too small: the metric needs at least 4×4 pixels")]
    TooSmall { width: usize, height: usize },
    #[error("frames a second must be a finite number above 0, got {0}")]
    FrameRate(f64),
    #[error(
        "a video needs at least 2 frames and one after its warm-up of {warmup}, got {frames} \
         (score a single frame as an image)"
    )]
    TooFewFrames { frames: usize, warmup: usize },
}
