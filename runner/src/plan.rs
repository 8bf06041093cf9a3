//! Raw CLI arguments → a checked [`RunPlan`], before any GPU work: manifests found and parsed
//! (a bad one becomes a failed scene, not a failed run), modes resolved, tier settings fixed.

use std::path::{Path, PathBuf};
use std::time::Duration;

use aabench_renderer::{ExtraSamples, Mode};
use serde::{Deserialize, Serialize};

use crate::manifest::{Manifest, ManifestError};

#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, clap::ValueEnum)]
#[serde(rename_all = "lowercase")]
pub enum Tier {
    /// Small resolution, few repetitions: the CI gate.
    Quick,
    /// 1024×768 (the paper's), more repetitions: nightly reports.
    Nightly,
}

impl Tier {
    pub fn name(self) -> &'static str {
        match self {
            Tier::Quick => "quick",
            Tier::Nightly => "nightly",
        }
    }

    /// Timed repetitions of every mode, after warm-up.
    pub fn repetitions(self) -> u32 {
        match self {
            Tier::Quick => 3,
            Tier::Nightly => 7,
        }
    }

    /// The modes run when `--modes` is not given: all but the ablations in the quick tier.
    pub fn default_modes(self) -> Vec<Mode> {
        let mut modes = Mode::baseline_modes();
        modes.extend(Mode::adaptive_modes());
        if self == Tier::Nightly {
            modes.extend(Mode::ablation_modes().into_iter().filter(|m| !m.stalled));
        }
        modes
    }
}

/// Parses `--modes`: comma-separated mode ids or the groups `baseline`, `adaptive`, `ablation`.
pub fn parse_modes(list: &str) -> Result<Vec<Mode>, String> {
    let mut modes: Vec<Mode> = Vec::new();
    for item in list.split(',').map(str::trim).filter(|s| !s.is_empty()) {
        let group = match item {
            "baseline" => Mode::baseline_modes(),
            "adaptive" => Mode::adaptive_modes(),
            "ablation" => Mode::ablation_modes(),
            id => vec![id.parse::<Mode>().map_err(|e| e.to_string())?],
        };
        for mode in group {
            if !modes.contains(&mode) {
                modes.push(mode);
            }
        }
    }
    if modes.is_empty() {
        return Err("--modes names no mode".into());
    }
    Ok(modes)
}

/// A manifest that parsed, or the error that names why it did not.
pub type SceneEntry = Result<Manifest, ManifestError>;

#[derive(Debug, Clone)]
pub struct RunPlan {
    pub tier: Tier,
    pub scenes: Vec<SceneEntry>,
    pub modes: Vec<Mode>,
    pub repetitions: u32,
    pub warmup: u32,
    pub frame_timeout: Duration,
    pub extra_samples: ExtraSamples,
    /// reports/<run-id>
    pub run_dir: PathBuf,
    pub run_id: String,
}

/// Finds the manifests named by `paths`: files as given, folders by their `*.json` files in
/// name order. Nothing given means `scenes/`.
pub fn find_manifests(paths: &[PathBuf]) -> Result<Vec<PathBuf>, String> {
    let paths = if paths.is_empty() { vec![PathBuf::from("scenes")] } else { paths.to_vec() };
    let mut found = Vec::new();
    for path in paths {
        if path.is_dir() {
            let mut files: Vec<PathBuf> = std::fs::read_dir(&path)
                .map_err(|e| format!("{}: {e}", path.display()))?
                .filter_map(|entry| entry.ok().map(|e| e.path()))
                .filter(|p| p.extension().is_some_and(|ext| ext == "json"))
                .collect();
            files.sort();
            if files.is_empty() {
                return Err(format!("{}: no *.json manifests in this folder", path.display()));
            }
            found.extend(files);
        } else if path.exists() {
            found.push(path);
        } else {
            return Err(format!("{}: no such file or folder", path.display()));
        }
    }
    Ok(found)
}

/// Loads every manifest; duplicates by name are an error of the later one.
pub fn load_scenes(paths: &[PathBuf]) -> Vec<SceneEntry> {
    let mut scenes: Vec<SceneEntry> = Vec::new();
    for path in paths {
        let entry = Manifest::load(path).and_then(|manifest| {
            let taken = scenes.iter().flatten().any(|other| other.name == manifest.name);
            if taken {
                Err(ManifestError {
                    path: path.clone(),
                    field: "name".into(),
                    message: format!("`{}` is already used by another manifest in this run", manifest.name),
                })
            } else {
                Ok(manifest)
            }
        });
        scenes.push(entry);
    }
    scenes
}

/// A run id that sorts by time: `20261122T101503Z-quick`, with a suffix when taken.
pub fn new_run_id(out: &Path, tier: Tier) -> String {
    let stamp =
        humantime::format_rfc3339_seconds(std::time::SystemTime::now()).to_string().replace(['-', ':'], "");
    let base = format!("{stamp}-{}", tier.name());
    let mut id = base.clone();
    let mut n = 2;
    while out.join(&id).exists() {
        id = format!("{base}-{n}");
        n += 1;
    }
    id
}

/// The scene name that a manifest path would have, for failed manifests.
pub fn fallback_name(path: &Path) -> String {
    path.file_stem().map_or_else(|| "unnamed".into(), |s| s.to_string_lossy().into_owned())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn groups_and_ids_combine_without_duplicates() {
        let modes = parse_modes("baseline, deferred-1x1,adaptive-2x2-geometry").unwrap();
        assert_eq!(modes.len(), 9);
        assert_eq!(modes[8].to_string(), "adaptive-2x2-geometry");
        assert!(parse_modes("reference-9x9").unwrap_err().contains("M must be"));
        assert!(parse_modes(" , ").is_err());
    }

    #[test]
    fn quick_leaves_out_the_ablations_and_nightly_adds_them() {
        let quick = Tier::Quick.default_modes();
        let nightly = Tier::Nightly.default_modes();
        assert_eq!(quick.len(), 14);
        assert_eq!(nightly.len(), 20);
        assert!(quick.iter().all(|m| !m.to_string().contains("geometry")));
    }
}
