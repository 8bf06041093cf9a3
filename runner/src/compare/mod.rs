//! The regression gate: a run against its baselines, decided per scene × mode × metric.
//!
//! Quality is nearly deterministic on one platform and is compared number to number within
//! tight tolerances. Time is noisy, so the gate decides on ratios measured inside one run,
//! which travel between processes and machines, with a distribution-free test over the
//! repetitions, and flags a change only when its whole confidence interval is past the
//! threshold. The ratios: each mode against the geometric mean of the scene's other unstalled
//! modes in the same round (`relative_time`), and adaptive-MxM against reference-MxM
//! (`time_vs_reference`). Absolute times are compared too, with a wide threshold, and only on
//! the baseline's own platform.
//!
//! Why not against deferred-1x1, the obvious anchor: measured over four quick-tier processes of
//! 25 repetitions, a mode's ratio to deferred-1x1 moved by up to 19% between processes (p99
//! 18%): one 10–50 ms frame carries drift of its own. Against the round's geometric mean of
//! the other unstalled modes it moved by at most 13.4% (p99 9.3%). The unstalled modes, not all: when
//! the stall grows, every stalled mode should regress and the plain ones stay unchanged,
//! instead of looking faster against an anchor that grew with them. deferred-1x1's ratio is
//! still recorded and shown; the gate uses the steadier anchor.

pub mod outputs;

use std::collections::BTreeMap;
use std::path::PathBuf;

use serde::{Deserialize, Serialize};

use crate::baseline::{Baseline, BaselineSet};
use crate::gate::{QualityTolerances, Tolerances};
use crate::metrics::Quality;
use crate::record::{ModeRecord, RunRecord, SceneRecord, Status};
use crate::stats::Shift;

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
    /// repetitions cannot tell. Reported, not failed.
    Noisy,
    /// In the baseline, not in the run.
    Missing,
    /// In the run, not in the baseline.
    New,
    Unchanged,
}

impl Outcome {
    pub const ALL: [Outcome; 7] = [
        Outcome::Regressed,
        Outcome::Failed,
        Outcome::Improved,
        Outcome::Noisy,
        Outcome::Missing,
        Outcome::New,
        Outcome::Unchanged,
    ];

    /// True for the outcomes that make `compare` exit 1.
    pub fn fails(self) -> bool {
        matches!(self, Outcome::Regressed | Outcome::Failed)
    }

    pub fn name(self) -> &'static str {
        match self {
            Outcome::Regressed => "regressed",
            Outcome::Failed => "failed",
            Outcome::Improved => "improved",
            Outcome::Noisy => "noisy",
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
    /// `all` against baselines of the run's own platform key, `quality` against another's:
    /// relative costs shift between CPUs, so another machine's times can only inform.
    Auto,
    /// Every check: quality and time.
    All,
    /// Quality and status only; time verdicts are reported but fail nothing (for machines
    /// whose timings the baselines cannot speak for, such as shared CI runners).
    Quality,
}

/// The time metrics: noisy, decided on intervals.
const TIME_METRICS: [&str; 3] = ["relative_time", "time_vs_reference", "frame_time"];

/// One decision: a metric of a mode of a scene.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Check {
    pub scene: String,
    pub mode: String,
    /// `status`, `psnr_vs_truth`, `mse_vs_truth`, `psnr_vs_reference`, `mse_vs_reference`,
    /// `shaded_percent`, `sample_histogram`, `output_hash`, `relative_time`,
    /// `time_vs_reference`, `frame_time` (absolute, wide threshold).
    pub metric: String,
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
    /// False when `--fail-on` exempts this check: its outcome is reported, not failed.
    pub gated: bool,
}

impl Check {
    /// True when this check makes `compare` exit 1.
    pub fn fails(&self) -> bool {
        self.gated && self.outcome.fails()
    }
}

/// Every check of a run against its baselines.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Verdict {
    pub schema: String,
    pub run_id: String,
    pub tier: String,
    pub run_platform: String,
    /// The baselines' folder, or `None` when there were none for the tier.
    pub baseline_dir: Option<PathBuf>,
    pub baseline_platform: Option<String>,
    pub same_platform: bool,
    pub fail_on: FailOn,
    /// True when a gated check regressed or failed: `compare` exits 1.
    pub regressed: bool,
    pub counts: BTreeMap<Outcome, usize>,
    /// Facts about the comparison as a whole (another platform, changed inputs, …).
    pub notes: Vec<String>,
    pub checks: Vec<Check>,
}

/// Compares `run` with `baselines`; `fail_on` says which checks may fail it.
pub fn compare(run: &RunRecord, baselines: &BaselineSet, fail_on: FailOn) -> Verdict {
    let fail_on = match fail_on {
        FailOn::Auto if baselines.same_platform => FailOn::All,
        FailOn::Auto => FailOn::Quality,
        chosen => chosen,
    };
    let mut notes = Vec::new();
    match (&baselines.dir, baselines.same_platform) {
        (None, _) => notes.push(format!(
            "no baselines for the {} tier: every mode is new (bless a run to create them)",
            run.tier.name()
        )),
        (Some(_), false) => notes.push(format!(
            "the baselines are of another platform (`{}`; this run: `{}`): quality is compared with the \
             cross-platform tolerances, in-run time ratios as usual, absolute times not at all",
            baselines.platform_key.as_deref().unwrap_or("?"),
            run.platform.key
        )),
        (Some(_), true) => {}
    }
    let mut checks = Vec::new();
    for scene in &run.scenes {
        // A scene that failed (to load, to render its truth, in a mode) or was interrupted
        // fails the gate, baseline or not.
        if scene.status != Status::Ok {
            let status = scene.status.to_string();
            let detail = scene.error.clone().unwrap_or_else(|| format!("the scene's status is {status}"));
            checks.push(status_check(scene, "*", Outcome::Failed, &detail));
        }
        match baselines.scene(&scene.name) {
            Some(_) if scene.modes.is_empty() => {}
            Some(baseline) => {
                notes.extend(input_notes(scene, baseline.scene()));
                checks.extend(compare_scene(scene, baseline, baselines.same_platform, &mut notes));
            }
            None => checks.extend(scene.modes.iter().map(|mode| {
                let outcome = if mode.status == Status::Ok { Outcome::New } else { Outcome::Failed };
                status_check(
                    scene,
                    &mode.mode,
                    outcome,
                    mode.error.as_deref().unwrap_or("no baseline for this scene"),
                )
            })),
        }
    }
    // A shard covers only some scenes: the others are not missing.
    if run.shard.is_none() {
        for baseline in &baselines.baselines {
            let scene = baseline.scene();
            if run.scenes.iter().all(|s| s.name != scene.name) {
                let detail = format!("the scene is not in the run (its {} modes)", scene.modes.len());
                checks.push(status_check(scene, "*", Outcome::Missing, &detail));
            }
        }
    }
    if fail_on == FailOn::Quality {
        notes.push("time verdicts are reported, not failed".into());
        for check in checks.iter_mut().filter(|c| TIME_METRICS.contains(&c.metric.as_str())) {
            check.gated = false;
        }
    }
    let mut counts = BTreeMap::new();
    for check in &checks {
        *counts.entry(check.outcome).or_insert(0) += 1;
    }
    Verdict {
        schema: VERDICT_SCHEMA.into(),
        run_id: run.run_id.clone(),
        tier: run.tier.name().into(),
        run_platform: run.platform.key.clone(),
        baseline_dir: baselines.dir.clone(),
        baseline_platform: baselines.platform_key.clone(),
        same_platform: baselines.same_platform,
        fail_on,
        regressed: checks.iter().any(Check::fails),
        counts,
        notes,
        checks,
    }
}

/// Notes on input files that changed since the baseline: the metrics may move for that reason.
fn input_notes(scene: &SceneRecord, baseline: &SceneRecord) -> Vec<String> {
    let mut notes = Vec::new();
    if let (Some(now), Some(then)) = (&scene.inputs, &baseline.inputs) {
        if now.manifest_sha256 != then.manifest_sha256 {
            notes.push(format!("{}: the manifest changed since the baseline", scene.name));
        }
        if now.gltf_sha256 != then.gltf_sha256 {
            notes.push(format!("{}: the glTF file changed since the baseline", scene.name));
        }
    }
    if let (Some(now), Some(then)) = (&scene.truth, &baseline.truth)
        && now.key != then.key
    {
        notes.push(format!(
            "{}: the ground truth's key changed (inputs, shaders, version or driver): errors against it may move",
            scene.name
        ));
    }
    notes
}

fn status_check(scene: &SceneRecord, mode: &str, outcome: Outcome, detail: &str) -> Check {
    Check {
        scene: scene.name.clone(),
        mode: mode.into(),
        metric: "status".into(),
        outcome,
        baseline: None,
        current: None,
        change: None,
        interval: None,
        threshold: None,
        unit: String::new(),
        detail: detail.into(),
        gated: true,
    }
}

fn compare_scene(
    scene: &SceneRecord,
    baseline: &Baseline,
    same_platform: bool,
    notes: &mut Vec<String>,
) -> Vec<Check> {
    let then = baseline.scene();
    if scene.resolution != then.resolution {
        let show = |r: Option<[u32; 2]>| r.map_or("?".into(), |[w, h]| format!("{w}×{h}"));
        let detail = format!(
            "rendered at {}, the baseline at {}: not comparable; re-bless",
            show(scene.resolution),
            show(then.resolution)
        );
        return scene.modes.iter().map(|m| status_check(scene, &m.mode, Outcome::Failed, &detail)).collect();
    }
    // The blessed tolerances decide: a change cannot loosen its own gate without a re-bless.
    let tolerances = then.gate;
    if scene.gate != then.gate {
        notes.push(format!(
            "{}: the manifest's gate tolerances differ from the baseline's; the baseline's apply until it is blessed again",
            scene.name
        ));
    }
    // The anchor of `relative_time`: the geometric mean of the unstalled modes that ran in
    // both (all common modes when fewer than two are unstalled), each mode left out of its own.
    let common: Vec<&ModeRecord> = scene
        .modes
        .iter()
        .filter(|m| m.status == Status::Ok && then.mode(&m.mode).is_some_and(|old| old.status == Status::Ok))
        .collect();
    let plain: Vec<&str> = common.iter().filter(|m| !m.stalled).map(|m| m.mode.as_str()).collect();
    let anchor_modes =
        if plain.len() >= 2 { plain } else { common.iter().map(|m| m.mode.as_str()).collect() };
    let mut checks = Vec::new();
    for mode in &scene.modes {
        let Some(old) = then.mode(&mode.mode) else {
            checks.push(status_check(scene, &mode.mode, Outcome::New, "not in the baseline"));
            continue;
        };
        if mode.status != Status::Ok {
            let error = mode.error.as_deref().unwrap_or("the mode failed");
            checks.push(status_check(scene, &mode.mode, Outcome::Failed, error));
            continue;
        }
        let context = ModeContext {
            scene,
            baselines: &baseline.scenes,
            mode,
            old,
            tolerances,
            same_platform,
            anchor_modes: &anchor_modes,
        };
        checks.extend(context.quality_checks());
        checks.extend(context.time_checks());
    }
    for old in &then.modes {
        if scene.mode(&old.mode).is_none() {
            checks.push(status_check(scene, &old.mode, Outcome::Missing, "not in the run"));
        }
    }
    checks
}

/// One mode of the run and the same mode in the baseline.
struct ModeContext<'a> {
    scene: &'a SceneRecord,
    /// The baseline's records of the scene, one per blessed run: time checks pool their rounds.
    baselines: &'a [SceneRecord],
    mode: &'a ModeRecord,
    /// The mode in the first baseline record: its quality numbers.
    old: &'a ModeRecord,
    tolerances: Tolerances,
    same_platform: bool,
    /// The modes whose geometric mean anchors `relative_time`.
    anchor_modes: &'a [&'a str],
}

impl ModeContext<'_> {
    fn check(&self, metric: &str, outcome: Outcome, unit: &str, detail: String) -> Check {
        Check {
            scene: self.scene.name.clone(),
            mode: self.mode.mode.clone(),
            metric: metric.into(),
            outcome,
            baseline: None,
            current: None,
            change: None,
            interval: None,
            threshold: None,
            unit: unit.into(),
            detail,
            gated: true,
        }
    }

    fn quality_checks(&self) -> Vec<Check> {
        let tolerance = self.tolerances.quality(self.same_platform);
        let mut checks = Vec::new();
        for (name, now, then) in [
            ("truth", &self.mode.vs_ground_truth, &self.old.vs_ground_truth),
            ("reference", &self.mode.vs_reference, &self.old.vs_reference),
        ] {
            match (now, then) {
                (Some(now), Some(then)) => {
                    checks.push(self.psnr_check(name, now, then, tolerance));
                    checks.push(self.mse_check(name, now, then, tolerance));
                }
                (None, Some(_)) => checks.push(self.check(
                    &format!("psnr_vs_{name}"),
                    Outcome::Failed,
                    "dB",
                    format!("the baseline has an error against the {name}, the run has none"),
                )),
                _ => {}
            }
        }
        if let (None, Some(_)) = (&self.mode.samples, &self.old.samples) {
            checks.push(self.check(
                "shaded_percent",
                Outcome::Failed,
                "percentage points",
                "the baseline has sample statistics, the run has none".into(),
            ));
        }
        if let (Some(now), Some(then)) = (&self.mode.samples, &self.old.samples) {
            let change = now.shaded_percent - then.shaded_percent;
            let outcome = beyond(change, tolerance.shaded_percent, false);
            checks.push(Check {
                baseline: Some(then.shaded_percent),
                current: Some(now.shaded_percent),
                change: Some(change),
                threshold: Some(tolerance.shaded_percent),
                ..self.check(
                    "shaded_percent",
                    outcome,
                    "percentage points",
                    format!(
                        "samples {:.2}% → {:.2}% ({change:+.2} points; tolerance ±{})",
                        then.shaded_percent, now.shaded_percent, tolerance.shaded_percent
                    ),
                )
            });
            let distance = total_variation(&now.histogram, &then.histogram);
            let outcome =
                if distance > tolerance.histogram { Outcome::Regressed } else { Outcome::Unchanged };
            checks.push(Check {
                change: Some(distance),
                threshold: Some(tolerance.histogram),
                ..self.check(
                    "sample_histogram",
                    outcome,
                    "total variation",
                    format!(
                        "the distribution of samples per pixel moved by {distance:.4} (total variation; tolerance {})",
                        tolerance.histogram
                    ),
                )
            });
        }
        if let (Some(now), Some(then)) = (&self.mode.output_hash, &self.old.output_hash)
            && now != then
        {
            // Reported, never failed: the metrics above decide whether the change matters.
            checks.push(self.check(
                "output_hash",
                Outcome::Unchanged,
                "",
                format!("the output changed ({then} → {now}); the metrics decide whether it matters"),
            ));
        }
        checks
    }

    fn psnr_check(
        &self,
        against: &str,
        now: &Quality,
        then: &Quality,
        tolerance: QualityTolerances,
    ) -> Check {
        let (now_db, then_db) = (now.psnr_db.value(), then.psnr_db.value());
        // Higher is better; two infinities (identical images both times) are no change.
        let change = if now_db == then_db { 0.0 } else { now_db - then_db };
        let outcome = beyond(change, tolerance.psnr_db, true);
        Check {
            baseline: Some(then_db).filter(|v| v.is_finite()),
            current: Some(now_db).filter(|v| v.is_finite()),
            change: Some(change).filter(|v| v.is_finite()),
            threshold: Some(tolerance.psnr_db),
            ..self.check(
                &format!("psnr_vs_{against}"),
                outcome,
                "dB",
                format!(
                    "PSNR against the {against} ({}) {} → {} dB ({}; tolerance ±{} dB)",
                    now.against,
                    show_db(then_db),
                    show_db(now_db),
                    show_signed_db(change),
                    tolerance.psnr_db
                ),
            )
        }
    }

    fn mse_check(&self, against: &str, now: &Quality, then: &Quality, tolerance: QualityTolerances) -> Check {
        let change = match (now.mse, then.mse) {
            (a, b) if a == b => 0.0,
            (_, 0.0) => f64::INFINITY,
            (a, b) => (a - b) / b,
        };
        let outcome = beyond(change, tolerance.mse_relative, false);
        Check {
            baseline: Some(then.mse),
            current: Some(now.mse),
            change: Some(change).filter(|v| v.is_finite()),
            threshold: Some(tolerance.mse_relative),
            ..self.check(
                &format!("mse_vs_{against}"),
                outcome,
                "relative",
                format!(
                    "MSE against the {against} {:.4} → {:.4} ×1e-5 ({}; tolerance ±{:.1}%)",
                    then.mse_e5,
                    now.mse_e5,
                    show_percent(change),
                    tolerance.mse_relative * 100.0
                ),
            )
        }
    }

    fn time_checks(&self) -> Vec<Check> {
        let mut checks = Vec::new();
        let threshold = self.tolerances.time_ratio;
        let Some(now) = &self.mode.frame_ms else { return checks };
        // The mode's frame samples in each baseline record, rounds in order.
        let then: Vec<&Vec<f64>> = self
            .baselines
            .iter()
            .filter_map(|record| record.mode(&self.mode.mode)?.frame_ms.as_ref().map(|f| &f.samples))
            .collect();
        if then.len() != self.baselines.len() {
            return checks;
        }
        let id = self.mode.mode.as_str();
        let now_anchor = self.scene.round_anchor(self.anchor_modes, id);
        let then_anchors: Option<Vec<Vec<f64>>> =
            self.baselines.iter().map(|record| record.round_anchor(self.anchor_modes, id)).collect();
        if let (Some(now_anchor), Some(then_anchors)) = (now_anchor, then_anchors) {
            let relative = |samples: &[f64], anchor: &[f64]| -> Vec<f64> {
                samples.iter().zip(anchor).map(|(s, a)| s.ln() - a).collect()
            };
            let now_log = relative(&now.samples, &now_anchor);
            let then_logs: Vec<Vec<f64>> =
                then.iter().zip(&then_anchors).map(|(samples, anchor)| relative(samples, anchor)).collect();
            checks.extend(self.time_check(
                "relative_time",
                &now_log,
                &then_logs,
                threshold,
                "frame time over the geometric mean of the round's other unstalled modes",
                (median_exp(&then_logs.concat()), median_exp(&now_log)),
                "×",
            ));
        }
        if let Some(cost) = &self.mode.adaptive {
            checks.extend(self.ratio_check("time_vs_reference", &cost.reference, threshold));
        }
        if self.same_platform {
            let log = |samples: &[f64]| samples.iter().map(|s| s.ln()).collect::<Vec<_>>();
            let then_logs: Vec<Vec<f64>> = then.iter().map(|samples| log(samples)).collect();
            let now_log = log(&now.samples);
            checks.extend(self.time_check(
                "frame_time",
                &now_log,
                &then_logs,
                self.tolerances.absolute_time,
                "absolute frame time (wide threshold: processes drift)",
                (median_exp(&then_logs.concat()), median_exp(&now_log)),
                "ms",
            ));
        }
        checks
    }

    /// The ratio of this mode's frame time to `anchor`'s, round by round, against the
    /// baseline's.
    fn ratio_check(&self, metric: &str, anchor: &str, threshold: f64) -> Option<Check> {
        let log = |ratios: Vec<f64>| ratios.iter().map(|r| r.ln()).collect::<Vec<_>>();
        let now = log(self.scene.paired_ratios(&self.mode.mode, anchor)?);
        let then: Option<Vec<Vec<f64>>> =
            self.baselines.iter().map(|record| record.paired_ratios(&self.mode.mode, anchor)).collect();
        let then: Vec<Vec<f64>> = then?.into_iter().map(log).collect();
        self.time_check(
            metric,
            &now,
            &then,
            threshold,
            &format!("frame time over {anchor}'s in the same round"),
            (median_exp(&then.concat()), median_exp(&now)),
            "×",
        )
    }

    /// Decides a time metric from log samples (the baseline's per process): the
    /// Hodges–Lehmann shift with its Moses interval, as relative changes, against the
    /// threshold widened by how far the baseline's own processes disagree ([`process_spread`]).
    #[allow(clippy::too_many_arguments)]
    fn time_check(
        &self,
        metric: &str,
        now: &[f64],
        then_per_process: &[Vec<f64>],
        threshold: f64,
        what: &str,
        (then_value, now_value): (f64, f64),
        unit: &str,
    ) -> Option<Check> {
        let then = then_per_process.concat();
        let shift = Shift::between(now, &then, CONFIDENCE)?;
        let relative = |log: f64| log.exp() - 1.0;
        // Widened by at most the tolerance itself: a 25% slowdown stays caught under the
        // default 10% however much one blessed process strayed.
        let tolerance = (1.0 + threshold).ln();
        let spread = process_spread(then_per_process).min(tolerance);
        let bound = tolerance + spread;
        let outcome = if shift.low > bound {
            Outcome::Regressed
        } else if shift.high < -bound {
            Outcome::Improved
        } else if shift.estimate.abs() > bound {
            Outcome::Noisy
        } else {
            Outcome::Unchanged
        };
        let (change, low, high) = (relative(shift.estimate), relative(shift.low), relative(shift.high));
        let value = |v: f64| if unit == "ms" { format!("{v:.1} ms") } else { format!("{v:.3}{unit}") };
        Some(Check {
            baseline: Some(then_value),
            current: Some(now_value),
            change: Some(change),
            interval: Some([low, high]),
            threshold: Some(relative(bound)),
            ..self.check(
                metric,
                outcome,
                "relative",
                format!(
                    "{what}: {} → {} ({}, {:.0}% interval {} … {}; thresholds {} and {}{})",
                    value(then_value),
                    value(now_value),
                    show_percent(change),
                    shift.level * 100.0,
                    show_percent(low),
                    show_percent(high),
                    show_percent(relative(-bound)),
                    show_percent(relative(bound)),
                    if spread > 0.0 {
                        format!(
                            ": the tolerance {} widened by the baseline processes' own spread, {}",
                            show_percent(threshold),
                            show_percent(relative(spread))
                        )
                    } else {
                        String::new()
                    }
                ),
            )
        })
    }
}

/// Improved or regressed when `change` is past `tolerance`; `higher_is_better` says which way
/// is which.
fn beyond(change: f64, tolerance: f64, higher_is_better: bool) -> Outcome {
    let better = if higher_is_better { change } else { -change };
    if better > tolerance {
        Outcome::Improved
    } else if better < -tolerance {
        Outcome::Regressed
    } else {
        Outcome::Unchanged
    }
}

/// Half the L1 distance between two histograms normalized to sum 1 (0: same shape, 1:
/// disjoint). Histograms of different lengths (another M) are disjoint beyond the shorter.
fn total_variation(a: &[u64], b: &[u64]) -> f64 {
    let (sum_a, sum_b) = (a.iter().sum::<u64>().max(1) as f64, b.iter().sum::<u64>().max(1) as f64);
    let length = a.len().max(b.len());
    let at = |h: &[u64], i: usize| h.get(i).copied().unwrap_or(0) as f64;
    (0..length).map(|i| (at(a, i) / sum_a - at(b, i) / sum_b).abs()).sum::<f64>() / 2.0
}

/// How far the baseline's processes disagree with one another: the largest distance (in log)
/// of one process's median from the pooled median; 0 for a baseline of one process. Frames of
/// one process vary less than processes do (a stalled mode's ratio moved 2.31–2.57× across the
/// three blessed processes of one build), and the shift's interval only covers the former: a
/// shift within this spread is no evidence of a change. The caller caps it, so that one
/// disturbed blessed process cannot switch a mode's time gate off.
fn process_spread(per_process: &[Vec<f64>]) -> f64 {
    let median = |logs: &[f64]| crate::stats::Summary::new(logs.to_vec()).map(|s| s.median);
    match (per_process.len(), median(&per_process.concat())) {
        (2.., Some(pooled)) => {
            per_process.iter().filter_map(|p| median(p)).map(|m| (m - pooled).abs()).fold(0.0, f64::max)
        }
        _ => 0.0,
    }
}

/// exp of the median of log values: the median ratio.
fn median_exp(logs: &[f64]) -> f64 {
    crate::stats::Summary::new(logs.to_vec()).map_or(f64::NAN, |s| s.median.exp())
}

fn show_db(db: f64) -> String {
    if db.is_finite() { format!("{db:.3}") } else { "∞".into() }
}

fn show_signed_db(db: f64) -> String {
    if db.is_finite() { format!("{db:+.3} dB") } else { format!("{db} dB") }
}

pub(crate) fn show_percent(fraction: f64) -> String {
    if fraction.is_finite() { format!("{:+.1}%", fraction * 100.0) } else { "+∞".into() }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tolerances_decide_direction_and_size() {
        assert_eq!(beyond(0.5, 0.25, true), Outcome::Improved);
        assert_eq!(beyond(-0.5, 0.25, true), Outcome::Regressed);
        assert_eq!(beyond(0.1, 0.25, true), Outcome::Unchanged);
        assert_eq!(beyond(0.5, 0.25, false), Outcome::Regressed, "more MSE is worse");
        assert_eq!(beyond(f64::INFINITY, 0.25, false), Outcome::Regressed);
    }

    #[test]
    fn the_process_spread_is_the_farthest_process_median_from_the_pooled_one() {
        let process = |median: f64| vec![median.ln() - 0.01, median.ln(), median.ln() + 0.01];
        assert_eq!(process_spread(&[process(2.4)]), 0.0, "one process: no spread to measure");
        // The baseline of specular's reference-4x4-stalled: 2.305, 2.416 and 2.57 × its anchor.
        let spread = process_spread(&[process(2.305), process(2.416), process(2.57)]);
        assert!((spread - (2.57f64 / 2.416).ln()).abs() < 1e-12, "{spread}");
        assert_eq!(process_spread(&[process(2.0), process(2.0)]), 0.0);
    }

    #[test]
    fn total_variation_is_half_the_l1_distance_of_the_shapes() {
        assert_eq!(total_variation(&[1, 1], &[2, 2]), 0.0);
        assert_eq!(total_variation(&[1, 0], &[0, 1]), 1.0);
        assert!((total_variation(&[3, 1], &[1, 1]) - 0.25).abs() < 1e-12);
        assert_eq!(total_variation(&[1], &[0, 1]), 1.0);
    }
}
