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
    /// Fresh processes that measured again the scenes of the times suspect against `base`.
    pub confirmation: Option<Confirmation<'a>>,
}

/// A second measurement of the scenes whose time is suspect against the base build (regressed,
/// or noisy with its interval above 0): fresh processes of both builds, alternating, run after
/// a first compare named them.
///
/// Each time check is a 95% interval, and a gate makes some two thousand of them, strongly
/// correlated within a scene (a process that lands slow on a scene lands slow on its modes). A
/// false alarm somewhere is then no rare event: a gate of code that cannot have changed a
/// scene's time once failed on it, every mode of that scene 10–30% slower in the head's six
/// processes. A suspect therefore is regressed only when the fresh processes estimate it past
/// the tolerance on their own, and all the processes together put its whole interval past it:
/// the fresh processes must point the same way, and the eight a side narrow the interval that
/// four a side left across the tolerance.
#[derive(Debug, Clone, Copy)]
pub struct Confirmation<'a> {
    pub runs: &'a [RunRecord],
    pub base: &'a [RunRecord],
}
