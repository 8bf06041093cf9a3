//! The gate's vocabulary: what a check decides (`Outcome`), what it compares with (`Against`),
//! one check of a metric of a mode of a scene (`Check`), and the verdict of a run (`Verdict`).

use std::collections::BTreeMap;
use std::path::PathBuf;

use serde::{Deserialize, Serialize};

pub const VERDICT_SCHEMA: &str = "aabench.verdict/1";

/// Coverage of the intervals that time verdicts are decided on.
pub const CONFIDENCE: f64 = 0.95;

#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Outcome {
    /// Worse beyond the tolerance (for times: the whole interval past the threshold).
    Regressed,
    /// The mode failed in the run, or the run cannot be compared with the baseline.
    Failed,
    /// Better beyond the tolerance.
    Improved,
    /// A time whose estimate is past the threshold but whose interval is not wholly: the
    /// repetitions cannot tell; or a time suspect against the base build that fresh processes
    /// did not find again. Reported, not failed.
    Noisy,
    /// A time with too little evidence to decide either way: fewer than [`MIN_FRAMES`] frames
    /// on a side, or fewer than [`MIN_PROCESSES`] processes of the base or the head. Reported,
    /// never failed, never called unchanged.
    Insufficient,
    /// In the baseline, not in the run: fails unless `--lenient`.
    Missing,
    /// In the run, not in the baseline.
    New,
    Unchanged,
}

impl Outcome {
    pub const ALL: [Outcome; 8] = [
        Outcome::Regressed,
        Outcome::Failed,
        Outcome::Improved,
        Outcome::Noisy,
        Outcome::Insufficient,
        Outcome::Missing,
        Outcome::New,
        Outcome::Unchanged,
    ];

    /// True for the outcomes that make `compare` exit 1 when their check is gated.
    /// How many of `checks` have each outcome.
    pub fn count(checks: &[Check]) -> BTreeMap<Outcome, usize> {
        let mut counts = BTreeMap::new();
        for check in checks {
            *counts.entry(check.outcome).or_insert(0) += 1;
        }
        counts
    }

    pub fn fails(self) -> bool {
        matches!(self, Outcome::Regressed | Outcome::Failed | Outcome::Missing)
    }

    pub fn name(self) -> &'static str {
        match self {
            Outcome::Regressed => "regressed",
            Outcome::Failed => "failed",
            Outcome::Improved => "improved",
            Outcome::Noisy => "noisy",
            Outcome::Insufficient => "insufficient",
            Outcome::Missing => "missing",
            Outcome::New => "new",
            Outcome::Unchanged => "unchanged",
        }
    }
}

/// Which checks may fail the verdict.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, clap::ValueEnum)]
#[serde(rename_all = "lowercase")]
pub enum FailOn {
    /// Quality and status always; time against the base build's processes (`--base-runs`)
    /// when given, else against the committed baselines only on the machine that blessed them
    /// (same platform key, CPU identity and calibration): relative costs shift between CPUs,
    /// so another machine's times can only inform.
    Auto,
    /// Every check: quality and time, whichever machine blessed the baselines.
    All,
    /// Quality and status only; time verdicts are reported but fail nothing.
    Quality,
}

/// Whether `metric` is a time, decided on intervals and gated by `--fail-on`.
pub(super) fn is_time_metric(metric: &str) -> bool {
    crate::record::vocabulary::TimeMetric::of(metric).is_some()
}

pub use crate::manifest::tolerances::MIN_FRAMES;

/// The fewest processes on each side from which a time check against the base build is
/// decided: four against four is the smallest design whose Moses interval reaches 95%
/// (97.1%; three against three reaches only 90%).
pub const MIN_PROCESSES: usize = 4;

/// What a time check is measured against.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Against {
    /// The committed baselines (quality, presence, and time on the machine that blessed them).
    #[default]
    Baseline,
    /// The base build, run in alternating processes on the same machine in the same job.
    Base,
}

/// One decision: a metric of a mode of a scene.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Check {
    /// The scene; `*` for the run as a whole, or for a time pooled over the scenes.
    pub scene: String,
    pub mode: String,
    /// `status`, `psnr_vs_truth`, `mse_vs_truth`, `flip_vs_truth`, `ssim_vs_truth`,
    /// `psnr_vs_reference`, `mse_vs_reference`, `shaded_percent`, `sample_histogram`, `output_hash`,
    /// `sequence_psnr_vs_truth`, `sequence_flip_vs_truth`, `flicker`, `instability`, `sequence_shaded_percent`,
    /// `relative_time`, `time_vs_reference`, `frame_time`, `pass_time:<pass>` (against the base
    /// build); `run` for the run as a whole.
    pub metric: String,
    /// What the check compares with: the committed baseline or the base build's processes.
    #[serde(default)]
    pub against: Against,
    pub outcome: Outcome,
    pub baseline: Option<f64>,
    pub current: Option<f64>,
    /// current − baseline in `unit`; for `relative` metrics (current − baseline) / baseline.
    pub change: Option<f64>,
    /// For times: the confidence interval of the relative change.
    pub interval: Option<[f64; 2]>,
    /// The tolerance that decided, in `unit`.
    pub threshold: Option<f64>,
    /// `dB`, `relative`, `percentage points`, `total variation`.
    pub unit: String,
    /// One sentence with the numbers, for people.
    pub detail: String,
    /// False when `--fail-on`, `--lenient` or another machine exempts this check: its outcome
    /// is reported, not failed.
    pub gated: bool,
}

impl Check {
    /// True when this check makes `compare` exit 1.
    pub fn fails(&self) -> bool {
        self.gated && self.outcome.fails()
    }

    /// A check with no numbers yet, gated, against the baseline.
    pub(super) fn new(scene: &str, mode: &str, metric: &str, outcome: Outcome, detail: String) -> Check {
        Check {
            scene: scene.into(),
            mode: mode.into(),
            metric: metric.into(),
            against: Against::Baseline,
            outcome,
            baseline: None,
            current: None,
            change: None,
            interval: None,
            threshold: None,
            unit: String::new(),
            detail,
            gated: true,
        }
    }

    /// A check of the run as a whole (`scene` and `mode` `*`).
    pub(super) fn of_run(outcome: Outcome, detail: String) -> Check {
        Check::new("*", "*", "run", outcome, detail)
    }
}

/// Every check of a run against its baselines.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Verdict {
    pub schema: String,
    pub run_id: String,
    /// Every process of the run under test (the first, `run_id`, gives the quality numbers).
    #[serde(default)]
    pub run_ids: Vec<String>,
    /// The base build's processes that time was gated against, if any.
    #[serde(default)]
    pub base_run_ids: Vec<String>,
    /// Fresh processes of the run's build and of the base build that measured again the scenes
    /// whose time regressed against the base (see [`Confirmation`](super::request::Confirmation)), if any.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub confirm_run_ids: Vec<String>,
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub confirm_base_run_ids: Vec<String>,
    /// The manifests of the scenes of the times suspect against the base build (regressed, or
    /// noisy with the interval above 0; a pooled suspect names every scene it drew on), not yet
    /// measured again: `ci/gate.sh` runs them in fresh processes and compares once more.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub to_confirm: Vec<String>,
    pub tier: String,
    pub run_platform: String,
    /// The baselines' folder, or `None` when there were none for the tier.
    pub baseline_dir: Option<PathBuf>,
    pub baseline_platform: Option<String>,
    pub same_platform: bool,
    /// True when the run's machine is the one that blessed the baselines (platform key, CPU
    /// identity and calibration agree).
    #[serde(default)]
    pub same_machine: bool,
    pub fail_on: FailOn,
    /// True when `--lenient` made missing baselines, scenes and modes informational.
    #[serde(default)]
    pub lenient: bool,
    /// True when a gated check regressed or failed: `compare` exits 1.
    pub regressed: bool,
    pub counts: BTreeMap<Outcome, usize>,
    /// Facts about the comparison as a whole (another platform, changed inputs, …).
    pub notes: Vec<String>,
    pub checks: Vec<Check>,
    /// The run's build (`run.json`'s `build`) and the base build's, where they are known.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub build: Option<String>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub base_build: Option<String>,
    /// Where the run is one shard of a suite: which one, and what `aabench merge-verdicts`
    /// needs to check that the shards together compared every baseline.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub shard: Option<ShardScope>,
}

/// The scenes one shard's verdict covers, and the scenes the baselines hold.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct ShardScope {
    /// 1-based.
    pub index: u32,
    pub count: u32,
    /// The scenes of the shard's run.
    pub scenes: Vec<String>,
    /// Every scene the baselines of the tier hold, the other shards' included.
    pub baseline_scenes: Vec<String>,
    /// Per baseline, its scene and when and from which runs it was blessed: which baselines
    /// these are, wherever their folder lies (absent in verdicts from before).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub baselines_blessed: Vec<String>,
}
