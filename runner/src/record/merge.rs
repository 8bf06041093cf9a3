//! `aabench merge`: joins the shard runs of one suite (`aabench run --shard I/N`, run on N
//! machines) into one run, with its images, that `compare` and `report` take like any other.

use std::path::{Path, PathBuf};

use crate::record::{Platform, RUN_SCHEMA, RunRecord, SceneRecord, Status};

/// Merges `shards` (each a record and its folder) into `out`, a new or empty folder: the
/// scenes' folders copied whole, run.json written last, so a merge that fails midway leaves no run. The shards must
/// be the N slices of one run: same tier, settings, platform and aabench version, every index
/// from 1 to N once, no scene twice. Nothing is written when they are not.
pub fn merge(shards: &[(RunRecord, PathBuf)], out: &Path) -> Result<RunRecord, String> {
    let merged = merged_record(shards, out)?;
    if std::fs::read_dir(out).is_ok_and(|mut entries| entries.next().is_some()) {
        return Err(format!("{}: is not empty; merge into a new folder", out.display()));
    }
    // Everything goes into a staging folder beside `out` (`<out>.tmp-<pid>`, which a later
    // merge removes once its process is gone) that is renamed into place whole: a merge that
    // fails or is killed midway (a full disk) leaves no `out` to refuse on the next try.
    let mut staging = out.as_os_str().to_owned();
    staging.push(format!(".tmp-{}", std::process::id()));
    let staging = PathBuf::from(staging);
    let fill = || -> Result<(), String> {
        std::fs::create_dir_all(&staging).map_err(|e| format!("{}: {e}", staging.display()))?;
        for (shard, dir) in shards {
            for scene in shard.scenes.iter().filter(|scene| !scene.modes.is_empty() || scene.truth.is_some())
            {
                copy_folder(&dir.join(&scene.name), &staging.join(&scene.name))?;
            }
        }
        crate::files::write_json(&staging.join("run.json"), &merged)?;
        // rename(2) replaces an empty folder, so an empty `out` is fine too.
        std::fs::rename(&staging, out)
            .map_err(|e| format!("{}: cannot move the merged run in: {e}", out.display()))
    };
    fill().inspect_err(|_| {
        let _ = std::fs::remove_dir_all(&staging);
    })?;
    Ok(merged)
}

/// The merged record, or why the shards do not belong together.
/// The shards' machine where they all ran on one (by the calibration `Machine::same_as`
/// compares); none where they did not, so that no machine's times are taken for another's.
fn common_machine(shards: &[(RunRecord, PathBuf)]) -> Option<crate::measure::machine::Machine> {
    let first = shards.first()?.0.platform.machine.clone()?;
    let same = |run: &RunRecord| run.platform.machine.as_ref().is_some_and(|m| m.same_as(&first).is_ok());
    shards.iter().all(|(run, _)| same(run)).then_some(first)
}

fn merged_record(shards: &[(RunRecord, PathBuf)], out: &Path) -> Result<RunRecord, String> {
    let name = |dir: &PathBuf| dir.join("run.json").display().to_string();
    let (first, first_dir) = shards.first().ok_or("no runs to merge")?;
    let count =
        first.shard.ok_or_else(|| format!("{}: not a shard run (no `shard`)", name(first_dir)))?.count;
    let mut seen = vec![false; count as usize];
    for (run, dir) in shards {
        let differs = |what: &str| format!("{}: its {what} differs from {}'s", name(dir), name(first_dir));
        let shard = run.shard.ok_or_else(|| format!("{}: not a shard run (no `shard`)", name(dir)))?;
        if shard.index == 0 || shard.index > shard.count {
            return Err(format!("{}: shard {}/{} is not a shard index", name(dir), shard.index, shard.count));
        }
        if shard.count != count {
            return Err(format!(
                "{}: a shard of {}, {} is a shard of {count}",
                name(dir),
                shard.count,
                name(first_dir)
            ));
        }
        if std::mem::replace(&mut seen[shard.index as usize - 1], true) {
            return Err(format!("{}: shard {}/{count} is given twice", name(dir), shard.index));
        }
        if run.tier != first.tier {
            return Err(differs("tier"));
        }
        if run.settings != first.settings {
            return Err(differs("settings (modes, repetitions, warm-up or extra samples)"));
        }
        if run.platform.key != first.platform.key {
            return Err(differs("platform key"));
        }
        if run.aabench_version != first.aabench_version {
            return Err(differs("aabench version"));
        }
        if let Some(why) = crate::record::different_builds(first, run) {
            return Err(why);
        }
    }
    let missing: Vec<String> =
        seen.iter().enumerate().filter(|(_, s)| !**s).map(|(i, _)| format!("{}/{count}", i + 1)).collect();
    if !missing.is_empty() {
        return Err(format!("shards {} are missing", missing.join(", ")));
    }
    // Where the shards ran on different machines, each scene keeps the machine that measured it.
    let machine = common_machine(shards);
    let scene_of = |run: &RunRecord, scene: &SceneRecord| SceneRecord {
        machine: if machine.is_some() { None } else { run.platform.machine.clone() },
        ..scene.clone()
    };
    let mut scenes: Vec<_> =
        shards.iter().flat_map(|(run, _)| run.scenes.iter().map(|scene| scene_of(run, scene))).collect();
    scenes.sort_by(|a, b| a.manifest.cmp(&b.manifest));
    let mut names = std::collections::HashSet::new();
    if let Some(twice) = scenes.iter().find(|scene| !names.insert(scene.name.as_str())) {
        return Err(format!("scene `{}` is in more than one shard", twice.name));
    }
    let statuses: Vec<Status> = shards.iter().map(|(run, _)| run.status).collect();
    let status = [Status::Running, Status::Interrupted, Status::Failed]
        .into_iter()
        .find(|worst| statuses.contains(worst))
        .unwrap_or(Status::Ok);
    let finished: Option<Vec<&String>> = shards.iter().map(|(run, _)| run.finished_at.as_ref()).collect();
    Ok(RunRecord {
        schema: RUN_SCHEMA.into(),
        run_id: out.file_name().map_or_else(|| "merged".into(), |n| n.to_string_lossy().into_owned()),
        started_at: shards.iter().map(|(run, _)| run.started_at.clone()).min().unwrap_or_default(),
        finished_at: finished.and_then(|times| times.into_iter().max().cloned()),
        status,
        tier: first.tier,
        aabench_version: first.aabench_version.clone(),
        build: first.build.clone(),
        platform: Platform { machine, ..first.platform.clone() },
        settings: first.settings.clone(),
        shard: None,
        merged_from: shards.iter().map(|(run, _)| run.run_id.clone()).collect(),
        scenes,
    })
}

/// Copies a shard's scene folder into the merged run, file for file and folder by folder: its
/// images, and below them what the sequences wrote (`path/`: the animations and distortion
/// maps) and the frames `--keep-frames` kept (`frames/`). aabench writes nothing else there;
/// a link or a device in it is refused by name rather than followed or skipped.
fn copy_folder(from: &Path, to: &Path) -> Result<(), String> {
    let entries =
        std::fs::read_dir(from).map_err(|e| format!("{}: {e} (the shard's images)", from.display()))?;
    std::fs::create_dir_all(to).map_err(|e| format!("{}: {e}", to.display()))?;
    for entry in entries {
        let entry = entry.map_err(|e| format!("{}: {e} (the shard's images)", from.display()))?;
        let (path, target) = (entry.path(), to.join(entry.file_name()));
        let kind = entry.file_type().map_err(|e| format!("{}: {e}", path.display()))?;
        if kind.is_dir() {
            copy_folder(&path, &target)?;
        } else if kind.is_file() {
            std::fs::copy(&path, &target)
                .map_err(|e| format!("{} → {}: {e}", path.display(), target.display()))?;
        } else {
            return Err(format!(
                "{}: neither a file nor a folder (a link?); a shard's folder holds only what aabench wrote",
                path.display()
            ));
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_scene_folder_is_copied_whole_and_a_link_in_it_is_refused_by_name() {
        let dir = std::env::temp_dir().join(format!("aabench-merge-{}", std::process::id()));
        let shard = dir.join("shard/thin");
        std::fs::create_dir_all(shard.join("frames/1/taa")).unwrap();
        std::fs::write(shard.join("taa.png"), b"still").unwrap();
        std::fs::write(shard.join("frames/1/taa/000.png"), b"frame").unwrap();
        copy_folder(&shard, &dir.join("merged/thin")).unwrap();
        assert_eq!(std::fs::read(dir.join("merged/thin/frames/1/taa/000.png")).unwrap(), b"frame");
        assert_eq!(std::fs::read(dir.join("merged/thin/taa.png")).unwrap(), b"still");

        std::os::unix::fs::symlink("/etc/passwd", shard.join("frames/1/link.png")).unwrap();
        let refused = copy_folder(&shard, &dir.join("again/thin")).unwrap_err();
        assert!(refused.contains("frames/1/link.png: neither a file nor a folder"), "{refused}");
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
