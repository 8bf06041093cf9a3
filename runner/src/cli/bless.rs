//! `aabench bless` (a run's scenes as baselines, and what that moved) and `aabench upgrade`.

use std::path::{Path, PathBuf};

use super::fail;
use crate::baseline;
use crate::exit;
use crate::plan;
use crate::record::{self, RunRecord};

pub(super) fn bless(runs: &[PathBuf], root: &Path, consent: baseline::Consent) -> u8 {
    let loaded: Result<Vec<_>, String> = runs.iter().map(|run| record::load_run(run)).collect();
    let (records, folders): (Vec<_>, Vec<_>) = match loaded {
        Ok(loaded) => loaded.into_iter().unzip(),
        Err(message) => return fail(message),
    };
    // What a killed bless left (files being written, a staging folder) goes first.
    let stale = plan::remove_stale_temporaries(root, 2);
    if stale > 0 {
        tell!(
            "aabench: removed {stale} temporary file(s) or folder(s) that killed blesses left in {}",
            root.display()
        );
    }
    let now = humantime::format_rfc3339_seconds(std::time::SystemTime::now()).to_string();
    let replaced = baseline::replaced_by(&records, root);
    match baseline::bless(&records, root, consent, &now) {
        Ok(blessed) => {
            for path in &blessed.written {
                say!("blessed {}", path.display());
            }
            if let Err(message) = say_what_moved(&records, &folders[0], &replaced, &blessed) {
                tell!("aabench: warning: {message}");
            }
            for (scene, reason) in &blessed.skipped {
                tell!("aabench: {scene}: not blessed: {reason}");
            }
            for warning in &blessed.warnings {
                tell!("aabench: warning: {warning}");
            }
            // Some scenes were written, others were not: done, with failures, as a run is.
            if blessed.skipped.is_empty() { exit::OK } else { exit::SCENE_FAILED }
        }
        Err(message) => fail(message),
    }
}

/// Prints what the bless moved against the baselines it replaced, and writes it into the
/// first run's folder (`bless.md`), for the message of the commit that carries them: a tracked
/// file that every bless rewrote would churn the tree.
fn say_what_moved(
    records: &[RunRecord],
    folder: &Path,
    replaced: &[baseline::Baseline],
    blessed: &baseline::Blessed,
) -> Result<(), String> {
    let Some(run) = records.first().filter(|_| !blessed.written.is_empty()) else { return Ok(()) };
    let written = blessed.written.iter().map(|path| baseline::load(path)).collect::<Result<Vec<_>, _>>()?;
    let changes = baseline::moved::between(replaced, &written);
    let runs: Vec<&str> = records.iter().map(|r| r.run_id.as_str()).collect();
    let heading = format!(
        "{} scene(s) of `{}/{}` blessed from run(s) `{}`, against the baselines they replace.",
        written.len(),
        run.platform.key,
        run.tier.name(),
        runs.join("`, `")
    );
    let text = baseline::moved::markdown(&changes, &heading);
    say!("{text}");
    let path = folder.join("bless.md");
    crate::files::write(&path, text.as_bytes())?;
    say!("(written to {}, for the commit message: `git commit -e -F {0}`)", path.display());
    Ok(())
}

/// `aabench upgrade`: rewrites the baselines of an older schema under `root` in today's.
pub(super) fn upgrade(root: &Path) -> u8 {
    match baseline::upgrade(root) {
        Ok(written) => {
            for path in &written {
                say!("upgraded {}", path.display());
            }
            if written.is_empty() {
                say!("every baseline under {} is of today's schema", root.display());
            }
            exit::OK
        }
        Err(message) => fail(message),
    }
}
