//! What `compare` is asked: the run's processes, the base build's, the baselines, and the
//! fresh processes that confirm a time regression.

use super::verdict::FailOn;
use crate::baseline::BaselineSet;
use crate::record::RunRecord;

/// What `compare` decides on.
#[derive(Debug, Clone, Copy)]
pub struct Request<'a> {
    /// The run under test: one process, or several of one build (the first gives the quality
    /// numbers; their images must agree; their frames are pooled for time against baselines).
    pub runs: &'a [RunRecord],
    /// Processes of the base build measured on the same machine in the same job, ideally
    /// alternating with `runs`: time is gated against them with the process as the unit.
    pub base: &'a [RunRecord],
    pub baselines: &'a BaselineSet,
    pub fail_on: FailOn,
    /// Missing baselines, scenes, modes and platforms, runs that timed alone and unfinished
    /// runs are reported, not failed (a first bless, an exploratory compare).
    pub lenient: bool,
    /// Fresh processes that measured again the scenes whose time regressed against `base`.
    pub confirmation: Option<Confirmation<'a>>,
}

/// A second, independent measurement of the scenes whose time regressed against the base
/// build: fresh processes of both builds, alternating, run after a first compare named them.
///
/// Each time check is a 95% interval, and a gate makes some two thousand of them, strongly
/// correlated within a scene (a process that lands slow on a scene lands slow on its modes). A
/// false alarm somewhere is then no rare event: a gate of code that cannot have changed a
/// scene's time once failed on it, every mode of that scene 10–30% slower in the head's six
/// processes. A regression found in the first processes therefore stands only when the fresh
/// processes, decided on their own, find it again; the chance that both are false is the
/// product of two small ones, while a real slowdown is found again as a matter of course.
#[derive(Debug, Clone, Copy)]
pub struct Confirmation<'a> {
    pub runs: &'a [RunRecord],
    pub base: &'a [RunRecord],
}
