//! Time against the base build: the run's processes and the base build's, measured on one
//! machine in one job (`ci/gate.sh` alternates them), compared with the process as the unit of
//! evidence. In-run ratios do not travel between hosts (a stalled mode against plain ones, or
//! adaptive against its reference, shifts 15–40 % from one CPU generation to the next), and
//! on one host some modes land in a different state per process (a 36 % jump between two
//! processes of one build), far beyond the frame-to-frame noise an interval over frames
//! describes. So each process contributes one number per mode and metric, the median of its
//! frames, and the shift between the two builds is the Hodges–Lehmann estimate over those
//! numbers with its Moses interval.
//!
//! Each time is decided twice: per scene, and pooled over the scenes ([`super::pooled`]), the
//! question a change to one pass poses ("did this pass get slower?") asked with all the
//! evidence the gate holds. A check whose first processes point past its tolerance (regressed,
//! or noisy with its interval wholly above 0) is a *suspect*: its scenes are measured again in
//! fresh processes and it is decided once more ([`confirm`]).

use crate::baseline::BaselineSet;
use crate::measure::stats::Rounds;
use crate::record::vocabulary::TimeMetric;
use crate::record::{ModeRecord, RunRecord, SceneRecord, Status};

use super::pooled;
use super::request::Confirmation;
use super::series::{Series, median};
use super::verdict::{Against, Check, Outcome};

/// Passes shorter than this in the base build are not checked on their own: at a few tenths of
/// a millisecond a pass is mostly submission and timer, and its slowdown cannot hide much.
pub const PASS_MIN_MS: f64 = 0.5;

/// Passes that take more than this share of their frame in the base build are not checked on
/// their own: the frame's check sees their slowdown (a quarter more in half the frame moves it
/// by an eighth), and the rest of their frame is too short to divide by steadily.
pub const PASS_MAX_SHARE: f64 = 0.5;

/// The checks of every mode that ran ok in the first process of `runs` and in the base's
/// processes: per scene `relative_time`, `time_vs_reference` (adaptive modes) and `frame_time`,
/// each against the time-ratio tolerance of the scene's baseline (its run's when it has none),
/// then each of them and each `pass_time:<pass>` pooled over the scenes ([`pooled::decide`]; a
/// pass that runs in one scene only is decided in it). The run's processes that did
/// other work than the base's between their rounds (quality measured where the base timed
/// alone) give no time: [`timing_processes`].
pub(super) fn checks(
    runs: &[&RunRecord],
    base: &[&RunRecord],
    baselines: &BaselineSet,
    notes: &mut Vec<String>,
) -> Vec<Check> {
    pooled::decide(&all_series(runs, base, baselines, notes))
}

/// Every time of every mode of every scene that `runs` (its first process giving the scenes and
/// modes) and `base` both timed ok.
fn all_series(
    runs: &[&RunRecord],
    base: &[&RunRecord],
    baselines: &BaselineSet,
    notes: &mut Vec<String>,
) -> Vec<Series> {
    let timing = timing_processes(runs, base, notes);
    let mut untimed = std::collections::BTreeSet::new();
    let mut series = Vec::new();
    for scene in runs[0].scenes.iter().filter(|s| s.status == Status::Ok) {
        let side = Side { head: records(&timing, &scene.name), base: records(base, &scene.name) };
        if side.present(&side.head).is_empty() || side.present(&side.base).is_empty() {
            let which = if side.present(&side.base).is_empty() {
                "the base build"
            } else {
                "the run's timing processes"
            };
            notes.push(format!(
                "{}: not rendered ok by {which}: its time is not compared with it",
                scene.name
            ));
            continue;
        }
        let tolerance = baselines.scene(&scene.name).map_or(scene.gate, |b| b.gate).time_ratio;
        let bound = (1.0 + tolerance).ln();
        let anchors = side.anchor_modes();
        for mode in scene.modes.iter().filter(|m| m.status == Status::Ok) {
            let id = mode.mode.as_str();
            let ok = |record: &&SceneRecord| record.mode(id).is_some_and(|m| m.status == Status::Ok);
            if !side.present(&side.base).iter().all(ok) || !side.present(&side.head).iter().any(ok) {
                untimed.insert(id.to_string());
                continue;
            }
            series.extend(mode_series(&scene.name, &side, &anchors, bound, mode));
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
    series
}

/// Mode `id`'s frames in `record`, each as its pass `pass`'s time and the rest of the frame.
fn pass_and_rest(record: &SceneRecord, id: &str, pass: &str) -> Option<Vec<(f64, f64)>> {
    let mode = record.mode(id)?;
    let pass = mode.passes.iter().find(|p| p.name == pass)?;
    let frame = &mode.frame_ms.as_ref()?.samples;
    Some(pass.ms.samples.iter().zip(frame).map(|(&pass, &frame)| (pass, frame - pass)).collect())
}

/// The passes of mode `id` checked on their own: those that take at least [`PASS_MIN_MS`] and
/// at most [`PASS_MAX_SHARE`] of their frame in the base build, so that a regression inside a
/// pass is caught where the frame hides it (a fifth of the frame slowed by a quarter moves the
/// frame by 5 %). What is compared is the pass's time over the rest of its own frame: a process
/// that lands slow or fast lands so in every pass of a frame, and the ratio cancels that, while
/// a slower pass moves it by its whole slowdown (docs/gate.md has the false alarms and the
/// slowdowns found on recorded gates).
fn checked_passes(side: &Side, id: &str) -> Vec<String> {
    let Some(first) = side.present(&side.head).first().and_then(|s| s.mode(id)) else { return Vec::new() };
    first
        .passes
        .iter()
        .filter_map(|pass| {
            let base: Vec<(f64, f64)> = side
                .present(&side.base)
                .iter()
                .filter_map(|record| pass_and_rest(record, id, &pass.name))
                .flatten()
                .collect();
            let ms = median(base.iter().map(|&(pass, _)| pass).collect())?;
            let share = median(base.iter().map(|&(pass, rest)| pass / (pass + rest)).collect())?;
            (ms >= PASS_MIN_MS && share <= PASS_MAX_SHARE).then(|| pass.name.clone())
        })
        .collect()
}

/// Whether the first processes point a check past its tolerance: regressed, or noisy with its
/// whole interval above 0 (the estimate past the tolerance, the interval not wholly). A suspect
/// is measured again before the gate decides it ([`confirm`]).
pub(super) fn is_suspect(check: &Check) -> bool {
    check.against == Against::Base
        && match check.outcome {
            Outcome::Regressed => true,
            Outcome::Noisy => check.interval.is_some_and(|[low, _]| low > 0.0),
            _ => false,
        }
}

/// The manifests of the scenes to measure again in fresh processes: each suspect's scene, and
/// every scene a suspect pooled over the scenes may draw on (where its mode ran ok, with the
/// pass for a pass's time); each once, in the run's order.
pub(super) fn manifests_to_confirm(checks: &[Check], run: &RunRecord) -> Vec<String> {
    let suspects: Vec<&Check> = checks.iter().filter(|c| is_suspect(c)).collect();
    let draws_on = |scene: &SceneRecord, check: &Check| {
        let pass = check.metric.strip_prefix(TimeMetric::Pass.id());
        scene.mode(&check.mode).is_some_and(|mode| {
            mode.status == Status::Ok && pass.is_none_or(|pass| mode.passes.iter().any(|p| p.name == pass))
        })
    };
    let wanted = |scene: &SceneRecord| {
        suspects
            .iter()
            .any(|s| s.scene == scene.name || (s.scene == pooled::ALL_SCENES && draws_on(scene, s)))
    };
    run.scenes.iter().filter(|s| wanted(s)).map(|s| s.manifest.clone()).collect()
}

/// Decides each suspect of `checks` again, once `fresh` processes of both builds have measured
/// its scenes: on the first processes and the fresh ones together, so that the interval
/// narrows, and against the fresh ones alone, so that the first cannot carry the verdict by
/// themselves. A suspect is regressed when, taken together, its whole interval lies past the
/// tolerance and the fresh processes' own estimate lies past it too, with their own interval
/// wholly above 0 (a slowdown they show, not one they only lean to). A first-pass regression
/// that is not found again becomes `noisy`; a noisy suspect takes the outcome of all its
/// processes together (never `regressed` without the fresh estimate). A first-pass regression
/// that the fresh processes did not measure, or could not decide, stands. Other checks are left
/// alone: the fresh processes test only what the first ones found.
pub(super) fn confirm(
    checks: &mut [Check],
    first: (&[&RunRecord], &[&RunRecord]),
    fresh: Confirmation,
    baselines: &BaselineSet,
) {
    let (fresh_runs, fresh_base): (Vec<&RunRecord>, Vec<&RunRecord>) =
        (fresh.runs.iter().collect(), fresh.base.iter().collect());
    let again = self::checks(&fresh_runs, &fresh_base, baselines, &mut Vec::new());
    let all_runs: Vec<&RunRecord> = first.0.iter().copied().chain(fresh_runs.iter().copied()).collect();
    let all_base: Vec<&RunRecord> = first.1.iter().copied().chain(fresh_base.iter().copied()).collect();
    let together = self::checks(&all_runs, &all_base, baselines, &mut Vec::new());
    for check in checks.iter_mut().filter(|c| is_suspect(c)) {
        let same = |c: &&Check| c.scene == check.scene && c.mode == check.mode && c.metric == check.metric;
        let decided = |c: &&Check| c.outcome != Outcome::Insufficient;
        let (Some(together), Some(again)) =
            (together.iter().find(same).filter(decided), again.iter().find(same).filter(decided))
        else {
            check.detail = format!(
                "{}; not decided again by the {} fresh processes of the run and {} of the base",
                check.detail,
                fresh.runs.len(),
                fresh.base.len()
            );
            continue;
        };
        let bound = check.threshold.map_or(f64::INFINITY, f64::ln_1p);
        let outcome = reconsidered(check.outcome, past_together(together, bound), shows_past(again, bound));
        let verb = if outcome == Outcome::Regressed { "found again" } else { "not found again" };
        let numbers = |c: &Check| c.detail.split_once(": ").map_or(c.detail.clone(), |(_, n)| n.to_string());
        let fresh_change = again.change.map_or("?".into(), |c| format!("{:+.1}%", c * 100.0));
        check.detail = format!(
            "{}; {verb} with fresh processes: first and fresh together {}; the fresh alone {fresh_change}",
            check.detail,
            numbers(together)
        );
        check.outcome = outcome;
        check.change = together.change;
        check.interval = together.interval;
        check.baseline = together.baseline;
        check.current = together.current;
    }
}

/// The outcome of a suspect decided on all its processes together (`together`), as
/// [`reconsidered`] takes it. Pooled over the scenes, a slowdown that all the processes show
/// (their interval above 0) and estimate past the tolerance counts as past it: the pool asks
/// the question a change to a pass poses, with the narrowest interval the gate has, and the
/// fresh processes must show it too.
fn past_together(together: &Check, bound: f64) -> Outcome {
    match together.outcome {
        Outcome::Noisy if together.scene == pooled::ALL_SCENES && shows_past(together, bound) => {
            Outcome::Regressed
        }
        outcome => outcome,
    }
}

/// Whether `check` shows a slowdown past the tolerance `bound`: its estimate past it and its
/// interval wholly above 0.
fn shows_past(check: &Check, bound: f64) -> bool {
    check.change.is_some_and(|change| change.ln_1p() > bound)
        && check.interval.is_some_and(|[low, _]| low > 0.0)
}

/// What a suspect whose first outcome was `first` becomes once all its processes together
/// decided `together`, the fresh ones alone showing it past the tolerance or not
/// (`fresh_past`): regressed where both say so; else a first-pass regression is noisy, and a
/// noisy suspect takes the outcome of all its processes, short of regressed.
fn reconsidered(first: Outcome, together: Outcome, fresh_past: bool) -> Outcome {
    match (together, fresh_past) {
        (Outcome::Regressed, true) => Outcome::Regressed,
        (Outcome::Regressed, false) => Outcome::Noisy,
        _ if first == Outcome::Regressed => Outcome::Noisy,
        (outcome, _) => outcome,
    }
}

/// The run's processes whose time is compared with the base's: those that measured as the
/// base's did. Where the base's processes timed their modes alone (`--quality off`), a process
/// that also measured quality (the gate's first, which gives the verdict its quality) did other
/// work between its rounds and is left out.
fn timing_processes<'a>(
    runs: &[&'a RunRecord],
    base: &[&RunRecord],
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

/// Every time of `mode` in `scene` that the gate compares: `relative_time`, `time_vs_reference`
/// (adaptive modes), `frame_time` and `pass_time:<pass>` of its checked passes.
fn mode_series(scene: &str, side: &Side, anchors: &[&str], bound: f64, mode: &ModeRecord) -> Vec<Series> {
    let id = mode.mode.as_str();
    let mut series = Vec::new();
    let mut add = |metric: String,
                   what: String,
                   (unit, alone): (&'static str, bool),
                   per_process: &dyn Fn(&SceneRecord) -> Option<f64>| {
        series.push(Series {
            scene: scene.to_string(),
            mode: id.to_string(),
            metric,
            what,
            unit,
            bound,
            head: side.head.iter().map(|r| r.and_then(per_process)).collect(),
            base: side.base.iter().map(|r| r.and_then(per_process)).collect(),
            alone,
        });
    };
    let relative = |record: &SceneRecord| {
        let anchor = record.round_anchor(anchors, id)?;
        let samples = &record.mode(id)?.frame_ms.as_ref()?.samples;
        median(samples.iter().zip(&anchor).map(|(s, a)| s.ln() - a).collect())
    };
    let what = "frame time over the geometric mean of the round's other unstalled modes";
    add(TimeMetric::Relative.id().into(), what.into(), ("×", true), &relative);
    if let Some(cost) = &mode.adaptive {
        let reference = cost.reference.as_str();
        let ratio = |record: &SceneRecord| {
            median(record.paired_ratios(id, reference)?.iter().map(|r| r.ln()).collect())
        };
        let what = format!("frame time over {reference}'s in the same round");
        add(TimeMetric::VsReference.id().into(), what, ("×", true), &ratio);
    }
    let frame = |record: &SceneRecord| {
        median(record.mode(id)?.frame_ms.as_ref()?.samples.iter().map(|s| s.ln()).collect())
    };
    add(TimeMetric::Frame.id().into(), "frame time".into(), ("ms", true), &frame);
    // A pass is decided pooled over the scenes: one scene's processes cannot judge it (the
    // module documentation of `pooled` says why).
    for pass in checked_passes(side, id) {
        let per_process = |record: &SceneRecord| {
            let ratios = pass_and_rest(record, id, &pass)?.into_iter().filter(|&(_, rest)| rest > 0.0);
            median(ratios.map(|(pass, rest)| pass.ln() - rest.ln()).collect())
        };
        let what = format!("{pass} pass time over the rest of its frame");
        add(format!("{}{pass}", TimeMetric::Pass.id()), what, ("×", false), &per_process);
    }
    series
}

/// Per process of `runs`, its record of scene `name` where it rendered it ok.
fn records<'a>(runs: &[&'a RunRecord], name: &str) -> Vec<Option<&'a SceneRecord>> {
    runs.iter().map(|run| run.scenes.iter().find(|s| s.name == name && s.status == Status::Ok)).collect()
}

/// One scene in the run's processes and in the base build's, a record per process where it
/// rendered the scene ok.
struct Side<'a> {
    head: Vec<Option<&'a SceneRecord>>,
    base: Vec<Option<&'a SceneRecord>>,
}

impl<'a> Side<'a> {
    /// The records that are there.
    fn present(&self, records: &[Option<&'a SceneRecord>]) -> Vec<&'a SceneRecord> {
        records.iter().flatten().copied().collect()
    }

    /// The unstalled modes that ran ok in every process of both builds (every such mode when
    /// fewer than two are unstalled): the anchor of `relative_time`, as against baselines.
    fn anchor_modes(&self) -> Vec<&'a str> {
        let (head, base) = (self.present(&self.head), self.present(&self.base));
        let first = head[0];
        let everywhere =
            |id: &str| head.iter().chain(&base).all(|s| s.mode(id).is_some_and(|m| m.status == Status::Ok));
        let common: Vec<_> = first.modes.iter().filter(|m| everywhere(&m.mode)).collect();
        let plain: Vec<&str> = common.iter().filter(|m| !m.stalled).map(|m| m.mode.as_str()).collect();
        if plain.len() >= 2 { plain } else { common.iter().map(|m| m.mode.as_str()).collect() }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A suspect is regressed only where all its processes together and the fresh ones alone
    /// both point past the tolerance; otherwise no more than noisy.
    #[test]
    fn a_suspect_stands_only_where_the_fresh_processes_point_the_same_way() {
        use Outcome::*;
        for first in [Regressed, Noisy] {
            assert_eq!(reconsidered(first, Regressed, true), Regressed);
            assert_eq!(reconsidered(first, Regressed, false), Noisy, "all together, not the fresh alone");
            assert_eq!(reconsidered(first, Noisy, true), Noisy, "the fresh alone, not all together");
        }
        assert_eq!(reconsidered(Regressed, Unchanged, false), Noisy, "a first regression stays in view");
        assert_eq!(reconsidered(Noisy, Unchanged, false), Unchanged, "more processes settle a noisy one");
    }

    /// All the processes together showing a pooled pass 13 % slower (interval +4 … +22 %, across
    /// the 10 % tolerance) count as past it; one scene's check so, or a pooled one whose interval
    /// reaches below 0 or whose estimate is within the tolerance, does not.
    #[test]
    fn a_pooled_slowdown_shown_past_the_tolerance_counts_as_past_it() {
        let bound = 0.1f64.ln_1p();
        let noisy = |scene: &str, change: f64, low: f64| Check {
            change: Some(change),
            interval: Some([low, 0.22]),
            ..Check::new(scene, "fxaa", "pass_time:fxaa", Outcome::Noisy, String::new())
        };
        assert_eq!(past_together(&noisy(pooled::ALL_SCENES, 0.13, 0.04), bound), Outcome::Regressed);
        assert_eq!(past_together(&noisy("wire", 0.13, 0.04), bound), Outcome::Noisy, "one scene");
        assert_eq!(past_together(&noisy(pooled::ALL_SCENES, 0.13, -0.01), bound), Outcome::Noisy, "0 inside");
        assert_eq!(past_together(&noisy(pooled::ALL_SCENES, 0.08, 0.01), bound), Outcome::Noisy, "within");
        assert!(shows_past(&noisy("wire", 0.13, 0.04), bound));
        assert!(!shows_past(&noisy("wire", 0.13, -0.01), bound), "the fresh must show it, not lean to it");
    }
}
