//! `aabench compare` (a run against its baselines and the base build's runs) and
//! `aabench merge-verdicts` (a sharded gate's verdicts as one).

use std::path::{Path, PathBuf};

use super::{fail, load_run_tidied, out};
use crate::baseline;
use crate::compare;
use crate::exit;
use crate::record::RunRecord;

#[derive(Debug, clap::Args)]
pub(super) struct CompareArgs {
    /// The run: its folder or its run.json; or several processes of one build (the first
    /// gives the quality numbers, their frames are pooled).
    #[arg(required = true)]
    runs: Vec<PathBuf>,
    /// The baselines' root folder.
    #[arg(long, default_value = "baselines")]
    baseline: PathBuf,
    /// Runs of the base build on this machine, in this job (alternating with the runs):
    /// time is then gated against them, with the process as the unit (at least 4 a side).
    #[arg(long, num_args = 1.., value_name = "RUN")]
    base_runs: Vec<PathBuf>,
    /// Fresh processes of the run's build that measured again the scenes of the times a first
    /// compare found suspect against the base build (its `to_confirm`): each suspect is then
    /// regressed only where all the processes together clear its tolerance and these, against
    /// `--confirm-base-runs`, estimate it past the tolerance too. `ci/gate.sh` runs them.
    #[arg(long, num_args = 1.., value_name = "RUN", requires_all = ["base_runs", "confirm_base_runs"])]
    confirm_runs: Vec<PathBuf>,
    /// The base build's fresh processes of those scenes, alternating with `--confirm-runs`.
    #[arg(long, num_args = 1.., value_name = "RUN", requires = "confirm_runs")]
    confirm_base_runs: Vec<PathBuf>,
    /// Folder for summary.md, junit.xml and verdict.json [default: the run's folder].
    #[arg(long)]
    out: Option<PathBuf>,
    /// Which checks may fail: auto (quality; time against the base runs, or against the
    /// baselines on the machine that blessed them), all, or quality only.
    #[arg(long, value_enum, default_value = "auto")]
    fail_on: compare::FailOn,
    /// Report, not fail, what the run lacks: no baselines (or only another platform's), a
    /// scene or mode the baselines hold, scenes at all; quality (`run --quality off`); an
    /// unfinished run. For a first bless or an exploratory compare, never for a gate.
    #[arg(long)]
    lenient: bool,
}

pub(super) fn compare(args: &CompareArgs) -> u8 {
    let load = |paths: &[PathBuf]| -> Result<Vec<RunRecord>, String> {
        paths.iter().map(|path| load_run_tidied(path).map(|(record, _)| record)).collect()
    };
    let loaded = (|| {
        Ok::<_, String>([
            load(&args.runs)?,
            load(&args.base_runs)?,
            load(&args.confirm_runs)?,
            load(&args.confirm_base_runs)?,
        ])
    })();
    let [head, base, confirm_head, confirm_base] = match loaded {
        Ok(sides) => sides,
        Err(message) => return fail(message),
    };
    if let Err(message) = compare::check_comparable(&[&head, &base, &confirm_head, &confirm_base]) {
        return fail(message);
    }
    let baselines = match baseline::BaselineSet::load(&args.baseline, &head[0]) {
        Ok(baselines) => baselines,
        Err(message) => return fail(message),
    };
    let confirmation = (!confirm_head.is_empty())
        .then_some(compare::Confirmation { runs: &confirm_head, base: &confirm_base });
    let request = compare::Request {
        runs: &head,
        base: &base,
        baselines: &baselines,
        fail_on: args.fail_on,
        lenient: args.lenient,
        confirmation,
    };
    let verdict = compare::compare(&request);
    let out_dir = match &args.out {
        Some(dir) => dir.clone(),
        None => crate::record::run_folder(&args.runs[0]),
    };
    match compare::outputs::write_all(&verdict, &out_dir) {
        Ok(files) => {
            out(format_args!("{}", compare::outputs::summary(&verdict)));
            for file in files {
                tell!("wrote {}", file.display());
            }
            if verdict.regressed { exit::REGRESSION } else { exit::OK }
        }
        Err(message) => fail(message),
    }
}

pub(super) fn merge_verdicts(paths: &[PathBuf], out_dir: &Path) -> u8 {
    let read = |path: &PathBuf| {
        let file = if path.is_dir() { path.join("verdict.json") } else { path.clone() };
        crate::files::json::read_versioned::<compare::Verdict>(&file, compare::VERDICT_SCHEMA)
            .map(|v| (v, file))
    };
    let joined =
        paths.iter().map(read).collect::<Result<Vec<_>, _>>().and_then(|v| compare::merge_verdicts(&v));
    let verdict = match joined {
        Ok(verdict) => verdict,
        Err(message) => return fail(message),
    };
    match compare::outputs::write_all(&verdict, out_dir) {
        Ok(_) => {
            out(format_args!("{}", compare::outputs::summary(&verdict)));
            if verdict.regressed { exit::REGRESSION } else { exit::OK }
        }
        Err(message) => fail(message),
    }
}
