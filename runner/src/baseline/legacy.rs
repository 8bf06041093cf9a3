//! Baselines of schema `aabench.baseline/1`, which held every blessed run's whole record of
//! the scene: read into the baseline of today, value for value.

use serde::Deserialize;

use super::{Baseline, Blessing};
use crate::files::json;
use crate::plan::Tier;
use crate::record::{Platform, RunSettings, SceneRecord};

pub const SCHEMA: &str = "aabench.baseline/1";

/// The file as that schema wrote it.
#[derive(Deserialize)]
struct WholeRecords {
    aabench_version: String,
    blessed_at: String,
    run_ids: Vec<String>,
    tier: Tier,
    platform: Platform,
    settings: RunSettings,
    /// The scene as each blessed run measured it, in the order of `run_ids`.
    scenes: Vec<SceneRecord>,
    #[serde(default)]
    why: Option<String>,
}

/// The baseline a file of that schema holds; errors name the field.
pub fn read(text: &[u8]) -> Result<Baseline, String> {
    let old: WholeRecords = json::parse(text)?;
    if old.scenes.is_empty() || old.scenes.len() != old.run_ids.len() {
        return Err(format!("scenes: {} records for {} run ids", old.scenes.len(), old.run_ids.len()));
    }
    let blessing = Blessing {
        aabench_version: old.aabench_version,
        at: old.blessed_at,
        run_ids: old.run_ids,
        why: old.why,
        platform: old.platform,
        settings: old.settings,
    };
    let measured: Vec<&SceneRecord> = old.scenes.iter().collect();
    Ok(Baseline::of(old.tier, blessing, &measured))
}
