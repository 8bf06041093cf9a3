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
mod mode;
pub mod outputs;
mod pooled;
mod quality;
mod request;
mod sensitivity;
mod series;
mod shards;
mod time;
mod verdict;

pub use request::{Confirmation, Request};
pub use shards::merge_verdicts;
pub use verdict::{
    Against, CONFIDENCE, Check, FailOn, MIN_FRAMES, MIN_PROCESSES, Outcome, ShardScope, VERDICT_SCHEMA,
    Verdict,
};

use crate::baseline::{Baseline, BaselineSet};
use crate::record::vocabulary::{self, Source};
use crate::record::{FrontVerdict, ModeRecord, RunRecord, SceneRecord, Status};
use mode::ModeContext;
use verdict::is_time_metric;

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
    // A run that timed fewer rounds in all its processes than a time verdict needs (the gate's
    // quality process renders one, without a warm-up) is compared in quality alone: a row of
    // `insufficient` per mode and time metric would only bury what it found.
    let rounds: u32 = runs.iter().map(|r| r.settings.repetitions).sum();
    let timed = rounds as usize >= MIN_FRAMES;
    if !timed && !baselines.baselines.is_empty() {
        notes.push(format!(
            "time not compared: the run timed {rounds} round{} of each mode, fewer than the {MIN_FRAMES} a time verdict needs",
            if rounds == 1 { "" } else { "s" }
        ));
    }
    for scene in &run.scenes {
        // A scene that failed (to load, to render its truth, in a mode) or was interrupted
        // fails the gate, baseline or not.
        if scene.status != Status::Ok {
            let status = scene.status.to_string();
            let detail = scene.error.clone().unwrap_or_else(|| format!("the scene's status is {status}"));
            checks.push(status_check(&scene.name, "*", Outcome::Failed, &detail));
        }
        notes.extend(unscored_note(scene));
        let processes: Vec<&SceneRecord> =
            runs.iter().filter_map(|r| r.scenes.iter().find(|s| s.name == scene.name)).collect();
        match baselines.scene(&scene.name) {
            Some(_) if scene.modes.is_empty() => {}
            Some(baseline) => {
                notes.extend(input_notes(scene, baseline));
                notes.extend(front_notes(scene, baseline));
                checks.extend(compare_scene(&processes, baseline, (baselines.same_platform, timed), notes));
            }
            None => checks.extend(scene.modes.iter().map(|mode| {
                let outcome = if mode.status == Status::Ok { Outcome::New } else { Outcome::Failed };
                status_check(
                    &scene.name,
                    &mode.mode,
                    outcome,
                    mode.error.as_deref().unwrap_or("no baseline for this scene"),
                )
            })),
        }
    }
    // A shard covers only some scenes: the others are not missing here (`merge-verdicts`
    // fails a baseline that no shard compared).
    if run.shard.is_none() {
        for baseline in &baselines.baselines {
            if run.scenes.iter().all(|s| s.name != baseline.scene) {
                let detail = format!("the scene is not in the run (its {} modes)", baseline.modes.len());
                checks.push(status_check(&baseline.scene, "*", Outcome::Missing, &detail));
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
    let hashes = Hashes::of(run, baselines);
    for problem in run_problems(run, baselines, &hashes) {
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
    notes.extend(hashes.note());
    let machine = same_machine(run, baselines);
    let baseline_time_gated = baseline_time_gated(request, &machine, &mut notes);
    checks.extend(disagreements(runs));
    checks.extend(scene_checks(runs, baselines, &mut notes));
    let mut to_confirm = Vec::new();
    if !base.is_empty() {
        let (runs, base): (Vec<&RunRecord>, Vec<&RunRecord>) = (runs.iter().collect(), base.iter().collect());
        let mut time = ab::checks(&runs, &base, baselines, &mut notes);
        match confirmation {
            Some(fresh) => ab::confirm(&mut time, (&runs, &base), fresh, baselines),
            None => to_confirm = ab::manifests_to_confirm(&time, run),
        }
        checks.extend(time);
    }
    for check in &mut checks {
        if is_time_metric(&check.metric) {
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
    let counts = Outcome::count(&checks);
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
        build: run.build.clone(),
        base_build: base.first().and_then(|b| b.build.clone()),
        shard: shard_scope(run, baselines),
    }
}

/// What a shard's verdict must say for `merge-verdicts` to join it: which shard, its scenes,
/// and every scene the baselines hold.
fn shard_scope(run: &RunRecord, baselines: &BaselineSet) -> Option<ShardScope> {
    run.shard.map(|shard| ShardScope {
        index: shard.index,
        count: shard.count,
        scenes: run.scenes.iter().map(|s| s.name.clone()).collect(),
        baseline_scenes: baselines.baselines.iter().map(|b| b.scene.clone()).collect(),
        baselines_blessed: baselines
            .baselines
            .iter()
            .map(|b| format!("{}: blessed {} from {}", b.scene, b.blessed.at, b.blessed.run_ids.join(", ")))
            .collect(),
    })
}

/// Runs that cannot be compared together at all (exit 2): processes of the run, of the base,
/// or of a confirmation on different platforms or tiers than the run's first, the same run
/// given twice, or the run's processes (or the base's) of more than one build. `groups` are
/// the run's processes, the base's, and the confirming runs of each.
pub fn check_comparable(groups: &[&[RunRecord]; 4]) -> Result<(), String> {
    // The run's processes are one build, the base's another: each group, and its confirming
    // runs, of one build.
    let [head, base, confirm_head, confirm_base] = groups;
    for (side, confirm) in [(head, confirm_head), (base, confirm_base)] {
        if let Some(first) = side.first().or(confirm.first()) {
            let builds =
                side.iter().chain(confirm.iter()).find_map(|run| crate::record::different_builds(first, run));
            if let Some(why) = builds {
                return Err(why);
            }
        }
    }
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

/// What makes a run unfit to gate on: no baselines, only another platform's whose images differ
/// from the run's (`hashes`), a run without scenes, one shard of a suite, a run that did not
/// finish. A strict compare fails on each.
fn run_problems(run: &RunRecord, baselines: &BaselineSet, hashes: &Hashes) -> Vec<String> {
    let mut problems = Vec::new();
    match (&baselines.absent, &baselines.platform_key) {
        (Some(why), _) => problems.push(format!(
            "no baselines to compare with: {why} (bless runs of this build with `aabench bless`)"
        )),
        // Baselines of another key still judge a run whose every image is theirs to the bit.
        (None, Some(key)) if !baselines.same_platform => {
            if let Err(first) = hashes.all_equal() {
                problems.push(format!(
                    "no baselines of this run's platform `{}` for the {} tier, only of `{key}`, whose images \
                     differ from this run's ({first}): bless runs made here",
                    run.platform.key,
                    run.tier.name()
                ));
            }
        }
        _ => {}
    }
    // A shard may hold no scene (more shards than scenes): `merge-verdicts` checks the whole.
    if run.scenes.is_empty() && run.shard.is_none() {
        problems.push("the run has no scenes: nothing was measured".into());
    }
    if !run.settings.quality {
        problems.push(
            "the run timed its modes alone (`--quality off`): give a run that measured their quality first, \
             and this one after it as another process"
                .into(),
        );
    }
    if run.finished_at.is_none() || matches!(run.status, Status::Running | Status::Interrupted) {
        problems.push(format!(
            "the run did not finish (status `{}`): it was killed, interrupted or is still running",
            run.status
        ));
    }
    problems
}

/// The run's output hashes against the baselines': of every (scene, mode) that has one on
/// both sides, how many are equal and the first that is not.
struct Hashes {
    compared: usize,
    equal: usize,
    first_different: Option<String>,
}

impl Hashes {
    fn of(run: &RunRecord, baselines: &BaselineSet) -> Hashes {
        let mut hashes = Hashes { compared: 0, equal: 0, first_different: None };
        for scene in &run.scenes {
            let Some(baseline) = baselines.scene(&scene.name) else { continue };
            for mode in &scene.modes {
                let old = baseline.mode(&mode.mode).and_then(|old| old.output_hash.as_ref());
                let (Some(now), Some(then)) = (&mode.output_hash, old) else { continue };
                hashes.compared += 1;
                if now == then {
                    hashes.equal += 1;
                } else if hashes.first_different.is_none() {
                    hashes.first_different = Some(format!("{} {}: {then} → {now}", scene.name, mode.mode));
                }
            }
        }
        hashes
    }

    /// `Ok` when at least one hash was compared and all were equal; otherwise what differs.
    fn all_equal(&self) -> Result<(), String> {
        match &self.first_different {
            Some(first) => Err(format!(
                "{} of {} output hashes differ, the first: {first}",
                self.compared - self.equal,
                self.compared
            )),
            None if self.compared == 0 => Err("no output hash to compare".into()),
            None => Ok(()),
        }
    }

    /// The verdict's note on the images: all the blessed bits, or where they first differ.
    fn note(&self) -> Option<String> {
        (self.compared > 0).then(|| match self.all_equal() {
            Ok(()) => format!(
                "every one of the {} output hashes equals its baseline's: the images are the blessed bits",
                self.compared
            ),
            Err(why) => why,
        })
    }
}

/// Whether the run's machine is the one that blessed the baselines: the same platform key, CPU
/// identity and calibration (see [`crate::measure::machine`]); otherwise why not.
fn same_machine(run: &RunRecord, baselines: &BaselineSet) -> Result<(), String> {
    if !baselines.same_platform {
        return Err("another platform key".into());
    }
    let blessed = baselines.baselines.first().ok_or("no baselines")?;
    match (&run.platform.machine, &blessed.blessed.platform.machine) {
        (Some(now), Some(then)) => now.same_as(then),
        (None, _) if run.scenes.iter().any(|scene| scene.machine.is_some()) => {
            Err("its shards ran on different machines (each scene records its own)".into())
        }
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
                        ..status_check(&scene.name, &mode.mode, Outcome::Failed, &detail)
                    });
                }
            }
        }
    }
    checks
}

/// Notes on input files that changed since the baseline: the metrics may move for that reason.
fn input_notes(scene: &SceneRecord, baseline: &Baseline) -> Vec<String> {
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

/// A note where the scene measured quality but no mode has a JOD against the truth (a frame
/// too small for ColorVideoVDP): the gate has no JOD check of it, and says so.
fn unscored_note(scene: &SceneRecord) -> Option<String> {
    let judged = scene.modes.iter().filter_map(|mode| mode.vs_ground_truth.as_ref());
    let unscored =
        scene.jod_display.is_some() && judged.clone().count() > 0 && judged.clone().all(|q| q.jod.is_none());
    unscored.then(|| {
        let size = scene.resolution.map_or("?".into(), |[w, h]| format!("{w}×{h}"));
        format!(
            "{}: JOD not measured (its frame, {size}, is smaller than ColorVideoVDP scores): no JOD check",
            scene.name
        )
    })
}

/// Notes on modes whose place on one of the scene's error-against-run-time fronts was decided
/// both in the baseline and now, and differently: informational, since a front moves with any
/// mode's time or error. A place undecided in either says nothing.
fn front_notes(scene: &SceneRecord, baseline: &Baseline) -> Vec<String> {
    let mut notes = Vec::new();
    for mode in &scene.modes {
        let Some(then) = baseline.times.get(&mode.mode) else { continue };
        for (key, now) in &mode.fronts {
            let Some((metric, index)) = vocabulary::keyed(key) else { continue };
            let along = match scene.sequences.get(index).filter(|_| metric.source == Source::Sequence) {
                Some(sequence) => format!(" at {}", sequence.speed()),
                None => String::new(),
            };
            let front = format!("the front of {}{along}", metric.label);
            match front_change(then.fronts.get(key).copied(), now.verdict) {
                Some(FrontChange::Left) => notes.push(format!(
                    "{}: {} left {front}: {}",
                    scene.name,
                    mode.mode,
                    now.describe(metric.unit())
                )),
                Some(FrontChange::Joined) => {
                    notes.push(format!("{}: {} joined {front}", scene.name, mode.mode))
                }
                None => {}
            }
        }
    }
    notes
}

/// A place on a front that both a baseline and a run decided, and differently.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum FrontChange {
    Left,
    Joined,
}

/// What a note says of a place that was `then` and is `now`: nothing where either is undecided
/// (the rounds did not settle it, so its change is no news) or where the baseline had none.
fn front_change(then: Option<FrontVerdict>, now: FrontVerdict) -> Option<FrontChange> {
    match (then?, now) {
        (FrontVerdict::Front, FrontVerdict::Behind) => Some(FrontChange::Left),
        (FrontVerdict::Behind, FrontVerdict::Front) => Some(FrontChange::Joined),
        _ => None,
    }
}

fn status_check(scene: &str, mode: &str, outcome: Outcome, detail: &str) -> Check {
    Check::new(scene, mode, "status", outcome, detail.into())
}

/// The checks of one scene: `processes` are its records in each process of the run (the
/// first gives the quality numbers), `baseline` its committed baseline; time is compared only
/// where the run is `timed`.
fn compare_scene(
    processes: &[&SceneRecord],
    baseline: &Baseline,
    (same_platform, timed): (bool, bool),
    notes: &mut Vec<String>,
) -> Vec<Check> {
    let (scene, then) = (processes[0], baseline);
    if scene.resolution != then.resolution {
        let show = |r: Option<[u32; 2]>| r.map_or("?".into(), |[w, h]| format!("{w}×{h}"));
        let detail = format!(
            "rendered at {}, the baseline at {}: not comparable; re-bless",
            show(scene.resolution),
            show(then.resolution)
        );
        return scene
            .modes
            .iter()
            .map(|m| status_check(&scene.name, &m.mode, Outcome::Failed, &detail))
            .collect();
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
    let common: Vec<&ModeRecord> =
        scene.modes.iter().filter(|m| m.status == Status::Ok && then.mode(&m.mode).is_some()).collect();
    let plain: Vec<&str> = common.iter().filter(|m| !m.stalled).map(|m| m.mode.as_str()).collect();
    let anchor_modes =
        if plain.len() >= 2 { plain } else { common.iter().map(|m| m.mode.as_str()).collect() };
    let blessed = baseline.processes();
    let mut checks = Vec::new();
    for mode in &scene.modes {
        let Some(old) = then.mode(&mode.mode) else {
            checks.push(status_check(&scene.name, &mode.mode, Outcome::New, "not in the baseline"));
            continue;
        };
        if mode.status != Status::Ok {
            let error = mode.error.as_deref().unwrap_or("the mode failed");
            checks.push(status_check(&scene.name, &mode.mode, Outcome::Failed, error));
            continue;
        }
        let context = ModeContext {
            scene,
            processes,
            blessed: &blessed,
            mode,
            old,
            tolerances,
            same_platform,
            anchor_modes: &anchor_modes,
        };
        checks.extend(context.quality_checks());
        if timed {
            checks.extend(context.time_checks());
        }
    }
    // Green means compared in full: a run without the sequence its baseline holds compared less.
    if !then.sequences.is_empty() && scene.sequence().is_none() {
        let detail = "the baseline holds the scene's sequence, the run rendered none (--sequences off?)";
        checks.push(status_check(&scene.name, "*", Outcome::Missing, detail));
    }
    checks.extend(sequence_lengths(scene, then));
    for old in then.modes.keys() {
        if scene.mode(old).is_none() {
            checks.push(status_check(&scene.name, old, Outcome::Missing, "not in the run"));
        }
    }
    checks
}

/// Means over other frames are other numbers: a sequence cut short (or of another length) is no
/// comparison of the baseline's, and fails.
fn sequence_lengths(scene: &SceneRecord, then: &Baseline) -> Vec<Check> {
    let mut checks = Vec::new();
    for (index, (now, before)) in scene.sequences.iter().zip(&then.sequences).enumerate() {
        let (frames, frames_then) = ((now.frames, now.frames_done), (before.frames, before.frames_done));
        if frames != frames_then {
            let detail = format!(
                "sequence {} ({}): {} of {} frames rendered, the baseline's {} of {}: its means are over other frames",
                index + 1,
                now.speed(),
                frames.1,
                frames.0,
                frames_then.1,
                frames_then.0
            );
            checks.push(status_check(&scene.name, "*", Outcome::Failed, &detail));
        }
    }
    checks
}

#[cfg(test)]
mod tests {
    use super::time::process_spread;
    use super::{FrontChange, FrontVerdict, front_change};

    #[test]
    fn only_a_place_decided_twice_and_differently_is_a_note() {
        use FrontVerdict::{Behind, Front, Undecided};
        assert_eq!(front_change(Some(Front), Behind), Some(FrontChange::Left));
        assert_eq!(front_change(Some(Behind), Front), Some(FrontChange::Joined));
        for (then, now) in
            [(Some(Front), Undecided), (Some(Undecided), Front), (Some(Behind), Behind), (None, Front)]
        {
            assert_eq!(front_change(then, now), None, "{then:?} then, {now:?} now");
        }
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
}
