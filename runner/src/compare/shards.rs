//! `aabench merge-verdicts`: the verdicts of a sharded gate joined into one. Each shard gated
//! its own scenes on its own machine (time against the base build measured there, quality
//! against the baselines of those scenes); the joined verdict holds every shard's checks and
//! notes, fails where any shard failed, and fails a baseline scene that no shard compared.
//! Shards that do not belong together (missing, given twice, of another count, build, base,
//! tier, platform or baselines) join into nothing.

use std::collections::BTreeMap;
use std::path::PathBuf;

use super::verdict::{Check, Outcome, ShardScope, Verdict};

/// The joined verdict of `shards` (each with the file it was read from), or why they do not
/// belong together.
pub fn merge_verdicts(shards: &[(Verdict, PathBuf)]) -> Result<Verdict, String> {
    let scopes = scopes(shards)?;
    let (first, _) = &shards[0];
    let mut checks: Vec<Check> =
        shards.iter().flat_map(|(verdict, _)| verdict.checks.iter().cloned()).collect();
    let compared: Vec<&String> = scopes.iter().flat_map(|scope| &scope.scenes).collect();
    for scene in scopes[0].baseline_scenes.iter().filter(|scene| !compared.contains(scene)) {
        let detail = "the scene has a baseline, and no shard's run holds it (was its manifest removed?)";
        // As in `compare`: with `--lenient` a missing scene is reported, not failed.
        let gated = !first.lenient;
        checks.push(Check { gated, ..Check::new(scene, "*", "status", Outcome::Missing, detail.into()) });
    }
    let counts = Outcome::count(&checks);
    let every = |ids: fn(&Verdict) -> &Vec<String>| -> Vec<String> {
        shards.iter().flat_map(|(verdict, _)| ids(verdict).iter().cloned()).collect()
    };
    let notes = shards.iter().flat_map(|(verdict, _)| {
        let scope = verdict.shard.as_ref().expect("checked by scopes");
        verdict.notes.iter().map(move |note| format!("shard {}/{}: {note}", scope.index, scope.count))
    });
    Ok(Verdict {
        run_id: first.run_id.clone(),
        run_ids: every(|v| &v.run_ids),
        base_run_ids: every(|v| &v.base_run_ids),
        confirm_run_ids: every(|v| &v.confirm_run_ids),
        confirm_base_run_ids: every(|v| &v.confirm_base_run_ids),
        to_confirm: every(|v| &v.to_confirm),
        same_machine: shards.iter().all(|(verdict, _)| verdict.same_machine),
        regressed: checks.iter().any(Check::fails),
        counts,
        notes: std::iter::once(format!(
            "the verdicts of {} shards, each gated on its own machine",
            shards.len()
        ))
        .chain(notes)
        .collect(),
        checks,
        shard: None,
        ..first.clone()
    })
}

fn scope_of((verdict, file): &(Verdict, PathBuf)) -> Result<&ShardScope, String> {
    verdict.shard.as_ref().ok_or_else(|| {
        format!("{}: not the verdict of a shard (compare a run of `--shard I/N`)", file.display())
    })
}

/// Every shard's scope, in shard order, once each shard is known to belong with the first.
fn scopes(shards: &[(Verdict, PathBuf)]) -> Result<Vec<&ShardScope>, String> {
    let (first, first_file) = shards.first().ok_or("no verdicts to merge")?;
    let count = scope_of(&shards[0])?.count;
    let mut seen: Vec<Option<&ShardScope>> = vec![None; count as usize];
    for shard in shards {
        let (verdict, file) = shard;
        let scope = scope_of(shard)?;
        let differs =
            |what: &str| format!("{}: its {what} differs from {}'s", file.display(), first_file.display());
        if scope.count != count || scope.index == 0 || scope.index > count {
            return Err(format!(
                "{}: shard {}/{} is no shard of {count}",
                file.display(),
                scope.index,
                scope.count
            ));
        }
        // A verdict from before verdicts recorded their baselines' blessing lists none.
        if scope.baselines_blessed.is_empty() != scope_of(&shards[0])?.baselines_blessed.is_empty() {
            return Err(format!(
                "{}: it and {} are verdicts of two versions of aabench (one records its baselines' blessing)",
                file.display(),
                first_file.display()
            ));
        }
        for (what, same) in [
            ("build", verdict.build == first.build),
            ("tier", verdict.tier == first.tier),
            ("baselines' platform", verdict.baseline_platform == first.baseline_platform),
            (
                "gate (--fail-on, --lenient)",
                verdict.fail_on == first.fail_on && verdict.lenient == first.lenient,
            ),
            ("list of baseline scenes", scope.baseline_scenes == scope_of(&shards[0])?.baseline_scenes),
            (
                "baselines' blessing (another folder, or the folder blessed again)",
                scope.baselines_blessed == scope_of(&shards[0])?.baselines_blessed,
            ),
        ] {
            if !same {
                return Err(differs(what));
            }
        }
        if seen[scope.index as usize - 1].replace(scope).is_some() {
            return Err(format!("{}: shard {}/{count} is given twice", file.display(), scope.index));
        }
    }
    // A shard whose base processes all failed knows no base build (its verdict says why); the
    // others must name one and the same.
    let bases: std::collections::BTreeSet<&String> =
        shards.iter().filter_map(|(verdict, _)| verdict.base_build.as_ref()).collect();
    if bases.len() > 1 {
        let bases: Vec<&str> = bases.into_iter().map(String::as_str).collect();
        return Err(format!("the shards were gated against different base builds: {}", bases.join(", ")));
    }
    let missing: Vec<String> =
        (1..=count).filter(|i| seen[*i as usize - 1].is_none()).map(|i| format!("{i}/{count}")).collect();
    if !missing.is_empty() {
        return Err(format!("the verdicts of shard(s) {} are missing", missing.join(", ")));
    }
    let scopes: Vec<&ShardScope> = seen.into_iter().flatten().collect();
    let mut holders = BTreeMap::new();
    for scope in &scopes {
        for scene in &scope.scenes {
            if let Some(other) = holders.insert(scene, scope.index) {
                return Err(format!(
                    "scene `{scene}` is in shard {other}/{count} and shard {}/{count}",
                    scope.index
                ));
            }
        }
    }
    Ok(scopes)
}
