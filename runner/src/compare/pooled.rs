//! One verdict per time of a mode across the scenes: did this pass (this frame) get slower?
//!
//! A change to one pass slows it in every scene that runs it, but each scene alone has four
//! processes a side, whose interval spans ±8–15 %: a true 15 % slowdown is then `noisy` in most
//! scenes, and whether the gate fails rests on one scene's interval happening to clear the
//! tolerance. Pooled, the scenes answer together.
//!
//! The process stays the unit of evidence. The scenes are not independent samples: a process
//! that lands slow lands slow in every scene (on recorded gates, the spread of a process's mean
//! over the scenes was 1.0–1.7 times what independent scenes would give for a pass's share of
//! its frame, and about twice for absolute frame time). So each process contributes one number,
//! the mean over the scenes of its log value in each (the scenes every process of both builds
//! timed, each with equal weight), and the two builds are compared on those numbers with the
//! same Hodges–Lehmann shift and Moses interval as one scene's time. Whatever the scenes share
//! within a process is in the spread of those numbers, and scenes that differ in their own
//! shift (a pass that costs more where there are more edges) are averaged, not assumed alike:
//! the estimate is the mean shift over the scenes. Its false-alarm rate is that of one scene's
//! check: under no change the processes of the two builds are exchangeable, and the interval's
//! coverage holds whatever the scenes do.
//!
//! A pass is decided only here (where it runs in two scenes or more), not in each scene: a pass
//! lands in one of several states per process and scene, far apart, and four processes a side
//! that happen to split so read as a slowdown of a third to a half, which fresh processes can
//! happen to repeat. On four recorded gates of one build pair, each scene's pass checks raised
//! a confirmed regression in two (walker's `compact`, 0.7 ms, took 0.043–0.06 or 0.08–0.086 of
//! the rest of its frame process by process in both builds; degenerate's `gbuffer` moved by
//! −57 … +142 % from mode to mode of one gate), and decided with another gate's processes as the
//! fresh ones, 5 of 12 pairings failed (3 with passes under 1 ms pooled); pooled, none did,
//! while a pass 15 % slower still fails the gate (docs/gate.md has the table).

use super::series::{Series, decide_processes};
use super::verdict::{Against, Check, Outcome};

/// The scene of a check pooled over the scenes.
pub(super) const ALL_SCENES: &str = "*";

/// The fewest scenes a pooled check draws on: with one, it is that scene's own check.
pub const MIN_SCENES: usize = 2;

/// Every check of `series`: each scene's, where the scene decides its time alone or no pooled
/// check of that time exists, then the pooled ones.
pub(super) fn decide(series: &[Series]) -> Vec<Check> {
    let pooled = checks(series);
    let pooled_over = |s: &&Series| pooled.iter().any(|c| c.mode == s.mode && c.metric == s.metric);
    let mut decided: Vec<Check> =
        series.iter().filter(|s| s.alone || !pooled_over(s)).filter_map(Series::check).collect();
    decided.extend(pooled);
    decided
}

/// One check per mode and time across the scenes of `series`, where at least [`MIN_SCENES`]
/// scenes were timed by every process that timed the mode's time in any: scene `*`, decided
/// against the largest of the scenes' tolerances.
pub(super) fn checks(series: &[Series]) -> Vec<Check> {
    let mut groups: Vec<Vec<&Series>> = Vec::new();
    for one in series {
        match groups.iter_mut().find(|g| g[0].mode == one.mode && g[0].metric == one.metric) {
            Some(group) => group.push(one),
            None => groups.push(vec![one]),
        }
    }
    groups.iter().filter_map(|group| pool(group)).collect()
}

/// The pooled check of one mode's time over `group`'s scenes.
fn pool(group: &[&Series]) -> Option<Check> {
    let first = group[0];
    // The processes of each build that timed the mode in some scene, and the scenes that every
    // one of them timed: a process is worth more than a scene.
    let timed = |values: fn(&Series) -> &[Option<f64>]| -> Vec<usize> {
        let processes = values(first).len();
        (0..processes)
            .filter(|&p| group.iter().any(|s| values(s).get(p).is_some_and(Option::is_some)))
            .collect()
    };
    let (head, base) = (timed(|s| &s.head), timed(|s| &s.base));
    let everywhere = |s: &&&Series| {
        head.iter().all(|&p| s.head.get(p).is_some_and(Option::is_some))
            && base.iter().all(|&p| s.base.get(p).is_some_and(Option::is_some))
    };
    let scenes: Vec<&Series> = group.iter().filter(everywhere).copied().collect();
    if scenes.len() < MIN_SCENES {
        return None;
    }
    let mean = |values: fn(&Series) -> &[Option<f64>], p: usize| {
        scenes.iter().filter_map(|s| values(s)[p]).sum::<f64>() / scenes.len() as f64
    };
    let head: Vec<f64> = head.iter().map(|&p| mean(|s| &s.head, p)).collect();
    let base: Vec<f64> = base.iter().map(|&p| mean(|s| &s.base, p)).collect();
    let bound = scenes.iter().map(|s| s.bound).fold(0.0, f64::max);
    let what = format!("{}, geometric mean over {} scenes", first.what, scenes.len());
    let template = Check {
        against: Against::Base,
        unit: "relative".into(),
        ..Check::new(ALL_SCENES, &first.mode, &first.metric, Outcome::Unchanged, String::new())
    };
    decide_processes(&head, &base, bound, &what, first.unit, template)
}

#[cfg(test)]
mod tests {
    use super::*;

    const TOLERANCE: f64 = 0.1;

    /// A deterministic noise in [−1, 1): the same for the same (scene, process, side).
    fn noise(scene: usize, process: usize, side: usize) -> f64 {
        let mut h =
            (scene as u64 * 0x9E37_79B9 + process as u64 * 0x85EB_CA6B + side as u64 * 0xC2B2_AE35) | 1;
        for _ in 0..3 {
            h ^= h >> 13;
            h = h.wrapping_mul(0x5DEE_CE66D);
        }
        (h % 2001) as f64 / 1000.0 - 1.0
    }

    /// `scenes` scenes of one pass, four processes a side: log values of `amplitude` noise per
    /// scene and process, plus `process_effect(p)` shared by every scene of head process `p`,
    /// the head slower by `shift(scene)` (a log ratio).
    fn series(
        scenes: usize,
        amplitude: f64,
        shift: impl Fn(usize) -> f64,
        process_effect: impl Fn(usize) -> f64,
    ) -> Vec<Series> {
        (0..scenes)
            .map(|s| Series {
                scene: format!("scene-{s}"),
                mode: "fxaa".into(),
                metric: "pass_time:fxaa".into(),
                what: "fxaa pass time over the rest of its frame".into(),
                unit: "×",
                bound: TOLERANCE.ln_1p(),
                head: (0..4)
                    .map(|p| Some(-1.5 + shift(s) + process_effect(p) + amplitude * noise(s, p, 0)))
                    .collect(),
                base: (0..4).map(|p| Some(-1.5 + amplitude * noise(s, p, 1))).collect(),
                alone: true,
            })
            .collect()
    }

    fn outcome_of(series: &[Series]) -> Outcome {
        let pooled = checks(series);
        assert_eq!(pooled.len(), 1, "{pooled:?}");
        assert_eq!(pooled[0].scene, ALL_SCENES);
        pooled[0].outcome
    }

    fn per_scene(series: &[Series]) -> Vec<Outcome> {
        series.iter().filter_map(Series::check).map(|c| c.outcome).collect()
    }

    /// The gate: a pass 15 % slower in each of 17 scenes, each scene's four processes a
    /// side spread ±10 %. Scene by scene it is mostly noisy; pooled it is a regression.
    #[test]
    fn a_pass_slower_in_every_scene_regresses_where_each_scene_alone_is_noisy() {
        let slower = series(17, 0.1, |_| 1.15f64.ln(), |_| 0.0);
        let alone = per_scene(&slower);
        let regressed = alone.iter().filter(|o| **o == Outcome::Regressed).count();
        assert!(regressed <= 3, "most scenes alone cannot tell: {alone:?}");
        assert_eq!(outcome_of(&slower), Outcome::Regressed);
    }

    /// Scenes that differ in their own shift (+5 % in some, +25 % in the others) are averaged,
    /// not assumed alike: the pooled estimate is their mean, and it regresses.
    #[test]
    fn scenes_with_their_own_shifts_pool_to_their_mean() {
        let shift = |s: usize| if s.is_multiple_of(2) { 1.05f64.ln() } else { 1.25f64.ln() };
        let mixed = series(16, 0.03, shift, |_| 0.0);
        let pooled = &checks(&mixed)[0];
        let mean = (1.05f64.ln() + 1.25f64.ln()) / 2.0;
        assert!((pooled.change.unwrap().ln_1p() - mean).abs() < 0.02, "{pooled:?}");
        assert_eq!(pooled.outcome, Outcome::Regressed);
    }

    /// The case that would fool a pooling with the scene as the unit: no change, but two of the
    /// head's four processes landed 20 % slow in every scene (a process's state, as bimodal
    /// modes show). Every scene then points the same way; the processes do not agree, and the
    /// pooled check does not regress.
    #[test]
    fn processes_that_land_slow_in_every_scene_are_no_regression() {
        let unlucky = series(17, 0.02, |_| 0.0, |p| if p < 2 { 1.2f64.ln() } else { 0.0 });
        let positive = unlucky.iter().filter_map(Series::check).filter(|c| c.change.unwrap() > 0.0).count();
        assert_eq!(positive, 17, "every scene alone points up");
        assert_ne!(outcome_of(&unlucky), Outcome::Regressed);
    }

    /// The false alarm a pass raises in one scene: no change, but in one scene the base's four
    /// processes landed in the pass's fast state and the run's in its slow one, 35 % apart (as
    /// walker's `compact` pass did, found again by fresh processes). That scene alone regresses;
    /// a time its scenes do not decide alone is decided pooled, where the other scenes' states
    /// average it out, and where there is no pool (one scene) its scene decides after all.
    #[test]
    fn a_pass_split_between_states_in_one_scene_is_decided_pooled() {
        let mut split = series(17, 0.03, |_| 0.0, |_| 0.0);
        for (p, value) in split[15].head.iter_mut().enumerate() {
            *value = Some(-1.5 + 1.35f64.ln() + 0.01 * p as f64);
        }
        assert_eq!(split[15].check().unwrap().outcome, Outcome::Regressed, "alone, walker regresses");
        let outcomes = |series: &[Series]| -> Vec<(String, Outcome)> {
            decide(series).into_iter().map(|c| (c.scene, c.outcome)).collect()
        };
        assert!(outcomes(&split).iter().any(|(_, o)| *o == Outcome::Regressed), "decided alone, it fails");
        for one in &mut split {
            one.alone = false;
        }
        let pooled = outcomes(&split);
        assert_eq!(pooled, [(ALL_SCENES.to_string(), Outcome::Unchanged)], "only the pool decides");
        assert_eq!(
            outcomes(&split[15..16]),
            [("scene-15".to_string(), Outcome::Regressed)],
            "without a pool its scene decides"
        );
    }

    /// No change anywhere: unchanged.
    #[test]
    fn the_same_build_pooled_is_unchanged() {
        assert_eq!(outcome_of(&series(17, 0.1, |_| 0.0, |_| 0.0)), Outcome::Unchanged);
    }

    /// A scene that some process did not time is left out of the pool, the processes kept; with
    /// fewer than two scenes left there is no pooled check.
    #[test]
    fn a_scene_a_process_missed_is_left_out_and_one_scene_is_no_pool() {
        let mut three = series(3, 0.02, |_| 1.3f64.ln(), |_| 0.0);
        three[1].base[2] = None;
        let pooled = &checks(&three)[0];
        assert!(pooled.detail.contains("over 2 scenes"), "{}", pooled.detail);
        assert!(pooled.detail.contains("over 4 processes of the base and 4 of the run"), "{}", pooled.detail);
        three[2].head[0] = None;
        assert!(checks(&three).is_empty());
    }

    /// The pooled tolerance is the largest of its scenes': a pooled regression is past every
    /// scene's tolerance.
    #[test]
    fn the_pooled_tolerance_is_the_largest_of_the_scenes() {
        let mut two = series(2, 0.0, |_| 1.2f64.ln(), |_| 0.0);
        two[1].bound = 0.25f64.ln_1p();
        let pooled = &checks(&two)[0];
        assert!((pooled.threshold.unwrap() - 0.25).abs() < 1e-12, "{pooled:?}");
        assert_eq!(pooled.outcome, Outcome::Unchanged);
    }
}
