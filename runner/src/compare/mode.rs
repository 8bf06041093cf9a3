//! One mode of the run against the same mode in its baseline: what its quality checks
//! (`quality.rs`) and time checks (`time.rs`) read.

use super::verdict::{Check, Outcome};
use crate::baseline::{BlessedMode, BlessedProcess};
use crate::manifest::tolerances::Tolerances;
use crate::record::{ModeRecord, SceneRecord};

/// One mode of the run and the same mode in the baseline.
pub(super) struct ModeContext<'a> {
    pub scene: &'a SceneRecord,
    /// The scene in every process of the run: time checks pool their rounds.
    pub processes: &'a [&'a SceneRecord],
    /// The baseline's frame times, one per blessed process: time checks pool their rounds.
    pub blessed: &'a [BlessedProcess<'a>],
    pub mode: &'a ModeRecord,
    /// The mode as blessed: its quality numbers.
    pub old: &'a BlessedMode,
    pub tolerances: Tolerances,
    pub same_platform: bool,
    /// The modes whose geometric mean anchors `relative_time`.
    pub anchor_modes: &'a [&'a str],
}

impl ModeContext<'_> {
    /// A check of this mode's `metric`, gated, against the baseline, its change in `unit`.
    pub fn check(&self, metric: &str, outcome: Outcome, unit: &str, detail: String) -> Check {
        Check { unit: unit.into(), ..Check::new(&self.scene.name, &self.mode.mode, metric, outcome, detail) }
    }
}

/// A relative change as a signed percentage, `+∞` past every number.
pub(super) fn show_percent(fraction: f64) -> String {
    if fraction.is_finite() { format!("{:+.1}%", fraction * 100.0) } else { "+∞".into() }
}
