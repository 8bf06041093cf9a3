//! Time against the base build: the run's processes and the base build's, measured on one
//! machine in one job (`ci/gate.sh` alternates them), compared with the process as the unit of
//! evidence. In-run ratios do not travel between hosts (a stalled mode against plain ones, or
//! adaptive against its reference, shifts 15–40 % from one CPU generation to the next), and
//! on one host some modes land in a different state per process (a 36 % jump between two
//! processes of one build), far beyond the frame-to-frame noise an interval over frames
//! describes. So each process contributes one number per mode and metric, the median of its
//! frames, and the shift between the two builds is the Hodges–Lehmann estimate over those
//! numbers with its Moses interval.

use crate::baseline::BaselineSet;
use crate::record::{RunRecord, SceneRecord, Status};
use crate::stats::{Rounds, Shift, Summary};
use crate::vocabulary::TimeMetric;

use super::request::Confirmation;
use super::time::decide;
use super::verdict::{Against, CONFIDENCE, Check, MIN_PROCESSES, Outcome};

/// Passes shorter than this in the base build are not checked on their own: at a few tenths of
/// a millisecond a pass is mostly submission and timer, and its slowdown cannot hide much.
pub const PASS_MIN_MS: f64 = 0.5;

/// Passes that take more than this share of their frame in the base build are not checked on
/// their own: the frame's check sees their slowdown (a quarter more in half the frame moves it
/// by an eighth), and the rest of their frame is too short to divide by steadily.
pub const PASS_MAX_SHARE: f64 = 0.5;

/// The checks of every mode that ran ok in the first process of `runs` and in the base's
/// processes: `relative_time`, `time_vs_reference` (adaptive modes) and `frame_time`, each
/// against the time-ratio tolerance of the scene's baseline (its run's when it has none). The
/// run's processes that did other work than the base's between their rounds (quality measured
/// where the base timed alone) give no time: [`timing_processes`].
pub(super) fn checks(
    runs: &[RunRecord],
    base: &[RunRecord],
    baselines: &BaselineSet,
    notes: &mut Vec<String>,
) -> Vec<Check> {
    let timing = timing_processes(runs, base, notes);
    let base: Vec<&RunRecord> = base.iter().collect();
    let mut untimed = std::collections::BTreeSet::new();
    let mut checks = Vec::new();
    for scene in runs[0].scenes.iter().filter(|s| s.status == Status::Ok) {
        let head = records(&timing, &scene.name);
        let then = records(&base, &scene.name);
        if then.is_empty() || head.is_empty() {
            let side = if then.is_empty() { "the base build" } else { "the run's timing processes" };
            notes
                .push(format!("{}: not rendered ok by {side}: its time is not compared with it", scene.name));
            continue;
        }
        let tolerance = baselines.scene(&scene.name).map_or(scene.gate, |b| b.gate).time_ratio;
        let side = Side { head: &head, base: &then };
        let anchors = side.anchor_modes();
        let bound = (1.0 + tolerance).ln();
        for mode in scene.modes.iter().filter(|m| m.status == Status::Ok) {
            let id = mode.mode.as_str();
            let ok = |record: &&SceneRecord| record.mode(id).is_some_and(|m| m.status == Status::Ok);
            if !then.iter().all(ok) || !head.iter().any(ok) {
                untimed.insert(id.to_string());
                continue;
            }
            let template = |metric: &str| Check {
                against: Against::Base,
                unit: "relative".into(),
                ..Check::new(&scene.name, id, metric, Outcome::Unchanged, String::new())
            };
            let relative = |record: &SceneRecord| {
                let anchor = record.round_anchor(&anchors, id)?;
                let samples = &record.mode(id)?.frame_ms.as_ref()?.samples;
                median(samples.iter().zip(&anchor).map(|(s, a)| s.ln() - a).collect())
            };
            let what = "frame time over the geometric mean of the round's other unstalled modes";
            checks.extend(side.check(relative, bound, what, "×", template(TimeMetric::Relative.id())));
            if let Some(cost) = &mode.adaptive {
                let reference = cost.reference.as_str();
                let ratio = |record: &SceneRecord| {
                    median(record.paired_ratios(id, reference)?.iter().map(|r| r.ln()).collect())
                };
                let what = format!("frame time over {reference}'s in the same round");
                checks.extend(side.check(ratio, bound, &what, "×", template(TimeMetric::VsReference.id())));
            }
            let frame = |record: &SceneRecord| {
                median(record.mode(id)?.frame_ms.as_ref()?.samples.iter().map(|s| s.ln()).collect())
            };
            checks.extend(side.check(frame, bound, "frame time", "ms", template(TimeMetric::Frame.id())));
            checks.extend(pass_checks(&side, id, bound, template));
        }
    }
    if !untimed.is_empty() {
        let ids: Vec<String> = untimed.into_iter().collect();
        notes.push(format!(
            "time against the base build: not compared for these modes, which the base's processes or the \
             run's timing processes did not time ok: {}",
            ids.join(", ")
        ));
    }
    checks
}

/// One check per pass of mode `id` that takes at least [`PASS_MIN_MS`] and at most
/// [`PASS_MAX_SHARE`] of its frame in the base build, so that a regression inside a pass is
/// caught where the frame hides it (a fifth of the frame slowed by a quarter moves the frame
/// by 5 %). What is compared is the pass's time over the
/// rest of its own frame: a process that lands slow or fast lands so in every pass of a frame,
/// and the ratio cancels that, while a slower pass moves it by its whole slowdown (docs/gate.md
/// has the false alarms and the slowdowns found on recorded gates).
fn pass_checks(side: &Side, id: &str, bound: f64, template: impl Fn(&str) -> Check) -> Vec<Check> {
    // Each frame's pass time and the rest of the frame, paired by frame.
    let frames = |record: &SceneRecord, pass: &str| -> Option<Vec<(f64, f64)>> {
        let mode = record.mode(id)?;
        let pass = mode.passes.iter().find(|p| p.name == pass)?;
        let frame = &mode.frame_ms.as_ref()?.samples;
        Some(pass.ms.samples.iter().zip(frame).map(|(&pass, &frame)| (pass, frame - pass)).collect())
    };
    let Some(first) = side.head[0].mode(id) else { return Vec::new() };
    first
        .passes
        .iter()
        .filter(|pass| {
            let base: Vec<(f64, f64)> =
                side.base.iter().filter_map(|record| frames(record, &pass.name)).flatten().collect();
            let ms = median(base.iter().map(|&(pass, _)| pass).collect());
            let share = median(base.iter().map(|&(pass, rest)| pass / (pass + rest)).collect());
            ms.is_some_and(|ms| ms >= PASS_MIN_MS) && share.is_some_and(|share| share <= PASS_MAX_SHARE)
        })
        .filter_map(|pass| {
            let per_process = |record: &SceneRecord| {
                let ratios = frames(record, &pass.name)?.into_iter().filter(|&(_, rest)| rest > 0.0);
                median(ratios.map(|(pass, rest)| pass.ln() - rest.ln()).collect())
            };
            let what = format!("{} pass time over the rest of its frame", pass.name);
            side.check(
                per_process,
                bound,
                &what,
                "×",
                template(&format!("{}{}", TimeMetric::Pass.id(), pass.name)),
            )
        })
        .collect()
}

/// The manifests of the scenes of `run` with a time regression against the base build, each
/// once, in the run's order.
pub(super) fn regressed_manifests(checks: &[Check], run: &RunRecord) -> Vec<String> {
    let regressed = |scene: &SceneRecord| {
        checks
            .iter()
            .any(|c| c.against == Against::Base && c.outcome == Outcome::Regressed && c.scene == scene.name)
    };
    run.scenes.iter().filter(|s| regressed(s)).map(|s| s.manifest.clone()).collect()
}

/// Decides each time regression of `checks` again on the fresh processes alone: it stands when
/// they find it again, or cannot decide (too few of them, the scene or mode not among them);
/// it becomes `noisy` when they decide that it did not regress. Other checks are left alone:
/// the fresh processes test only what the first ones found.
pub(super) fn confirm(checks: &mut [Check], fresh: Confirmation, baselines: &BaselineSet) {
    let again = self::checks(fresh.runs, fresh.base, baselines, &mut Vec::new());
    for check in checks.iter_mut().filter(|c| c.outcome == Outcome::Regressed) {
        let same = |c: &&Check| c.scene == check.scene && c.mode == check.mode && c.metric == check.metric;
        let Some(again) = again.iter().find(same) else {
            check.detail = format!(
                "{}; not measured again by the {} fresh processes of the run",
                check.detail,
                fresh.runs.len()
            );
            continue;
        };
        let (outcome, verb) = match again.outcome {
            Outcome::Regressed => (Outcome::Regressed, "found again"),
            Outcome::Insufficient => (Outcome::Regressed, "not decided"),
            _ => (Outcome::Noisy, "not found again"),
        };
        // The fresh detail without its "<what> against the base build: " lead, which the
        // first detail already says.
        let numbers = again.detail.split_once(": ").map_or(again.detail.as_str(), |(_, numbers)| numbers);
        check.outcome = outcome;
        check.detail = format!("{}; {verb} in fresh processes: {numbers}", check.detail);
    }
}

/// The run's processes whose time is compared with the base's: those that measured as the
/// base's did. Where the base's processes timed their modes alone (`--quality off`), a process
/// that also measured quality (the gate's first, which gives the verdict its quality) did other
/// work between its rounds and is left out.
fn timing_processes<'a>(
    runs: &'a [RunRecord],
    base: &[RunRecord],
    notes: &mut Vec<String>,
) -> Vec<&'a RunRecord> {
    let alone = base.iter().all(|run| !run.settings.quality);
    let (timing, measuring): (Vec<&RunRecord>, Vec<&RunRecord>) =
        runs.iter().partition(|run| !alone || !run.settings.quality);
    if !measuring.is_empty() {
        let ids: Vec<&str> = measuring.iter().map(|run| run.run_id.as_str()).collect();
        notes.push(format!(
            "time against the base build: {} measured quality too and gives no time (the base's processes timed alone)",
            ids.join(", ")
        ));
    }
    timing
}

/// The records of scene `name` that ran ok, one per process that has it.
fn records<'a>(runs: &[&'a RunRecord], name: &str) -> Vec<&'a SceneRecord> {
    runs.iter()
        .filter_map(|run| run.scenes.iter().find(|s| s.name == name && s.status == Status::Ok))
        .collect()
}

fn median(logs: Vec<f64>) -> Option<f64> {
    Summary::new(logs).map(|s| s.median)
}

/// One scene in the run's processes and in the base build's.
struct Side<'a> {
    head: &'a [&'a SceneRecord],
    base: &'a [&'a SceneRecord],
}

impl Side<'_> {
    /// The unstalled modes that ran ok in every process of both builds (every such mode when
    /// fewer than two are unstalled): the anchor of `relative_time`, as against baselines.
    fn anchor_modes(&self) -> Vec<&str> {
        let first = self.head[0];
        let everywhere = |id: &str| {
            self.head.iter().chain(self.base).all(|s| s.mode(id).is_some_and(|m| m.status == Status::Ok))
        };
        let common: Vec<_> = first.modes.iter().filter(|m| everywhere(&m.mode)).collect();
        let plain: Vec<&str> = common.iter().filter(|m| !m.stalled).map(|m| m.mode.as_str()).collect();
        if plain.len() >= 2 { plain } else { common.iter().map(|m| m.mode.as_str()).collect() }
    }

    /// One metric: `per_process` gives a process's log value; the head's against the base's.
    fn check(
        &self,
        per_process: impl Fn(&SceneRecord) -> Option<f64>,
        bound: f64,
        what: &str,
        unit: &str,
        template: Check,
    ) -> Option<Check> {
        let head: Vec<f64> = self.head.iter().filter_map(|s| per_process(s)).collect();
        let base: Vec<f64> = self.base.iter().filter_map(|s| per_process(s)).collect();
        let value = |logs: &[f64]| median(logs.to_vec()).map(f64::exp);
        let values = (value(&base)?, value(&head)?);
        if head.len() < MIN_PROCESSES || base.len() < MIN_PROCESSES {
            return Some(Check {
                outcome: Outcome::Insufficient,
                baseline: Some(values.0),
                current: Some(values.1),
                detail: format!(
                    "{what} against the base build: {} process(es) of the base and {} of the run, fewer than the \
                     {MIN_PROCESSES} on each side a time verdict needs",
                    base.len(),
                    head.len()
                ),
                ..template
            });
        }
        let shift = Shift::between(&head, &base, CONFIDENCE)?;
        let extra = format!(", over {} processes of the base and {} of the run", base.len(), head.len());
        let what = format!("{what} against the base build");
        Some(decide(shift, bound, values, unit, &what, &extra).into_check(template))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn four_processes_a_side_reach_the_confidence_three_do_not() {
        let base = [0.0, 0.01, -0.01, 0.005];
        let slower: Vec<f64> = base.iter().map(|x| x + 0.25).collect();
        let shift = Shift::between(&slower, &base, CONFIDENCE).unwrap();
        assert!(shift.level >= CONFIDENCE, "{shift:?}");
        let decided = decide(shift, 0.1f64.ln_1p(), (1.0, 1.28), "×", "t", "");
        assert_eq!(decided.outcome, Outcome::Regressed);
        let few = Shift::between(&slower[..3], &base[..3], CONFIDENCE).unwrap();
        assert!(few.level < CONFIDENCE, "three a side cannot reach 95%: {few:?}");
    }

    /// One head process of six landing 30% slower while the others do not move leaves the
    /// outcome `unchanged`: the Hodges–Lehmann estimate stays within the threshold, so the
    /// stray process is not called a regression.
    #[test]
    fn one_stray_process_makes_a_shift_noisy_not_regressed() {
        let base = [0.0, 0.01, -0.01, 0.005, 0.0, 0.002];
        // One head process landed 30% slower, as bimodal modes do; the others did not move.
        let head = [0.26, 0.01, -0.005, 0.0, 0.004, 0.003];
        let shift = Shift::between(&head, &base, CONFIDENCE).unwrap();
        let decided = decide(shift, 0.1f64.ln_1p(), (1.0, 1.0), "×", "t", "");
        assert_eq!(decided.outcome, Outcome::Unchanged, "{}", decided.detail);
    }
}
