//! `aabench bless`: baselines written from finished runs, all of a tier's folder at once, and
//! `aabench upgrade`: baselines of the schema before rewritten in today's.

use std::path::{Path, PathBuf};

use super::{Baseline, Blessing, load, parse, path, write};
use crate::files;
use crate::plan::Tier;
use crate::record::{RunRecord, RunSettings, SceneRecord, Status};

/// What `bless` did.
#[derive(Debug, Default)]
pub struct Blessed {
    pub written: Vec<PathBuf>,
    /// Scenes that were not blessed, with the reason.
    pub skipped: Vec<(String, String)>,
    /// What the baselines can support less well than they should, one line each: records too
    /// short to gate time on.
    pub warnings: Vec<String>,
}

/// What the user allows a bless beyond writing baselines of unchanged images.
#[derive(Debug, Clone, Copy, Default)]
pub struct Consent<'a> {
    /// Replace baselines of another platform key, tier or schema, and files that are no baseline.
    pub force: bool,
    /// Why the paper's mode renders other bits than its baseline: required when it does, and
    /// kept in the baselines written.
    pub why: Option<&'a str>,
}

/// Writes a baseline for every scene that finished ok in each of `runs` (one run, or several
/// of the same build and platform, whose rounds compare pools). Existing baselines of another
/// platform key, tier or schema, or files that are no baseline at all, are overwritten only
/// with `consent.force`, and a baseline whose paper's mode the runs render other bits of only
/// with `consent.why`; otherwise nothing is written and the error lists each refusal.
pub fn bless(runs: &[RunRecord], root: &Path, consent: Consent, now: &str) -> Result<Blessed, String> {
    let run = runs.first().ok_or("no run to bless")?;
    if consent.why.is_some_and(|why| why.trim().is_empty()) {
        return Err("--why is empty: say in words why the paper's mode renders other bits".into());
    }
    check_finished(runs)?;
    check_alike(runs)?;
    let mut blessed = Blessed::default();
    let mut planned = Vec::new();
    let mut refusals = Vec::new();
    let mut unexplained = Vec::new();
    for scene in &run.scenes {
        let measured: Vec<&SceneRecord> =
            runs.iter().filter_map(|r| r.scenes.iter().find(|s| s.name == scene.name)).collect();
        if let Some(bad) = measured.iter().find(|s| s.status != Status::Ok) {
            let reason =
                bad.error.clone().unwrap_or_else(|| format!("status {:?}", bad.status).to_lowercase());
            blessed.skipped.push((scene.name.clone(), reason));
            continue;
        }
        if measured.len() != runs.len() {
            blessed.skipped.push((scene.name.clone(), "not in every run".into()));
            continue;
        }
        same_images(&measured)?;
        let target = path(root, &run.platform.key, run.tier, &scene.name);
        match refusal(&target, run) {
            // A place no bless can write to: `--force` would not help.
            Err(error) => return Err(format!("{}: {error}; nothing was written", target.display())),
            Ok(Some(reason)) if !consent.force => {
                refusals.push(format!("{}: {reason}", target.display()));
                continue;
            }
            Ok(_) => {}
        }
        if let (Some(moved), None) = (paper_moved(&target, scene), consent.why) {
            unexplained.push(format!("{}: {moved}", target.display()));
            continue;
        }
        blessed.warnings.extend(short_records(&measured));
        planned.push((target, measured));
    }
    if !unexplained.is_empty() {
        return Err(format!(
            "the paper's mode renders other bits than these baselines hold:\n  {}\nsay why with --why \"…\" \
             (kept in the baselines); nothing was written",
            unexplained.join("\n  ")
        ));
    }
    if !refusals.is_empty() {
        return Err(format!(
            "not overwriting (use --force to replace):\n  {}\nnothing was written",
            refusals.join("\n  ")
        ));
    }
    let baselines: Vec<(PathBuf, Baseline)> = planned
        .into_iter()
        .map(|(target, measured)| {
            // A bless that says nothing keeps the reason of the one that moved the bits.
            let why =
                consent.why.map(String::from).or_else(|| load(&target).ok().and_then(|old| old.blessed.why));
            let baseline = Baseline::of(run.tier, blessing(runs, now, why), &measured);
            (target, baseline)
        })
        .collect();
    let dir = root.join(&run.platform.key).join(run.tier.name());
    if !baselines.is_empty() {
        write_together(&dir, &baselines, "bless")?;
    }
    blessed.written = baselines.into_iter().map(|(target, _)| target).collect();
    blessed.warnings.extend(strangers(&dir, &blessed.written));
    Ok(blessed)
}

/// Who blesses `runs` (their first's version, platform and settings) `at`, and why.
fn blessing(runs: &[RunRecord], at: &str, why: Option<String>) -> Blessing {
    let run = &runs[0];
    Blessing {
        aabench_version: run.aabench_version.clone(),
        at: at.into(),
        run_ids: runs.iter().map(|r| r.run_id.clone()).collect(),
        why,
        platform: run.platform.clone(),
        settings: run.settings.clone(),
    }
}

/// The baselines that blessing `runs` into `root` would replace: the readable ones of the
/// runs' own platform, tier and scenes.
pub fn replaced_by(runs: &[RunRecord], root: &Path) -> Vec<Baseline> {
    let Some(run) = runs.first() else { return Vec::new() };
    run.scenes
        .iter()
        .filter_map(|scene| load(&path(root, &run.platform.key, run.tier, &scene.name)).ok())
        .collect()
}

/// Writes `baselines` into `dir` as one transaction: the folder's other files and the new
/// ones are assembled in a staging folder beside it (`<tier>.tmp-<pid>`, a temporary that a
/// later bless removes once its process is gone), which then trades places with `dir` in one
/// `renameat2(RENAME_EXCHANGE)`. A bless killed at any point leaves every baseline old or
/// every one new, never a mix. `command` (`bless`, `upgrade`) is what a refusal names.
fn write_together(dir: &Path, baselines: &[(PathBuf, Baseline)], command: &str) -> Result<(), String> {
    let parent = dir.parent().ok_or_else(|| format!("{}: no parent folder", dir.display()))?;
    let name = dir.file_name().ok_or_else(|| format!("{}: no folder name", dir.display()))?;
    let mut staging = name.to_owned();
    staging.push(format!(".tmp-{}", std::process::id()));
    let staging = parent.join(staging);
    let error = |path: &Path, e: std::io::Error| format!("{}: {e}", path.display());
    let assemble = || -> Result<(), String> {
        let kept = if dir.is_dir() { kept_files(dir, command)? } else { Vec::new() };
        std::fs::create_dir_all(&staging).map_err(|e| error(&staging, e))?;
        for file in kept {
            let copy = staging.join(file.file_name().unwrap_or_default());
            std::fs::copy(&file, &copy).map_err(|e| error(&file, e))?;
        }
        for (target, baseline) in baselines {
            write(&staging.join(target.file_name().unwrap_or_default()), baseline)?;
        }
        swap_into_place(&staging, dir)
            .map_err(|e| format!("{}: cannot move the new baselines in: {e}", dir.display()))
    };
    let result = assemble();
    // After the swap the staging path holds the old baselines; before it, the unused new ones.
    let _ = std::fs::remove_dir_all(&staging);
    result
}

/// The files of a tier's folder that a bless carries over: every regular file, baselines and
/// the user's own (notes, a README). Anything else there (a folder, a link, a FIFO) could not
/// be carried over whole and would go with the old folder, so it is refused by name, with the
/// `command` to run again.
fn kept_files(dir: &Path, command: &str) -> Result<Vec<PathBuf>, String> {
    let mut files = Vec::new();
    for entry in std::fs::read_dir(dir).map_err(|e| format!("{}: {e}", dir.display()))? {
        let entry = entry.map_err(|e| format!("{}: {e}", dir.display()))?;
        match entry.file_type() {
            Ok(kind) if kind.is_file() => files.push(entry.path()),
            _ => {
                return Err(format!(
                    "{}: is no file: {command} writes the tier's folder anew and could not keep it; move \
                     it out of {} and {command} again",
                    entry.path().display(),
                    dir.display()
                ));
            }
        }
    }
    files.sort();
    Ok(files)
}

/// A warning for each `*.json` of the tier's folder `dir` that is no baseline (a user's
/// `notes.json`): bless keeps it, but compare reads every `*.json` there as a baseline and
/// refuses the folder, naming it.
fn strangers(dir: &Path, written: &[PathBuf]) -> Vec<String> {
    let files = files::files_in(dir).unwrap_or_default();
    files
        .into_iter()
        .filter(|file| !written.contains(file))
        .filter_map(|file| {
            let error = parse(&files::read_regular(&file).ok()?).err()?;
            Some(format!(
                "{}: is no baseline ({error}): compare reads every *.json of {} as one and will refuse \
                 the folder; rename it (notes.md) or move it out",
                file.display(),
                dir.display()
            ))
        })
        .collect()
}

/// Moves the folder `from` to `to` atomically: a plain rename when `to` does not exist, else an
/// exchange of the two (Linux's `renameat2`), after which `from` names the old folder.
fn swap_into_place(from: &Path, to: &Path) -> std::io::Result<()> {
    use std::os::unix::ffi::OsStrExt;
    if !to.exists() {
        return std::fs::rename(from, to);
    }
    let c_path = |path: &Path| {
        std::ffi::CString::new(path.as_os_str().as_bytes())
            .map_err(|_| std::io::Error::new(std::io::ErrorKind::InvalidInput, "a NUL byte in the path"))
    };
    let (from, to) = (c_path(from)?, c_path(to)?);
    // SAFETY: both are valid NUL-terminated paths that outlive the call; AT_FDCWD resolves
    // them as relative paths are resolved everywhere else.
    #[allow(unsafe_code)]
    let status = unsafe {
        libc::renameat2(libc::AT_FDCWD, from.as_ptr(), libc::AT_FDCWD, to.as_ptr(), libc::RENAME_EXCHANGE)
    };
    if status == 0 { Ok(()) } else { Err(std::io::Error::last_os_error()) }
}

/// Refuses a run listed twice (its one process would be pooled as two, and the processes'
/// spread, which widens later thresholds, would read 0) and a run that did not finish (killed
/// or interrupted: its record may stop mid-scene).
fn check_finished(runs: &[RunRecord]) -> Result<(), String> {
    for (index, run) in runs.iter().enumerate() {
        // Equal records are one process read twice: two processes never time alike.
        if runs[..index].contains(run) {
            return Err(format!(
                "run {} is given twice: a baseline pools separate processes, each once; nothing was written",
                run.run_id
            ));
        }
        if run.finished_at.is_none() || matches!(run.status, Status::Running | Status::Interrupted) {
            return Err(format!(
                "run {} did not finish (status `{}`): bless finished runs only; nothing was written",
                run.run_id, run.status
            ));
        }
    }
    Ok(())
}

/// A warning when some of the scene's modes have fewer pooled frames than a time verdict
/// needs: `compare` will call their time checks insufficient.
fn short_records(measured: &[&SceneRecord]) -> Option<String> {
    let first = measured[0];
    let frames = |id: &str| -> usize {
        measured.iter().filter_map(|scene| scene.mode(id)?.frame_ms.as_ref().map(|f| f.samples.len())).sum()
    };
    let short: Vec<usize> = first
        .modes
        .iter()
        .map(|m| frames(&m.mode))
        .filter(|&n| n < crate::manifest::tolerances::MIN_FRAMES)
        .collect();
    let fewest = short.iter().min()?;
    Some(format!(
        "{}: {} of {} modes have fewer than the {} timed frames a time verdict needs (the fewest {fewest}): \
         their time checks will be `insufficient`; bless runs with more --repetitions",
        first.name,
        short.len(),
        first.modes.len(),
        crate::manifest::tolerances::MIN_FRAMES
    ))
}

/// Runs blessed together must be of one platform, tier, build and settings (rounds aside).
fn check_alike(runs: &[RunRecord]) -> Result<(), String> {
    if let Some(run) = runs.iter().find(|run| !run.settings.quality) {
        return Err(format!(
            "run {} timed its modes alone (`--quality off`): a baseline needs their quality; bless runs that measured it",
            run.run_id
        ));
    }
    let first = &runs[0];
    for run in &runs[1..] {
        let differs =
            |what: &str| Err(format!("run {} and run {} differ in their {what}", first.run_id, run.run_id));
        if run.platform.key != first.platform.key {
            return differs("platform key");
        }
        if run.tier != first.tier {
            return differs("tier");
        }
        if run.aabench_version != first.aabench_version {
            return differs("aabench version");
        }
        if let Some(why) = crate::record::different_builds(first, run) {
            return Err(why);
        }
        // Repetitions may differ, and whether sequences were rendered (the gate renders them in
        // one process of several); how frames were made may not.
        let settings = RunSettings {
            repetitions: first.settings.repetitions,
            confidence: first.settings.confidence,
            sequences: first.settings.sequences,
            ..run.settings.clone()
        };
        if settings != first.settings {
            return differs("settings (modes, warm-up, frame timeout or extra samples)");
        }
    }
    Ok(())
}

/// The runs of one scene must agree on every image and input: same build, same scene.
fn same_images(measured: &[&SceneRecord]) -> Result<(), String> {
    let first = measured[0];
    for scene in &measured[1..] {
        if scene.inputs != first.inputs {
            return Err(format!("{}: the runs rendered different input files", first.name));
        }
        for mode in &first.modes {
            let other = scene.mode(&mode.mode).map(|m| &m.output_hash);
            if other != Some(&mode.output_hash) {
                return Err(format!(
                    "{}: the runs disagree on {}'s images (another build or scene?): not blessed together",
                    first.name, mode.mode
                ));
            }
        }
    }
    Ok(())
}

/// Why an existing file at `target` must not be replaced by a baseline of `run` without
/// `--force`, if it must not; an error where nothing can be written there at all (a path
/// through a file, a folder in the baseline's place).
fn refusal(target: &Path, run: &RunRecord) -> Result<Option<String>, String> {
    let text = match files::read_regular(target) {
        Ok(text) => text,
        Err(error) if error.kind() == std::io::ErrorKind::NotFound => return Ok(None),
        Err(error) => return Err(format!("cannot be read or written ({error})")),
    };
    Ok(replaced(&text, run))
}

/// The paper's modes of `scene` whose output hash differs from the existing baseline at
/// `target` of the same platform (`adaptive-2x2 (old → new)`, comma-separated), if any.
fn paper_moved(target: &Path, scene: &SceneRecord) -> Option<String> {
    let old = load(target).ok()?;
    let moved: Vec<String> = scene
        .modes
        .iter()
        .filter(|mode| mode.is_paper())
        .filter_map(|mode| {
            let (now, then) = (mode.output_hash.as_ref()?, old.mode(&mode.mode)?.output_hash.as_ref()?);
            (now != then).then(|| format!("{} ({then} → {now})", mode.mode))
        })
        .collect();
    (!moved.is_empty()).then(|| moved.join(", "))
}

/// Why the existing file `text` must not be replaced by a baseline of `run` without `--force`.
fn replaced(text: &[u8], run: &RunRecord) -> Option<String> {
    let existing = match parse(text) {
        Ok(existing) => existing,
        Err(error) => return Some(format!("the existing file is no baseline this aabench reads ({error})")),
    };
    let key = &existing.blessed.platform.key;
    if *key != run.platform.key {
        return Some(format!(
            "the existing baseline is of platform `{key}`, the run of `{}`",
            run.platform.key
        ));
    }
    if existing.tier != run.tier {
        return Some(format!(
            "the existing baseline is of the {} tier, the run of the {} tier",
            existing.tier.name(),
            run.tier.name()
        ));
    }
    None
}

/// Rewrites every baseline under `root` (`<root>/<key>/<tier>/*.json`) whose schema is the
/// one before in today's, value for value, a tier's folder at once; returns the files
/// rewritten. A file that does not read stops it before anything is written, naming the file.
pub fn upgrade(root: &Path) -> Result<Vec<PathBuf>, String> {
    let keys = std::fs::read_dir(root).map_err(|e| format!("{}: {e}", root.display()))?;
    let mut tiers: Vec<PathBuf> = keys
        .filter_map(|entry| entry.ok())
        .flat_map(|key| [Tier::Quick, Tier::Nightly].map(|tier| key.path().join(tier.name())))
        .filter(|tier| tier.is_dir())
        .collect();
    tiers.sort();
    let mut folders = Vec::new();
    for tier in tiers {
        let mut older = Vec::new();
        for file in files::files_in(&tier)? {
            let text =
                files::read_regular(&file).map_err(|e| format!("{}: cannot read: {e}", file.display()))?;
            let baseline = parse(&text).map_err(|e| format!("{}: {e}", file.display()))?;
            if crate::files::json::schema_of(&text).ok().as_deref() != Some(super::BASELINE_SCHEMA) {
                older.push((file, baseline));
            }
        }
        if !older.is_empty() {
            folders.push((tier, older));
        }
    }
    let mut written = Vec::new();
    for (tier, baselines) in folders {
        write_together(&tier, &baselines, "upgrade")?;
        written.extend(baselines.into_iter().map(|(file, _)| file));
    }
    Ok(written)
}
