//! Baselines: `baselines/<platform-key>/<tier>/<scene>.json`, schema `aabench.baseline/2`. A
//! baseline is one scene as blessed, holding what `compare` and the gate read and nothing
//! else: per mode its output hash, every metric of the vocabulary (along each sequence too),
//! its sample statistics and its place on the front; the scene's resolution, input and truth
//! hashes, tolerances and sequences; and, last and apart, who blessed it from which runs on
//! which platform, and every blessed process's frame times. The full run records stay in their run
//! folders.
//!
//! Files are written by [`crate::files::json::reviewable`]: a fixed order, one value a line, what moves
//! with every measurement last, so that a bless's diff shows each moved value as its own line
//! and a bless that moved nothing changes only the last two sections (who blessed it when, on
//! which machine, and the times).
//!
//! Blessing several runs (separate processes) is worth it: each process drifts a little on its
//! own, and a baseline of one process carries its drift into every later comparison. Compare
//! pools the rounds of all of them. Baselines of schema `aabench.baseline/1` (whole run
//! records) are read as they were blessed; `aabench upgrade` rewrites them.

mod bless;
mod legacy;
pub mod moved;

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use serde::{Deserialize, Deserializer, Serialize, Serializer};

pub use self::bless::{Blessed, Consent, bless, replaced_by, upgrade};
use crate::files::{self, json};
use crate::manifest::tolerances::Tolerances;
use crate::measure::pixels::SampleStats;
use crate::measure::stats::Rounds;
use crate::plan::Tier;
use crate::plan::inputs::SceneInputs;
use crate::record::vocabulary::{METRICS, Metric, PSNR_VS_TRUTH, Source};
use crate::record::{FrontVerdict, ModeRecord, Platform, RunRecord, RunSettings, SceneRecord};

pub const BASELINE_SCHEMA: &str = "aabench.baseline/2";

/// One scene as blessed.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Baseline {
    pub schema: String,
    pub scene: String,
    pub tier: Tier,
    pub resolution: Option<[u32; 2]>,
    /// Content hashes of the manifest and glTF files.
    pub inputs: Option<SceneInputs>,
    pub truth: Option<BlessedTruth>,
    /// The tolerances `compare` applies to the scene: the blessed ones decide, so that a change
    /// cannot loosen its own gate.
    pub gate: Tolerances,
    /// The scene's sequences, one per speed, where it has a camera path.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub sequences: Vec<BlessedSequence>,
    /// Every mode of the scene (a scene is blessed only when all of them ran ok).
    pub modes: BTreeMap<String, BlessedMode>,
    /// Who blessed it when, from which runs, on which platform and machine (whose probes move
    /// with every measurement too).
    pub blessed: Blessing,
    /// Per mode, what moves with every measurement, last and apart: its frame times and its
    /// place on the front.
    pub times: BTreeMap<String, BlessedTimes>,
}

/// Who blessed a baseline, from which runs, on which platform, measured how.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Blessing {
    /// The aabench version of the blessed runs.
    pub aabench_version: String,
    pub at: String,
    /// The runs (separate processes) blessed together, in the order of each mode's `times`.
    pub run_ids: Vec<String>,
    /// Why the bless that wrote it moved the paper's bits (`bless --why`): the paper's mode may
    /// change its bits only with a reason.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub why: Option<String>,
    pub platform: Platform,
    pub settings: RunSettings,
}

/// The truth the modes' errors were measured against.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct BlessedTruth {
    /// The hash of everything its image depends on: it changes with any edit of the rendering
    /// source.
    pub key: String,
    /// The hash of the image itself: whether the truth moved.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub image_hash: Option<String>,
}

/// One of the scene's sequences: its speed, and how many frames it rendered of how many.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct BlessedSequence {
    pub speed: String,
    pub frames: u32,
    pub frames_done: u32,
}

/// One mode as blessed.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct BlessedMode {
    /// FNV-1a 64 of its display image (and its sample counts): its bits.
    pub output_hash: Option<String>,
    /// Every metric of the vocabulary the mode has, by [`Metric::key`], in key order.
    pub metrics: BTreeMap<String, Reading>,
    /// Its sample statistics, for a mode with a sample-count map (`shaded_percent` is among
    /// the metrics).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub samples: Option<BlessedSamples>,
}

/// A mode's times as blessed.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct BlessedTimes {
    /// What each of the scene's error-against-run-time fronts decided of it, by the key of the
    /// front's metric (its time decides that as much as its error). Baselines from before hold
    /// whether it was on the PSNR front, as `on_front`.
    #[serde(
        default,
        alias = "on_front",
        deserialize_with = "verdicts_or_flag",
        skip_serializing_if = "BTreeMap::is_empty"
    )]
    pub fronts: BTreeMap<String, FrontVerdict>,
    /// Each blessed process's frame times in milliseconds, round by round, to the nanosecond
    /// the clock resolves: what the time rules pool and pair. Absent where a process has none.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub frame_ms: Option<Vec<Vec<f64>>>,
}

/// The verdicts by key, or (in baselines from before) whether the mode was on the PSNR front.
fn verdicts_or_flag<'de, D: Deserializer<'de>>(
    deserializer: D,
) -> Result<BTreeMap<String, FrontVerdict>, D::Error> {
    #[derive(Deserialize)]
    #[serde(untagged)]
    enum Stored {
        Keyed(BTreeMap<String, FrontVerdict>),
        Flag(bool),
    }
    Ok(match Option::<Stored>::deserialize(deserializer)? {
        Some(Stored::Keyed(verdicts)) => verdicts,
        Some(Stored::Flag(on)) => {
            let verdict = if on { FrontVerdict::Front } else { FrontVerdict::Behind };
            BTreeMap::from([(PSNR_VS_TRUTH.id.to_string(), verdict)])
        }
        None => BTreeMap::new(),
    })
}

/// The sample statistics of an adaptive mode beside `shaded_percent` (see [`SampleStats`]).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct BlessedSamples {
    pub shaded: u64,
    pub total: u64,
    pub full_pixels: u64,
    pub reshaded: u64,
    pub work_percent: f64,
    /// `histogram[i]`: pixels that shaded i + 1 samples.
    pub histogram: Vec<u64>,
}

/// A metric's value: a number, or `inf`, `-inf` or `NaN` where it is not finite (PSNR between
/// identical images).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Reading(pub f64);

impl Serialize for Reading {
    fn serialize<S: Serializer>(&self, serializer: S) -> Result<S::Ok, S::Error> {
        match self.0 {
            value if value.is_finite() => serializer.serialize_f64(value),
            value if value.is_nan() => serializer.serialize_str("NaN"),
            value if value > 0.0 => serializer.serialize_str("inf"),
            _ => serializer.serialize_str("-inf"),
        }
    }
}

impl<'de> Deserialize<'de> for Reading {
    fn deserialize<D: Deserializer<'de>>(deserializer: D) -> Result<Reading, D::Error> {
        #[derive(Deserialize)]
        #[serde(untagged)]
        enum Text {
            Number(f64),
            Word(String),
        }
        match Text::deserialize(deserializer)? {
            Text::Number(value) => Ok(Reading(value)),
            Text::Word(word) => match word.as_str() {
                "inf" => Ok(Reading(f64::INFINITY)),
                "-inf" => Ok(Reading(f64::NEG_INFINITY)),
                "NaN" => Ok(Reading(f64::NAN)),
                _ => Err(serde::de::Error::custom(format!("`{word}` is no number (nor inf, -inf, NaN)"))),
            },
        }
    }
}

impl BlessedMode {
    /// The mode as `record` holds it, along a scene of `sequences` sequences.
    fn of(record: &ModeRecord, sequences: usize) -> BlessedMode {
        let mut metrics = BTreeMap::new();
        for metric in &METRICS {
            for index in 0..metric.values_in(sequences) {
                if let Some(value) = metric.value_at(record, index) {
                    metrics.insert(metric.key(index), Reading(value));
                }
            }
        }
        BlessedMode {
            output_hash: record.output_hash.clone(),
            metrics,
            samples: record.samples.as_ref().map(BlessedSamples::of),
        }
    }

    /// `metric`'s value along the scene's sequence `index` (0 for a still's metric).
    pub fn value_at(&self, metric: &Metric, index: usize) -> Option<f64> {
        self.metrics.get(&metric.key(index)).map(|reading| reading.0)
    }

    /// `metric`'s value, a sequence's along the scene's first sequence (the gate's).
    pub fn value(&self, metric: &Metric) -> Option<f64> {
        self.value_at(metric, 0)
    }

    /// Whether the blessed mode has this part: a value of any of its metrics (each part has
    /// one that is always there when the part is).
    pub fn has(&self, source: Source) -> bool {
        METRICS.iter().any(|metric| metric.source == source && self.value(metric).is_some())
    }
}

impl BlessedSamples {
    fn of(stats: &SampleStats) -> BlessedSamples {
        BlessedSamples {
            shaded: stats.shaded,
            total: stats.total,
            full_pixels: stats.full_pixels,
            reshaded: stats.reshaded,
            work_percent: stats.work_percent,
            histogram: stats.histogram.clone(),
        }
    }
}

/// A frame time to the nanosecond: a sum of passes timed in whole nanoseconds, without the
/// binary digits of the sum's rounding, which no clock measured.
fn to_the_nanosecond(ms: f64) -> f64 {
    (ms * 1e6).round() / 1e6
}

impl Baseline {
    /// The scene as `measured` by each blessed process (in the order of `blessed.run_ids`): the
    /// quality of the first stands for all (their images are the same), the times are every
    /// process's.
    pub fn of(tier: Tier, blessed: Blessing, measured: &[&SceneRecord]) -> Baseline {
        let scene = measured[0];
        let times = scene
            .modes
            .iter()
            .map(|mode| {
                let frame_ms = measured
                    .iter()
                    .map(|record| {
                        Some(record.frames(&mode.mode)?.iter().copied().map(to_the_nanosecond).collect())
                    })
                    .collect();
                let fronts = mode.fronts.iter().map(|(key, place)| (key.clone(), place.verdict)).collect();
                (mode.mode.clone(), BlessedTimes { fronts, frame_ms })
            })
            .collect();
        Baseline {
            schema: BASELINE_SCHEMA.into(),
            scene: scene.name.clone(),
            tier,
            blessed,
            resolution: scene.resolution,
            inputs: scene.inputs.clone(),
            truth: scene
                .truth
                .as_ref()
                .map(|truth| BlessedTruth { key: truth.key.clone(), image_hash: truth.image_hash.clone() }),
            gate: scene.gate,
            sequences: scene
                .sequences
                .iter()
                .map(|s| BlessedSequence { speed: s.speed(), frames: s.frames, frames_done: s.frames_done })
                .collect(),
            modes: scene
                .modes
                .iter()
                .map(|mode| (mode.mode.clone(), BlessedMode::of(mode, scene.sequences.len())))
                .collect(),
            times,
        }
    }

    pub fn mode(&self, id: &str) -> Option<&BlessedMode> {
        self.modes.get(id)
    }

    /// Each blessed process's frame times, in the order of `blessed.run_ids`.
    pub fn processes(&self) -> Vec<BlessedProcess<'_>> {
        (0..self.blessed.run_ids.len())
            .map(|process| BlessedProcess { times: &self.times, process })
            .collect()
    }
}

/// The frame times of one blessed process.
#[derive(Debug)]
pub struct BlessedProcess<'a> {
    times: &'a BTreeMap<String, BlessedTimes>,
    process: usize,
}

impl Rounds for BlessedProcess<'_> {
    fn frames(&self, id: &str) -> Option<&[f64]> {
        self.times.get(id)?.frame_ms.as_ref()?.get(self.process).map(Vec::as_slice)
    }
}

/// `<root>/<platform key>/<tier>/<scene>.json`
pub fn path(root: &Path, platform_key: &str, tier: Tier, scene: &str) -> PathBuf {
    root.join(platform_key).join(tier.name()).join(format!("{scene}.json"))
}

/// Reads a baseline file, of this schema or converted from the one before; errors name the
/// file and what is wrong with it.
pub fn load(path: &Path) -> Result<Baseline, String> {
    let text = files::read_regular(path).map_err(|e| format!("{}: cannot read: {e}", path.display()))?;
    parse(&text).map_err(|e| format!("{}: {e}", path.display()))
}

/// A baseline's text, of this schema or the one before; errors name the field, a tolerance out
/// of range among them (a negative one would call identical values improved).
fn parse(text: &[u8]) -> Result<Baseline, String> {
    let schema = json::schema_of(text).map_err(|e| format!("not an {BASELINE_SCHEMA} file: {e}"))?;
    let baseline = match schema.as_str() {
        BASELINE_SCHEMA => json::parse(text)?,
        legacy::SCHEMA => legacy::read(text)?,
        other => {
            return Err(format!(
                "schema is `{other}`, this aabench reads `{BASELINE_SCHEMA}` (and `{}`)",
                legacy::SCHEMA
            ));
        }
    };
    baseline.gate.validate().map_err(|(field, why)| format!("{field}: {why}"))?;
    Ok(baseline)
}

/// Writes `baseline` to `path` atomically, laid out for review.
fn write(path: &Path, baseline: &Baseline) -> Result<(), String> {
    let text = json::reviewable(baseline).map_err(|e| format!("{}: {e}", path.display()))?;
    files::write(path, text.as_bytes())
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
    /// Why there are no baselines, when there are none: the root is missing or no folder, or
    /// holds nothing for the tier.
    pub absent: Option<String>,
}

impl BaselineSet {
    /// Loads the baselines for `run`: its own platform's when they exist, else those of the
    /// platform whose key agrees with the run's over the longest prefix (keys begin with the
    /// driver and its version). Every file of the chosen folder must read, or this fails
    /// naming the file.
    pub fn load(root: &Path, run: &RunRecord) -> Result<BaselineSet, String> {
        let tier = run.tier.name();
        let none = |why: String| BaselineSet {
            dir: None,
            platform_key: None,
            same_platform: false,
            baselines: Vec::new(),
            absent: Some(why),
        };
        match std::fs::metadata(root) {
            Err(error) => {
                return Ok(none(format!("the baseline folder {} cannot be read ({error})", root.display())));
            }
            Ok(meta) if !meta.is_dir() => return Ok(none(format!("{} is not a folder", root.display()))),
            Ok(_) => {}
        }
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
            return Ok(none(format!("{} holds no baselines for the {tier} tier", root.display())));
        };
        let baselines =
            files::files_in(&dir)?.iter().map(|file| load(file)).collect::<Result<Vec<_>, _>>()?;
        let absent = baselines.is_empty().then(|| format!("{} holds no baseline files", dir.display()));
        Ok(BaselineSet {
            same_platform: key == run.platform.key,
            platform_key: Some(key),
            dir: Some(dir),
            baselines,
            absent,
        })
    }

    pub fn scene(&self, name: &str) -> Option<&Baseline> {
        self.baselines.iter().find(|b| b.scene == name)
    }
}
