//! `aabench merge`: the shard runs of one suite joined into one run.

use std::path::{Path, PathBuf};

use super::{fail, load_run_tidied};
use crate::exit;
use crate::plan;

pub(super) fn merge(runs: &[PathBuf], out: &Path) -> u8 {
    // A killed merge's staging folder sits beside `out`.
    let beside = out.parent().filter(|p| !p.as_os_str().is_empty()).unwrap_or(Path::new("."));
    plan::remove_stale_temporaries(beside, 0);
    let shards: Result<Vec<_>, String> = runs.iter().map(|run| load_run_tidied(run)).collect();
    match shards.and_then(|shards| crate::record::merge::merge(&shards, out)) {
        Ok(merged) => {
            say!(
                "merged {} scenes from {} shards into {}",
                merged.scenes.len(),
                runs.len(),
                out.join("run.json").display()
            );
            exit::OK
        }
        Err(message) => fail(message),
    }
}
