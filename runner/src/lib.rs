//! aabench's runner: manifests, run plans, the GPU worker, timing, metrics and run records.
//! The `aabench` binary (main.rs) is a thin CLI over this library.

pub mod baseline;
pub mod compare;
pub mod gate;
pub mod images;
pub mod inputs;
pub mod json;
pub mod manifest;
pub mod merge;
pub mod metrics;
pub mod plan;
pub mod progress;
pub mod record;
pub mod report;
pub mod run;
pub mod scenes;
pub mod stats;
pub mod truth;
pub mod worker;

/// Exit codes: 0 success, 1 a regression was found, 2 an error (bad input, no device, a failed
/// scene), 130 interrupted.
pub mod exit {
    pub const OK: u8 = 0;
    pub const REGRESSION: u8 = 1;
    pub const ERROR: u8 = 2;
    pub const INTERRUPTED: u8 = 130;
}
