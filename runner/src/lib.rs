//! aabench's runner: manifests, run plans, the GPU worker, timing, metrics and run records.
//! The `aabench` binary (main.rs) is a thin CLI over this library.

pub mod baseline;
pub mod compare;
pub mod flicker;
pub mod front;
pub mod fs;
pub mod gate;
pub mod images;
pub mod inputs;
pub mod json;
pub mod machine;
pub mod manifest;
pub mod markup;
pub mod merge;
pub mod metrics;
pub mod motion;
pub mod moved;
pub mod perceptual;
pub mod plan;
pub mod progress;
pub mod record;
pub mod repetitions;
pub mod report;
pub mod run;
pub mod scenes;
pub mod spool;
pub mod stats;
pub mod temporal;
pub mod truth;
pub mod vocabulary;
pub mod worker;

/// Exit codes, one meaning each: 0 success; 1 `compare` found a regression; 2 the command could
/// not do its work (bad arguments, as clap also reports them, unreadable input, no device); 3 a
/// run finished, but some scene or mode failed (run.json says which and why), or a bless wrote
/// the ok scenes and skipped the failed ones; 130 interrupted
/// by SIGINT, SIGTERM or SIGHUP (what was measured is recorded).
pub mod exit {
    pub const OK: u8 = 0;
    pub const REGRESSION: u8 = 1;
    pub const ERROR: u8 = 2;
    pub const SCENE_FAILED: u8 = 3;
    pub const INTERRUPTED: u8 = 130;
}
