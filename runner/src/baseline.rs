//! Baselines: `baselines/<platform-key>/<tier>/<scene>.json`, schema `aabench.baseline/1`. A
//! baseline is one scene as measured by one or more blessed runs, whole: every timing sample,
//! the in-run ratios, quality numbers, sample statistics, output hashes, the input files'
//! hashes and the gate tolerances, with the platform and aabench version that produced them.
//!
//! Blessing several runs (separate processes) is worth it: each process drifts a little on its
//! own, and a baseline of one process carries its drift into every later comparison. Compare
//! pools the rounds of all of them.

use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};

use crate::json;
use crate::plan::Tier;
use crate::record::{Platform, RunRecord, RunSettings, SceneRecord, Status};

pub const BASELINE_SCHEMA: &str = "aabench.baseline/1";

#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Baseline {
    pub schema: String,
    /// The aabench version of the blessed run.
    pub aabench_version: String,
    pub blessed_at: String,
    pub run_ids: Vec<String>,
    pub tier: Tier,
    pub platform: Platform,
    pub settings: RunSettings,
    /// The scene as each blessed run measured it, in the order of `run_ids`. Their images,
    /// sample counts and input files are the same (bless checks); their times differ.
    pub scenes: Vec<SceneRecord>,
}

impl Baseline {
    /// The first run's record: its quality numbers stand for all of them.
    pub fn scene(&self) -> &SceneRecord {
        &self.scenes[0]
    }
}

/// `<root>/<platform key>/<tier>/<scene>.json`
pub fn path(root: &Path, platform_key: &str, tier: Tier, scene: &str) -> PathBuf {
    root.join(platform_key).join(tier.name()).join(format!("{scene}.json"))
}

/// Reads a baseline file; errors name the file and what is wrong with it.
pub fn load(path: &Path) -> Result<Baseline, String> {
    json::read_versioned(path, BASELINE_SCHEMA)
}

/// What `bless` did.
#[derive(Debug, Default)]
pub struct Blessed {
    pub written: Vec<PathBuf>,
    /// Scenes that were not blessed, with the reason.
    pub skipped: Vec<(String, String)>,
}

/// Writes a baseline for every scene that finished ok in each of `runs` (one run, or several
/// of the same build and platform, whose rounds compare pools). Existing baselines of another
/// platform key, tier or schema, or files that are no baseline at all, are overwritten only
/// with `force`; otherwise nothing is written and the error lists each refusal.
pub fn bless(runs: &[RunRecord], root: &Path, force: bool, now: &str) -> Result<Blessed, String> {
    let run = runs.first().ok_or("no run to bless")?;
    check_alike(runs)?;
    let mut blessed = Blessed::default();
    let mut planned = Vec::new();
    let mut refusals = Vec::new();
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
        if !force && let Some(reason) = refusal(&target, run) {
            refusals.push(format!("{}: {reason}", target.display()));
            continue;
        }
        planned.push((target, measured));
    }
    if !refusals.is_empty() {
        return Err(format!(
            "not overwriting (use --force to replace):\n  {}\nnothing was written",
            refusals.join("\n  ")
        ));
    }
    for (target, measured) in planned {
        let baseline = Baseline {
            schema: BASELINE_SCHEMA.into(),
            aabench_version: run.aabench_version.clone(),
            blessed_at: now.into(),
            run_ids: runs.iter().map(|r| r.run_id.clone()).collect(),
            tier: run.tier,
            platform: run.platform.clone(),
            settings: run.settings.clone(),
            scenes: measured.into_iter().cloned().collect(),
        };
        if let Some(dir) = target.parent() {
            std::fs::create_dir_all(dir).map_err(|e| format!("{}: {e}", dir.display()))?;
        }
        json::write_atomic(&target, &baseline)?;
        blessed.written.push(target);
    }
    Ok(blessed)
}

/// Runs blessed together must be of one platform, tier, build and settings (repetitions aside).
fn check_alike(runs: &[RunRecord]) -> Result<(), String> {
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
        // Repetitions may differ; how frames were made may not.
        let settings = RunSettings { repetitions: first.settings.repetitions, ..run.settings.clone() };
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

/// Why an existing file at `target` must not be replaced by a baseline of `run`, if it must not.
fn refusal(target: &Path, run: &RunRecord) -> Option<String> {
    let text = std::fs::read(target).ok()?;
    let schema = match json::schema_of(&text) {
        Ok(schema) => schema,
        Err(error) => return Some(format!("the existing file is not a baseline ({error})")),
    };
    if schema != BASELINE_SCHEMA {
        return Some(format!("the existing baseline has schema `{schema}`, not `{BASELINE_SCHEMA}`"));
    }
    let existing: Baseline = match json::parse(&text) {
        Ok(existing) => existing,
        Err(error) => return Some(format!("the existing baseline does not parse ({error})")),
    };
    if existing.platform.key != run.platform.key {
        return Some(format!(
            "the existing baseline is of platform `{}`, the run of `{}`",
            existing.platform.key, run.platform.key
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

/// The baselines a run is compared with: one platform's folder for the run's tier.
#[derive(Debug)]
pub struct BaselineSet {
    /// `<root>/<key>/<tier>`, or `None` when no platform has baselines for the tier.
    pub dir: Option<PathBuf>,
    pub platform_key: Option<String>,
    /// True when the baselines are of the run's own platform key.
    pub same_platform: bool,
    pub baselines: Vec<Baseline>,
}

impl BaselineSet {
    /// Loads the baselines for `run`: its own platform's when they exist, else those of the
    /// platform whose key agrees with the run's over the longest prefix (keys begin with the
    /// driver and its version). Every file of the chosen folder must read, or this fails
    /// naming the file.
    pub fn load(root: &Path, run: &RunRecord) -> Result<BaselineSet, String> {
        let tier = run.tier.name();
        let own = root.join(&run.platform.key).join(tier);
        let chosen = if own.is_dir() {
            Some((run.platform.key.clone(), own))
        } else {
            let mut others: Vec<String> = std::fs::read_dir(root)
                .into_iter()
                .flatten()
                .filter_map(|entry| entry.ok())
                .filter(|entry| entry.path().join(tier).is_dir())
                .map(|entry| entry.file_name().to_string_lossy().into_owned())
                .collect();
            others.sort();
            let shared =
                |key: &String| key.chars().zip(run.platform.key.chars()).take_while(|(a, b)| a == b).count();
            others.iter().max_by_key(|key| (shared(key), std::cmp::Reverse((*key).clone()))).map(|key| {
                let dir = root.join(key).join(tier);
                (key.clone(), dir)
            })
        };
        let Some((key, dir)) = chosen else {
            return Ok(BaselineSet {
                dir: None,
                platform_key: None,
                same_platform: false,
                baselines: Vec::new(),
            });
        };
        let baselines = json::files_in(&dir)?.iter().map(|file| load(file)).collect::<Result<Vec<_>, _>>()?;
        Ok(BaselineSet {
            same_platform: key == run.platform.key,
            platform_key: Some(key),
            dir: Some(dir),
            baselines,
        })
    }

    pub fn scene(&self, name: &str) -> Option<&Baseline> {
        self.baselines.iter().find(|b| b.scene().name == name)
    }
}
