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

mod ab;
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
    /// repetitions cannot tell; or a time regression against the base build that fresh
    /// processes did not find again. Reported, not failed.
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

/// The time metrics: noisy, decided on intervals.
const TIME_METRICS: [&str; 3] = ["relative_time", "time_vs_reference", "frame_time"];

pub use crate::gate::MIN_FRAMES;

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
    pub scene: String,
    pub mode: String,
    /// `status`, `psnr_vs_truth`, `mse_vs_truth`, `flip_vs_truth`, `ssim_vs_truth`,
    /// `psnr_vs_reference`, `mse_vs_reference`, `shaded_percent`, `sample_histogram`, `output_hash`,
    /// `sequence_psnr_vs_truth`, `sequence_flip_vs_truth`, `instability`, `sequence_shaded_percent`,
    /// `relative_time`, `time_vs_reference`, `frame_time`; `run` for the run as a whole.
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
    fn new(scene: &str, mode: &str, metric: &str, outcome: Outcome, detail: String) -> Check {
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
    fn of_run(outcome: Outcome, detail: String) -> Check {
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
    /// whose time regressed against the base (see [`Confirmation`]), if any.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub confirm_run_ids: Vec<String>,
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub confirm_base_run_ids: Vec<String>,
    /// The manifests of the scenes whose time regressed against the base build and was not yet
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
}

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
    /// Missing baselines, scenes, modes and platforms, shards and unfinished runs are
    /// reported, not failed (a first bless, an exploratory compare).
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

/// Whether time against the committed baselines may fail the gate: with `--fail-on auto`, only
/// without base runs and on the machine that blessed them. Says why not in a note.
fn baseline_time_gated(request: &Request, machine: &Result<(), String>, notes: &mut Vec<String>) -> bool {
    let gated = match request.fail_on {
        FailOn::All => true,
        FailOn::Quality => false,
        FailOn::Auto => request.base.is_empty() && machine.is_ok(),
    };
    if request.baselines.dir.is_some() && !gated && request.fail_on == FailOn::Auto {
        let why = match machine {
            _ if !request.base.is_empty() => "the base build's processes on this machine decide".to_string(),
            Err(why) => format!("another machine ({why})"),
            Ok(()) => String::new(),
        };
        notes.push(format!("time against the committed baselines is informational: {why}"));
    }
    gated
}

/// Every scene of the run against its baseline (or as new, or failed), then every baseline
/// scene the run lacks.
fn scene_checks(runs: &[RunRecord], baselines: &BaselineSet, notes: &mut Vec<String>) -> Vec<Check> {
    let run = &runs[0];
    let mut checks = Vec::new();
    for scene in &run.scenes {
        // A scene that failed (to load, to render its truth, in a mode) or was interrupted
        // fails the gate, baseline or not.
        if scene.status != Status::Ok {
            let status = scene.status.to_string();
            let detail = scene.error.clone().unwrap_or_else(|| format!("the scene's status is {status}"));
            checks.push(status_check(scene, "*", Outcome::Failed, &detail));
        }
        let processes: Vec<&SceneRecord> =
            runs.iter().filter_map(|r| r.scenes.iter().find(|s| s.name == scene.name)).collect();
        match baselines.scene(&scene.name) {
            Some(_) if scene.modes.is_empty() => {}
            Some(baseline) => {
                notes.extend(input_notes(scene, baseline.scene()));
                notes.extend(front_notes(scene, baseline.scene()));
                checks.extend(compare_scene(&processes, baseline, baselines.same_platform, notes));
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
    // A shard covers only some scenes: the others are not missing (a strict compare has
    // already failed the shard itself).
    if run.shard.is_none() {
        for baseline in &baselines.baselines {
            let scene = baseline.scene();
            if run.scenes.iter().all(|s| s.name != scene.name) {
                let detail = format!("the scene is not in the run (its {} modes)", scene.modes.len());
                checks.push(status_check(scene, "*", Outcome::Missing, &detail));
            }
        }
    }
    checks
}

/// Compares the request's run with its baselines (and its base build's processes, if any).
pub fn compare(request: &Request) -> Verdict {
    let Request { runs, base, baselines, fail_on, lenient, confirmation } = *request;
    let run = &runs[0];
    let mut notes = Vec::new();
    let mut checks = Vec::new();
    for problem in run_problems(run, baselines) {
        if lenient {
            notes.push(format!("{problem} (--lenient: reported, not failed)"));
        } else {
            checks.push(Check::of_run(Outcome::Failed, format!("{problem}; or compare with --lenient")));
        }
    }
    if let (Some(_), false) = (&baselines.dir, baselines.same_platform) {
        notes.push(format!(
            "the baselines are of another platform (`{}`; this run: `{}`): quality is compared with the \
             cross-platform tolerances, in-run time ratios as usual, absolute times not at all",
            baselines.platform_key.as_deref().unwrap_or("?"),
            run.platform.key
        ));
    }
    let machine = same_machine(run, baselines);
    let baseline_time_gated = baseline_time_gated(request, &machine, &mut notes);
    checks.extend(disagreements(runs));
    checks.extend(scene_checks(runs, baselines, &mut notes));
    let mut to_confirm = Vec::new();
    if !base.is_empty() {
        let mut time = ab::checks(runs, base, baselines, &mut notes);
        match confirmation {
            Some(fresh) => ab::confirm(&mut time, fresh, baselines),
            None => to_confirm = ab::regressed_manifests(&time, run),
        }
        checks.extend(time);
    }
    for check in &mut checks {
        if TIME_METRICS.contains(&check.metric.as_str()) {
            check.gated = match check.against {
                Against::Baseline => baseline_time_gated,
                Against::Base => fail_on != FailOn::Quality,
            };
        }
        if lenient && check.outcome == Outcome::Missing {
            check.gated = false;
        }
    }
    if fail_on == FailOn::Quality {
        notes.push("time verdicts are reported, not failed".into());
    }
    let mut counts = BTreeMap::new();
    for check in &checks {
        *counts.entry(check.outcome).or_insert(0) += 1;
    }
    Verdict {
        schema: VERDICT_SCHEMA.into(),
        run_id: run.run_id.clone(),
        run_ids: runs.iter().map(|r| r.run_id.clone()).collect(),
        base_run_ids: base.iter().map(|r| r.run_id.clone()).collect(),
        confirm_run_ids: confirmation
            .map_or(Vec::new(), |c| c.runs.iter().map(|r| r.run_id.clone()).collect()),
        confirm_base_run_ids: confirmation
            .map_or(Vec::new(), |c| c.base.iter().map(|r| r.run_id.clone()).collect()),
        to_confirm: if fail_on == FailOn::Quality { Vec::new() } else { to_confirm },
        tier: run.tier.name().into(),
        run_platform: run.platform.key.clone(),
        baseline_dir: baselines.dir.clone(),
        baseline_platform: baselines.platform_key.clone(),
        same_platform: baselines.same_platform,
        same_machine: machine.is_ok(),
        fail_on,
        lenient,
        regressed: checks.iter().any(Check::fails),
        counts,
        notes,
        checks,
    }
}

/// Runs that cannot be compared together at all (exit 2): processes of the run, of the base,
/// or of a confirmation on different platforms or tiers than the run's first, or the same run
/// given twice. `groups` are the run's processes first, then the others.
pub fn check_comparable(groups: &[&[RunRecord]]) -> Result<(), String> {
    let all: Vec<&RunRecord> = groups.iter().flat_map(|group| group.iter()).collect();
    let first = all[0];
    for (index, run) in all.iter().enumerate() {
        // Equal records are one process read twice: two processes never time alike.
        if all[..index].contains(run) {
            return Err(format!(
                "run {} is given twice: each process counts once (pass each run folder once)",
                run.run_id
            ));
        }
        if run.platform.key != first.platform.key || run.tier != first.tier {
            return Err(format!(
                "run {} ({}, {} tier) and run {} ({}, {} tier) were not measured alike: compare runs of one \
                 platform and tier",
                first.run_id,
                first.platform.key,
                first.tier.name(),
                run.run_id,
                run.platform.key,
                run.tier.name()
            ));
        }
    }
    Ok(())
}

/// What makes a run unfit to gate on: no baselines, another platform's, a run without scenes,
/// one shard of a suite, a run that did not finish. A strict compare fails on each.
fn run_problems(run: &RunRecord, baselines: &BaselineSet) -> Vec<String> {
    let mut problems = Vec::new();
    match (&baselines.absent, &baselines.platform_key) {
        (Some(why), _) => problems.push(format!(
            "no baselines to compare with: {why} (bless runs of this build with `aabench bless`)"
        )),
        (None, Some(key)) if !baselines.same_platform => problems.push(format!(
            "no baselines of this run's platform `{}` for the {} tier, only of `{key}`: bless runs made here",
            run.platform.key,
            run.tier.name()
        )),
        _ => {}
    }
    if run.scenes.is_empty() {
        problems.push("the run has no scenes: nothing was measured".into());
    }
    if let Some(shard) = run.shard {
        problems.push(format!(
            "the run is shard {}/{} of a suite: join the shards with `aabench merge` and compare the merged run",
            shard.index, shard.count
        ));
    }
    if run.finished_at.is_none() || matches!(run.status, Status::Running | Status::Interrupted) {
        problems.push(format!(
            "the run did not finish (status `{}`): it was killed, interrupted or is still running",
            run.status
        ));
    }
    problems
}

/// Whether the run's machine is the one that blessed the baselines: the same platform key, CPU
/// identity and calibration (see [`crate::machine`]); otherwise why not.
fn same_machine(run: &RunRecord, baselines: &BaselineSet) -> Result<(), String> {
    if !baselines.same_platform {
        return Err("another platform key".into());
    }
    let blessed = baselines.baselines.first().ok_or("no baselines")?;
    match (&run.platform.machine, &blessed.platform.machine) {
        (Some(now), Some(then)) => now.same_as(then),
        (None, _) => Err("the run did not record its machine".into()),
        (_, None) => Err("the baselines do not record their machine (blessed before aabench did)".into()),
    }
}

/// Processes of one build must render the same images: a mode whose output hash differs
/// between them fails (their times are pooled, their quality taken from the first).
fn disagreements(runs: &[RunRecord]) -> Vec<Check> {
    let mut checks = Vec::new();
    let first = &runs[0];
    for (index, other) in runs.iter().enumerate().skip(1) {
        for scene in &first.scenes {
            let Some(theirs) = other.scenes.iter().find(|s| s.name == scene.name) else { continue };
            for mode in scene.modes.iter().filter(|m| m.output_hash.is_some()) {
                let hash = theirs.mode(&mode.mode).and_then(|m| m.output_hash.as_ref());
                if hash.is_some_and(|hash| Some(hash) != mode.output_hash.as_ref()) {
                    let detail = format!(
                        "process {} ({}) rendered another image than process 1 ({}): the build is not deterministic",
                        index + 1,
                        other.run_id,
                        first.run_id
                    );
                    checks.push(Check {
                        metric: "output_hash".into(),
                        ..status_check(scene, &mode.mode, Outcome::Failed, &detail)
                    });
                }
            }
        }
    }
    checks
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
    if let (Some(now), Some(then)) = (&scene.truth, &baseline.truth) {
        // The key changes with any edit of the rendering source, a comment included; the
        // image's own hash says whether the truth itself moved.
        let changed = match (&now.image_hash, &then.image_hash) {
            (Some(now), Some(then)) => now != then,
            _ => now.key != then.key,
        };
        if changed {
            notes.push(format!(
                "{}: the ground truth's image changed since the baseline: errors against it may move",
                scene.name
            ));
        }
    }
    notes
}

/// Notes on modes that left or joined the scene's error-against-run-time front since the
/// baseline: informational, since the front moves with any mode's time or error.
fn front_notes(scene: &SceneRecord, baseline: &SceneRecord) -> Vec<String> {
    scene
        .modes
        .iter()
        .filter_map(|mode| {
            let now = mode.front.as_ref()?;
            let then = baseline.mode(&mode.mode)?.front.as_ref()?;
            match (then.on_front, now.on_front) {
                (true, false) => {
                    Some(format!("{}: {} left the front: {}", scene.name, mode.mode, now.describe()))
                }
                (false, true) => Some(format!("{}: {} joined the front", scene.name, mode.mode)),
                _ => None,
            }
        })
        .collect()
}

fn status_check(scene: &SceneRecord, mode: &str, outcome: Outcome, detail: &str) -> Check {
    Check::new(&scene.name, mode, "status", outcome, detail.into())
}

/// The checks of one scene: `processes` are its records in each process of the run (the
/// first gives the quality numbers), `baseline` its committed baseline.
fn compare_scene(
    processes: &[&SceneRecord],
    baseline: &Baseline,
    same_platform: bool,
    notes: &mut Vec<String>,
) -> Vec<Check> {
    let scene = processes[0];
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
            processes,
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
    // Green means compared in full: a run without the sequence its baseline holds compared less.
    if then.sequence.is_some() && scene.sequence.is_none() {
        let detail = "the baseline holds the scene's sequence, the run rendered none (--sequences off?)";
        checks.push(status_check(scene, "*", Outcome::Missing, detail));
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
    /// The scene in every process of the run: time checks pool their rounds.
    processes: &'a [&'a SceneRecord],
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
        Check { unit: unit.into(), ..Check::new(&self.scene.name, &self.mode.mode, metric, outcome, detail) }
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
                    checks.extend(self.perceptual_checks(name, now, then, tolerance));
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
        checks.extend(self.sequence_checks(tolerance));
        if let (None, Some(_)) = (&self.mode.samples, &self.old.samples) {
            checks.push(self.check(
                "shaded_percent",
                Outcome::Failed,
                "percentage points",
                "the baseline has sample statistics, the run has none".into(),
            ));
        }
        if let (Some(now), Some(then)) = (&self.mode.samples, &self.old.samples) {
            checks.push(self.shaded_check(
                "shaded_percent",
                now.shaded_percent,
                then.shaded_percent,
                tolerance,
            ));
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
        let label = format!("PSNR against the {against} ({})", now.against);
        self.db_check(
            &format!("psnr_vs_{against}"),
            &label,
            now.psnr_db.value(),
            then.psnr_db.value(),
            tolerance,
        )
    }

    /// A PSNR-like value in dB, higher better, moved by more than the tolerance's dB or not.
    fn db_check(
        &self,
        metric: &str,
        label: &str,
        now_db: f64,
        then_db: f64,
        tolerance: QualityTolerances,
    ) -> Check {
        // Two infinities (identical images both times) are no change.
        let change = if now_db == then_db { 0.0 } else { now_db - then_db };
        let outcome = beyond(change, tolerance.psnr_db, true);
        Check {
            baseline: Some(then_db).filter(|v| v.is_finite()),
            current: Some(now_db).filter(|v| v.is_finite()),
            change: Some(change).filter(|v| v.is_finite()),
            threshold: Some(tolerance.psnr_db),
            ..self.check(
                metric,
                outcome,
                "dB",
                format!(
                    "{label} {} → {} dB ({}; tolerance ±{} dB)",
                    show_db(then_db),
                    show_db(now_db),
                    show_signed_db(change),
                    tolerance.psnr_db
                ),
            )
        }
    }

    /// The mode's sequence against the baseline's: its mean PSNR and mean FLIP against the
    /// truth's frames (the PSNR and FLIP tolerances), its samples shaded and its instability (an error of squared code values, so the MSE
    /// tolerance, relative). A run that rendered no sequence of the scene is one missing check
    /// of the scene (`compare_scene`); a mode that has none in a run that did fails.
    fn sequence_checks(&self, tolerance: QualityTolerances) -> Vec<Check> {
        let (Some(then), Some(_)) = (&self.old.sequence, &self.scene.sequence) else {
            return Vec::new();
        };
        let Some(now) = &self.mode.sequence else {
            let detail = "the baseline has a sequence of this mode, the run has none".to_string();
            return vec![self.check("sequence_psnr_vs_truth", Outcome::Failed, "dB", detail)];
        };
        let label = "mean PSNR against the truth's frames";
        let psnr = self.db_check(
            "sequence_psnr_vs_truth",
            label,
            now.mean_psnr_db.value(),
            then.mean_psnr_db.value(),
            tolerance,
        );
        let change = relative_change(now.instability, then.instability);
        let instability = Check {
            baseline: Some(then.instability),
            current: Some(now.instability),
            change: Some(change).filter(|v| v.is_finite()),
            threshold: Some(tolerance.mse_relative),
            ..self.check(
                "instability",
                beyond(change, tolerance.mse_relative, false),
                "relative",
                format!(
                    "temporal instability {:.4e} → {:.4e} ({}; tolerance ±{:.1}%)",
                    then.instability,
                    now.instability,
                    show_percent(change),
                    tolerance.mse_relative * 100.0
                ),
            )
        };
        let mut checks = vec![psnr, instability];
        checks.extend(self.error_check(
            "sequence_flip_vs_truth",
            "mean FLIP against the truth's frames",
            now.mean_flip,
            then.mean_flip,
            tolerance.flip_relative,
            0.0,
        ));
        match (now.shaded_percent, then.shaded_percent) {
            (Some(now), Some(then)) => {
                checks.push(self.shaded_check("sequence_shaded_percent", now, then, tolerance));
            }
            (None, Some(_)) => checks.push(self.check(
                "sequence_shaded_percent",
                Outcome::Failed,
                "percentage points",
                "the baseline has the samples shaded along the path, the run has none".into(),
            )),
            _ => {}
        }
        checks
    }

    /// The share of samples shaded, `now` against `then`, in percentage points.
    fn shaded_check(&self, metric: &str, now: f64, then: f64, tolerance: QualityTolerances) -> Check {
        let change = now - then;
        Check {
            baseline: Some(then),
            current: Some(now),
            change: Some(change),
            threshold: Some(tolerance.shaded_percent),
            ..self.check(
                metric,
                beyond(change, tolerance.shaded_percent, false),
                "percentage points",
                format!(
                    "samples {then:.2}% → {now:.2}% ({change:+.2} points; tolerance ±{})",
                    tolerance.shaded_percent
                ),
            )
        }
    }

    fn mse_check(&self, against: &str, now: &Quality, then: &Quality, tolerance: QualityTolerances) -> Check {
        let change = relative_change(now.mse, then.mse);
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

    /// FLIP and SSIM where both records have them: a baseline from before them checks
    /// neither; a run that lost one fails it. Each moves by its relative change (of 1 − SSIM
    /// for SSIM, so that both read as errors).
    fn perceptual_checks(
        &self,
        against: &str,
        now: &Quality,
        then: &Quality,
        tolerance: QualityTolerances,
    ) -> Vec<Check> {
        let metrics = [
            ("flip", "FLIP", now.flip, then.flip, tolerance.flip_relative, 0.0),
            ("ssim", "SSIM", now.ssim, then.ssim, tolerance.ssim_relative, 1.0),
        ];
        metrics
            .into_iter()
            .filter_map(|(metric, label, now, then, threshold, perfect)| {
                let label = format!("{label} against the {against}");
                self.error_check(&format!("{metric}_vs_{against}"), &label, now, then, threshold, perfect)
            })
            .collect()
    }

    /// An error metric where the baseline has it: its relative change in the distance from
    /// `perfect` (the value of identical images) against `threshold`. A run without it fails.
    fn error_check(
        &self,
        name: &str,
        label: &str,
        now: Option<f64>,
        then: Option<f64>,
        threshold: f64,
        perfect: f64,
    ) -> Option<Check> {
        let (now, then) = match (now, then) {
            (Some(now), Some(then)) => (now, then),
            (None, Some(_)) => {
                let detail = format!("the baseline has {label}, the run has none");
                return Some(self.check(name, Outcome::Failed, "relative", detail));
            }
            _ => return None,
        };
        let change = relative_change((now - perfect).abs(), (then - perfect).abs());
        Some(Check {
            baseline: Some(then),
            current: Some(now),
            change: Some(change).filter(|v| v.is_finite()),
            threshold: Some(threshold),
            ..self.check(
                name,
                beyond(change, threshold, false),
                "relative",
                format!(
                    "{label} {then:.5} → {now:.5} ({} of its error; tolerance ±{:.1}%)",
                    show_percent(change),
                    threshold * 100.0
                ),
            )
        })
    }

    fn time_checks(&self) -> Vec<Check> {
        let mut checks = Vec::new();
        let threshold = self.tolerances.time_ratio;
        let id = self.mode.mode.as_str();
        // The mode's frame samples in each baseline record and each process of the run.
        let frames = |record: &SceneRecord| record.mode(id)?.frame_ms.as_ref().map(|f| f.samples.clone());
        let Some(now) = self.processes.iter().map(|record| frames(record)).collect::<Option<Vec<_>>>() else {
            return checks;
        };
        let Some(then) = self.baselines.iter().map(frames).collect::<Option<Vec<_>>>() else { return checks };
        let anchors = |record: &SceneRecord| record.round_anchor(self.anchor_modes, id);
        if let (Some(now_anchors), Some(then_anchors)) = (
            self.processes.iter().map(|record| anchors(record)).collect::<Option<Vec<_>>>(),
            self.baselines.iter().map(anchors).collect::<Option<Vec<_>>>(),
        ) {
            let relative = |samples: &[f64], anchor: &[f64]| -> Vec<f64> {
                samples.iter().zip(anchor).map(|(s, a)| s.ln() - a).collect()
            };
            let relatives = |samples: &[Vec<f64>], anchors: &[Vec<f64>]| -> Vec<Vec<f64>> {
                samples.iter().zip(anchors).map(|(s, a)| relative(s, a)).collect()
            };
            checks.extend(self.time_check(
                "relative_time",
                &relatives(&now, &now_anchors).concat(),
                &relatives(&then, &then_anchors),
                threshold,
                "frame time over the geometric mean of the round's other unstalled modes",
                "×",
            ));
        }
        if let Some(cost) = &self.mode.adaptive {
            checks.extend(self.ratio_check("time_vs_reference", &cost.reference, threshold));
        }
        if self.same_platform {
            let log = |samples: &Vec<f64>| samples.iter().map(|s| s.ln()).collect::<Vec<_>>();
            let now_log: Vec<f64> = now.iter().flat_map(log).collect();
            checks.extend(self.time_check(
                "frame_time",
                &now_log,
                &then.iter().map(log).collect::<Vec<_>>(),
                self.tolerances.absolute_time,
                "absolute frame time (wide threshold: processes drift)",
                "ms",
            ));
        }
        checks
    }

    /// The ratio of this mode's frame time to `anchor`'s, round by round, against the
    /// baseline's.
    fn ratio_check(&self, metric: &str, anchor: &str, threshold: f64) -> Option<Check> {
        let log = |ratios: Vec<f64>| ratios.iter().map(|r| r.ln()).collect::<Vec<_>>();
        let ratios = |record: &SceneRecord| record.paired_ratios(&self.mode.mode, anchor).map(log);
        let now: Vec<Vec<f64>> = self.processes.iter().map(|record| ratios(record)).collect::<Option<_>>()?;
        let then: Vec<Vec<f64>> = self.baselines.iter().map(ratios).collect::<Option<_>>()?;
        self.time_check(
            metric,
            &now.concat(),
            &then,
            threshold,
            &format!("frame time over {anchor}'s in the same round"),
            "×",
        )
    }

    /// Decides a time metric from log samples (the baseline's per process): the
    /// Hodges–Lehmann shift with its Moses interval, as relative changes, against the
    /// threshold widened by how far the baseline's own processes disagree ([`process_spread`]).
    /// Fewer than [`MIN_FRAMES`] samples on either side is `insufficient`.
    fn time_check(
        &self,
        metric: &str,
        now: &[f64],
        then_per_process: &[Vec<f64>],
        threshold: f64,
        what: &str,
        unit: &str,
    ) -> Option<Check> {
        let then = then_per_process.concat();
        let values = (median_exp(&then), median_exp(now));
        if now.len() < MIN_FRAMES || then.len() < MIN_FRAMES {
            let value = |v: f64| show_time(v, unit);
            return Some(Check {
                baseline: Some(values.0),
                current: Some(values.1),
                ..self.check(
                    metric,
                    Outcome::Insufficient,
                    "relative",
                    format!(
                        "{what}: {} → {}; {} frames in the run and {} in the baseline, fewer than the {MIN_FRAMES} a time verdict needs",
                        value(values.0),
                        value(values.1),
                        now.len(),
                        then.len()
                    ),
                )
            });
        }
        let shift = Shift::between(now, &then, CONFIDENCE)?;
        // Widened by at most the tolerance itself: a 25% slowdown stays caught under the
        // default 10% however much one blessed process strayed.
        let tolerance = (1.0 + threshold).ln();
        let spread = process_spread(then_per_process).min(tolerance);
        let widening = (spread > 0.0).then(|| {
            format!(
                ": the tolerance {} widened by the baseline processes' own spread, {}",
                show_percent(threshold),
                show_percent(spread.exp() - 1.0)
            )
        });
        let decided =
            decide(shift, tolerance + spread, values, unit, what, widening.as_deref().unwrap_or(""));
        Some(decided.into_check(self.check(metric, Outcome::Unchanged, "relative", String::new())))
    }
}

/// A time shift decided against a bound: its outcome and the numbers that go into a check.
struct Decided {
    outcome: Outcome,
    values: (f64, f64),
    change: f64,
    interval: [f64; 2],
    bound: f64,
    detail: String,
}

impl Decided {
    /// `template` with this decision's outcome, numbers and detail.
    fn into_check(self, template: Check) -> Check {
        Check {
            outcome: self.outcome,
            baseline: Some(self.values.0),
            current: Some(self.values.1),
            change: Some(self.change),
            interval: Some(self.interval),
            threshold: Some(self.bound.exp() - 1.0),
            detail: self.detail,
            ..template
        }
    }
}

/// Regressed when the whole interval of `shift` (in log) is past `bound`, improved when it is
/// wholly below `-bound`, noisy when only the estimate is past either, else unchanged.
/// `values` are the two sides' medians for the detail, `extra` ends its threshold clause.
fn decide(shift: Shift, bound: f64, values: (f64, f64), unit: &str, what: &str, extra: &str) -> Decided {
    let outcome = if shift.low > bound {
        Outcome::Regressed
    } else if shift.high < -bound {
        Outcome::Improved
    } else if shift.estimate.abs() > bound {
        Outcome::Noisy
    } else {
        Outcome::Unchanged
    };
    let relative = |log: f64| log.exp() - 1.0;
    let (change, low, high) = (relative(shift.estimate), relative(shift.low), relative(shift.high));
    let detail = format!(
        "{what}: {} → {} ({}, {:.0}% interval {} … {}; thresholds {} and {}{extra})",
        show_time(values.0, unit),
        show_time(values.1, unit),
        show_percent(change),
        shift.level * 100.0,
        show_percent(low),
        show_percent(high),
        show_percent(relative(-bound)),
        show_percent(relative(bound)),
    );
    Decided { outcome, values, change, interval: [low, high], bound, detail }
}

/// A time for people: milliseconds, or a ratio with its unit (`×`).
fn show_time(value: f64, unit: &str) -> String {
    if unit == "ms" { format!("{value:.1} ms") } else { format!("{value:.3}{unit}") }
}

/// Improved or regressed when `change` is past `tolerance`; `higher_is_better` says which way
/// is which.
/// An error's change over its baseline value, as a fraction: 0 when unchanged (two zeros
/// included), infinite from an error of zero.
fn relative_change(now: f64, then: f64) -> f64 {
    match (now, then) {
        (a, b) if a == b => 0.0,
        (_, 0.0) => f64::INFINITY,
        (a, b) => (a - b) / b,
    }
}

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
