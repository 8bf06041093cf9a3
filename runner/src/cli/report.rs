//! `aabench report`: the HTML page beside each run, or one run's results as Markdown.

use std::path::{Path, PathBuf};

use super::{fail, load_run_tidied};
use crate::compare;
use crate::exit;
use crate::record::RunRecord;

/// `report --markdown`: one run's results on stdout, figures into `figures`.
pub(super) fn markdown_report(runs: &[PathBuf], figures: Option<&Path>) -> u8 {
    let [run] = runs else {
        return fail("--markdown takes one run: its tables name it, and documentation quotes one run");
    };
    let (record, dir) = match crate::record::load_run(run) {
        Ok(run) => run,
        Err(message) => return fail(message),
    };
    if let Some(folder) = figures {
        match crate::report::markdown::figures(&dir, &record, folder) {
            Ok((written, left_out)) => {
                for reason in left_out {
                    tell!("aabench: warning: {reason}");
                }
                for file in written {
                    tell!("wrote {file}");
                }
            }
            Err(message) => return fail(message),
        }
    }
    say!("{}", crate::report::markdown::document(&record).trim_end());
    exit::OK
}

pub(super) fn report(runs: &[PathBuf], history: Option<&Path>, verdict: Option<&Path>) -> u8 {
    if verdict.is_some() && runs.len() > 1 {
        return fail("--verdict belongs to one run; give one run, or let each use its own verdict.json");
    }
    let history = match history.map(crate::report::load_history).transpose() {
        Ok(Some((runs, skipped))) => {
            for warning in skipped {
                tell!("aabench: {warning}");
            }
            runs
        }
        Ok(None) => Vec::new(),
        Err(message) => return fail(message),
    };
    for run in runs {
        let (record, dir) = match load_run_tidied(run) {
            Ok(run) => run,
            Err(message) => return fail(message),
        };
        let verdict = match verdict_of(&record, &dir, verdict) {
            Ok(verdict) => verdict,
            Err(message) => return fail(message),
        };
        match crate::report::write(&dir, &record, verdict.as_ref(), &history) {
            Ok((path, left_out)) => {
                for reason in left_out {
                    tell!("aabench: warning: {reason}");
                }
                say!("wrote {}", path.display());
            }
            Err(message) => return fail(message),
        }
    }
    exit::OK
}

/// The verdict a run's page shows: `given`, or else the run folder's verdict.json if there is
/// one. A verdict of another run is refused when given, and left out with a warning when found
/// in the folder (a copied or reused folder), so that no page shows a gate that did not judge it.
fn verdict_of(
    record: &RunRecord,
    dir: &Path,
    given: Option<&Path>,
) -> Result<Option<compare::Verdict>, String> {
    let file = given.map_or_else(|| dir.join("verdict.json"), Path::to_path_buf);
    if given.is_none() && !file.exists() {
        return Ok(None);
    }
    let verdict: compare::Verdict = crate::files::json::read_versioned(&file, compare::VERDICT_SCHEMA)?;
    if verdict.run_id == record.run_id || verdict.run_ids.contains(&record.run_id) {
        return Ok(Some(verdict));
    }
    let message =
        format!("{}: the verdict of run {}, not of run {}", file.display(), verdict.run_id, record.run_id);
    if given.is_some() {
        return Err(message);
    }
    tell!("aabench: warning: {message}: left out of the page");
    Ok(None)
}
