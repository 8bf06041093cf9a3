//! aabench's runner: manifests, run plans, the GPU worker, timing, metrics and run records.
//! The `aabench` binary (main.rs) calls [`cli::main`].

// The rooms, in the order the data of `aabench run` flows through them, then the commands that
// read its record. Each room's `mod.rs` says what its files hold.
pub mod baseline;
pub mod cli;
pub mod compare;
pub mod files;
pub mod manifest;
pub mod measure;
pub mod plan;
pub mod record;
pub mod report;
pub mod run;

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
