//! The run record, `reports/<run-id>/run.json`: everything a run measured, schema versioned.
//! It is rewritten atomically after every scene, so a killed run leaves what finished.

use aabench_renderer::{DisplayImage, PlatformInfo};
use std::collections::BTreeMap;

use serde::{Deserialize, Serialize};

use crate::manifest::tolerances::Tolerances;
use crate::measure::machine::Machine;
use crate::measure::pixels::{FrameChecks, Quality, SampleStats};
use crate::measure::stats::{Rounds, Summary};
pub use crate::plan::Shard;
use crate::plan::Tier;
use crate::plan::inputs::SceneInputs;
use crate::plan::repetitions::{Confidence, Stop};

pub mod front;
pub mod merge;
mod place;
mod sequence;
pub mod vocabulary;
pub use place::{FrontPlace, FrontVerdict, Rival};
pub use sequence::{FlickerRegion, GhostFrame, Ghosting, ModeSequence, SequenceRecord};

/// Version 2: the ground truth is an 8×8 render of its own (`truth`), scenes record their
/// input hashes and gate tolerances, `ratio_to_deferred` is against plain deferred-1x1, and
/// runs may be shards.
pub const RUN_SCHEMA: &str = "aabench.run/2";

#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Status {
    /// Still running (only in a record read while the run is alive, or killed).
    Running,
    Ok,
    Failed,
    /// Stopped by SIGINT, SIGTERM or SIGHUP before it finished.
    Interrupted,
    /// Never started: the run was interrupted, or an earlier frame left the device unusable.
    #[serde(rename = "not run")]
    NotRun,
}

impl std::fmt::Display for Status {
    /// As run.json writes it.
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            Status::Running => "running",
            Status::Ok => "ok",
            Status::Failed => "failed",
            Status::Interrupted => "interrupted",
            Status::NotRun => "not run",
        })
    }
}

#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct RunRecord {
    pub schema: String,
    pub run_id: String,
    pub started_at: String,
    pub finished_at: Option<String>,
    pub status: Status,
    pub tier: Tier,
    pub aabench_version: String,
    /// The build that made it: the first 16 hex digits of a SHA-256 of everything that renders
    /// and measures (both crates' source, the shaders, the lock file). Runs of one build pool
    /// (bless, a compare's processes, merge); absent in runs from before.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub build: Option<String>,
    pub platform: Platform,
    pub settings: RunSettings,
    /// Set when the run rendered one slice of the scenes (`--shard I/N`).
    pub shard: Option<Shard>,
    /// The shard runs that `aabench merge` joined into this one.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub merged_from: Vec<String>,
    pub scenes: Vec<SceneRecord>,
}

/// The machine: results with the same `key` are comparable in absolute time. The renderer's
/// [`PlatformInfo`] is recorded as it is, its fields beside the key in run.json.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Platform {
    pub key: String,
    #[serde(flatten)]
    pub info: PlatformInfo,
    /// The CPU's identity and calibration (absent in records from before it): decides whether
    /// time is gated against a baseline blessed on another machine of the same key.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub machine: Option<Machine>,
}

impl From<&PlatformInfo> for Platform {
    fn from(info: &PlatformInfo) -> Platform {
        Platform { key: info.key(), info: info.clone(), machine: None }
    }
}

#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct RunSettings {
    pub modes: Vec<String>,
    /// Timed rounds of every mode, or with `confidence` the most a mode takes.
    pub repetitions: u32,
    /// The rule by which each mode took its rounds, where not by count (runs from before took
    /// `repetitions` each).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub confidence: Option<Confidence>,
    pub warmup: u32,
    pub frame_timeout_s: f64,
    /// How the frames were ordered: every repetition renders each mode once, in this order.
    pub interleaving: String,
    /// How adaptive modes shaded their extra samples: `compact` or `loop`.
    pub extra_samples: String,
    /// Whether scenes with a camera path were rendered as sequences too (runs from before
    /// sequences read as false).
    #[serde(default)]
    pub sequences: bool,
    /// Whether each mode's image was measured against the truth and written (`--quality off`:
    /// time alone; runs from before read as true).
    #[serde(default = "measured_quality", skip_serializing_if = "is_measured")]
    pub quality: bool,
}

fn measured_quality() -> bool {
    true
}

fn is_measured(quality: &bool) -> bool {
    *quality
}

#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SceneRecord {
    pub name: String,
    pub manifest: String,
    pub status: Status,
    pub error: Option<String>,
    pub resolution: Option<[u32; 2]>,
    pub triangles: Option<usize>,
    pub textures: Option<usize>,
    /// Seconds to generate (if needed) and import the glTF file.
    pub load_s: Option<f64>,
    /// Wall seconds of the work after the timed rounds: every mode's quality against its
    /// reference and the truth, and its images written, on the blocking threads in parallel.
    #[serde(default)]
    pub images_s: Option<f64>,
    /// Of that work, the CPU seconds spent comparing with the truth (MSE, FLIP, SSIM), summed
    /// over the modes: what the perceptual metrics cost, spread over the cores.
    #[serde(default)]
    pub perceptual_s: Option<f64>,
    /// Bytes of render targets once every mode was prepared.
    pub target_bytes: Option<u64>,
    /// Bytes of the scene's textures on the device, mipmaps included.
    #[serde(default)]
    pub texture_bytes: Option<u64>,
    /// The memory limit its modes were prepared under (`--memory-limit`, or 90% of the memory
    /// available after upload).
    #[serde(default)]
    pub memory_limit_bytes: Option<u64>,
    /// What the glTF file uses that aabench ignores (optional extensions), one line each.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub warnings: Vec<String>,
    pub stall_iterations: u32,
    /// Content hashes of the manifest and glTF files (absent when they could not be read).
    pub inputs: Option<SceneInputs>,
    /// The tolerances `compare` applies to this scene (the manifest's `gate` section).
    pub gate: Tolerances,
    /// The exposure its frames rendered at, the truth's included.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub exposure: Option<ExposureRecord>,
    /// The ColorVideoVDP display model its JOD was judged on (`display.jod_display`), where
    /// quality was measured.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub jod_display: Option<String>,
    /// How many of its frame's pixels a degree of the viewer's sight spans, for JOD and FLIP
    /// alike: the viewing conditions its rankings assume (absent in runs from before, whose
    /// FLIP judged at 67 pixels a degree and JOD at the display model's).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub pixels_per_degree: Option<f64>,
    /// The ground truth every mode's `vs_ground_truth` is measured against.
    pub truth: Option<TruthRecord>,
    /// The sequences along the manifest's camera path, where it has one: one per speed of the
    /// tier (runs from before hold one, as `sequence`).
    #[serde(
        default,
        alias = "sequence",
        deserialize_with = "one_or_many",
        skip_serializing_if = "Vec::is_empty"
    )]
    pub sequences: Vec<SequenceRecord>,
    pub modes: Vec<ModeRecord>,
    /// The machine that measured the scene where the run's scenes were measured on different
    /// ones (a merge of shards from several machines); otherwise the run's `platform.machine`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub machine: Option<Machine>,
}

/// The linear scale a scene's frames took before tonemapping.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct ExposureRecord {
    pub value: f32,
    /// Metered from one deferred-1x1 frame because the manifest gives no `tonemap.exposure`.
    pub metered: bool,
}

impl SceneRecord {
    /// The scene's first (the gate's) sequence, where it has a camera path.
    pub fn sequence(&self) -> Option<&SequenceRecord> {
        self.sequences.first()
    }

    pub fn mode(&self, id: &str) -> Option<&ModeRecord> {
        self.modes.iter().find(|m| m.mode == id)
    }

    /// The record of `mode`, where the scene ran it.
    pub fn mode_of(&self, mode: aabench_renderer::Mode) -> Option<&ModeRecord> {
        self.mode(&mode.to_string())
    }
}

impl Rounds for SceneRecord {
    fn frames(&self, id: &str) -> Option<&[f64]> {
        Some(&self.mode(id)?.frame_ms.as_ref()?.samples)
    }
}

impl<T: Rounds + ?Sized> Rounds for &T {
    fn frames(&self, id: &str) -> Option<&[f64]> {
        (**self).frames(id)
    }
}

#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ModeRecord {
    pub mode: String,
    pub m: u32,
    pub stalled: bool,
    pub status: Status,
    pub error: Option<String>,
    /// Wall-clock frame time in milliseconds: the sum of its passes.
    pub frame_ms: Option<Summary>,
    /// Why it took no more rounds (absent in runs from before, which took `repetitions` each).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub stopped: Option<Stop>,
    /// Per pass, in submission order.
    pub passes: Vec<PassRecord>,
    /// Frame median over plain deferred-1x1's in the same run: travels between machines.
    pub ratio_to_deferred: Option<f64>,
    /// True when every timed repetition produced the same display image and sample counts.
    pub deterministic: Option<bool>,
    /// FNV-1a 64 of the display image's RGBA bytes, followed by the sample counts of adaptive
    /// modes.
    pub output_hash: Option<String>,
    pub images: ImageFiles,
    /// Adaptive modes: how many samples were shaded.
    pub samples: Option<SampleStats>,
    /// Against the reference at the same M (adaptive modes).
    pub vs_reference: Option<Quality>,
    /// Against the ground truth (`truth-8x8`).
    pub vs_ground_truth: Option<Quality>,
    pub adaptive: Option<AdaptiveCost>,
    /// Its places on the scene's error-against-run-time fronts, among the modes with the same
    /// stall, by the key of the front's metric (none where it has no frame time or no value of
    /// the metric). Runs from before hold one, on the PSNR front, as `front`.
    #[serde(
        default,
        alias = "front",
        deserialize_with = "place::keyed_or_legacy",
        skip_serializing_if = "BTreeMap::is_empty"
    )]
    pub fronts: BTreeMap<String, FrontPlace>,
    /// The mode's compiled pass graph: passes run and the allocations they share.
    #[serde(default)]
    pub graph: Option<GraphRecord>,
    /// NaN and infinities in the HDR output and sample counts outside [1, M²], summed over
    /// every frame rendered (warm-up included); any fails the mode.
    #[serde(default)]
    pub checks: Option<FrameChecks>,
    /// Its sequences against the truth's, where the scene has a camera path: one per scene
    /// sequence, in its order, `null` where the mode has none of that one (runs from before
    /// hold one, as `sequence`).
    #[serde(
        default,
        alias = "sequence",
        deserialize_with = "one_or_many",
        skip_serializing_if = "Vec::is_empty"
    )]
    pub sequences: Vec<Option<ModeSequence>>,
}

impl ModeRecord {
    /// Whether it is the paper's adaptive mode (`adaptive-MxM`, plain or stalled), whose bits
    /// the gate holds to its baseline.
    pub fn is_paper(&self) -> bool {
        is_paper(&self.mode)
    }

    /// Its place on the front of the metric of key `key` (`psnr_vs_truth`), where it has one.
    pub fn front(&self, key: &str) -> Option<&FrontPlace> {
        self.fronts.get(key)
    }

    /// Whether the front of key `key` decided it is on the front.
    pub fn on_front(&self, key: &str) -> bool {
        self.front(key).is_some_and(|place| place.verdict == FrontVerdict::Front)
    }

    /// Its sequence along the scene's first (the gate's) sequence, where it has one.
    pub fn sequence(&self) -> Option<&ModeSequence> {
        self.sequences.first()?.as_ref()
    }

    /// Its sequence along the scene's sequence `index`, where it has one.
    pub fn sequence_at(&self, index: usize) -> Option<&ModeSequence> {
        self.sequences.get(index)?.as_ref()
    }

    /// The mode the record's id names; `None` for an id this build does not know (a record of
    /// another version of aabench).
    pub fn parsed(&self) -> Option<aabench_renderer::Mode> {
        self.mode.parse().ok()
    }
}

/// Whether mode `id` is the paper's adaptive mode (`adaptive-MxM`, plain or stalled).
pub fn is_paper(id: &str) -> bool {
    id.parse::<aabench_renderer::Mode>()
        .is_ok_and(|mode| mode.technique == aabench_renderer::Technique::PAPER)
}

/// A mode's pass graph as compiled for this scene: what ran and what it allocated, against
/// one allocation per output and against the lower bound (per descriptor, the most resources
/// alive at once). `allocated_bytes − lower_bound_bytes` is what the allocator missed.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct GraphRecord {
    /// In submission order.
    pub passes: Vec<String>,
    pub allocations: Vec<AllocationRecord>,
    pub allocated_bytes: u64,
    pub one_per_output_bytes: u64,
    pub lower_bound_bytes: u64,
}

#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct AllocationRecord {
    /// Format and size (`Rgba16Float 512×384`) or `buffer N B`.
    pub descriptor: String,
    pub bytes: u64,
    /// The outputs it holds in turn, as `pass.port`.
    pub holds: Vec<String>,
}

impl GraphRecord {
    pub fn of(graph: &aabench_renderer::frame::GraphSummary) -> GraphRecord {
        GraphRecord {
            passes: graph.passes.clone(),
            allocations: graph
                .allocations
                .iter()
                .map(|a| AllocationRecord {
                    descriptor: a.descriptor.clone(),
                    bytes: a.bytes,
                    holds: a.holds.clone(),
                })
                .collect(),
            allocated_bytes: graph.allocated_bytes,
            one_per_output_bytes: graph.one_per_output_bytes,
            lower_bound_bytes: graph.lower_bound_bytes,
        }
    }
}

#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct PassRecord {
    pub name: String,
    pub ms: Summary,
}

/// Image files, relative to the run folder.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct ImageFiles {
    pub display: Option<String>,
    pub hdr: Option<String>,
    /// Heatmap of samples per pixel (adaptive modes).
    pub samples: Option<String>,
    /// Heatmap of |image − reference| (reference: the same-M reference for adaptive modes,
    /// deferred-1x1 for FXAA, else the ground truth).
    pub difference: Option<String>,
    /// FLIP's error map against the ground truth, in its magma scale.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub flip: Option<String>,
}

/// An adaptive mode's time against its reference and against its own limit.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct AdaptiveCost {
    /// The reference at the same M and stall.
    pub reference: String,
    /// Reference frame median over this mode's.
    pub speedup: f64,
    /// Shadow cubes (where the scene has them) + G-buffer + S + evaluation + (samples shaded
    /// after S / M²·w·h) × the reference's shading pass, all medians: what adaptive would cost
    /// if shading scaled exactly with samples and its other passes were free. S's own share is
    /// not counted twice.
    pub limit_ms: f64,
    /// limit_ms over this mode's frame median: 1 means at the limit.
    pub efficiency: f64,
    /// The per-sample cost model (absent in records from before it, and where no sample was
    /// shaded after S).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub samples: Option<SampleCost>,
}

/// What an adaptive mode's samples cost against the reference's, and where the rest of its
/// frame goes.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct SampleCost {
    /// Samples shaded after S (in `shade_extra`, the full pixels' second S included).
    pub extra_samples: u64,
    /// `shade_extra`'s median over the extra samples, in nanoseconds.
    pub extra_sample_ns: f64,
    /// The same-M reference's `shade` median over its M²·w·h samples, in nanoseconds.
    pub reference_sample_ns: f64,
    /// extra_sample_ns / reference_sample_ns: 1 means an extra sample costs what a
    /// reference sample does.
    pub extra_sample_cost: f64,
    /// Shares of this mode's frame median: `evaluate` with `compact` (the list), and
    /// `gather`, costs the reference does not pay.
    pub evaluate_share: f64,
    pub gather_share: f64,
}

/// Reads a run: its folder or its run.json. Returns the record and the run folder (image
/// paths in the record are relative to it). Errors name the file.
/// This build (see [`RunRecord::build`]): this binary's source and the shaders it reads, the
/// embedded ones or those of `AABENCH_SHADER_DIR`, so that runs of two shader trees are no one
/// build's.
pub fn this_build() -> String {
    use aabench_renderer::shaders;
    use sha2::{Digest, Sha256};
    let dir = std::env::var_os(shaders::SHADER_DIR_VARIABLE).map(std::path::PathBuf::from);
    let mut hasher = Sha256::new();
    hasher.update(env!("AABENCH_BUILD_SHA256").as_bytes());
    for (name, embedded) in shaders::SOURCES {
        let text = match &dir {
            Some(dir) => crate::files::read_regular(&dir.join(name)).unwrap_or_default(),
            None => embedded.as_bytes().to_vec(),
        };
        hasher.update(name.as_bytes());
        hasher.update((text.len() as u64).to_le_bytes());
        hasher.update(&text);
    }
    hasher.finalize().iter().take(8).map(|b| format!("{b:02x}")).collect()
}

/// Why runs of different builds cannot be taken together, where they are of different builds:
/// each names its build (`none recorded` for a run from before builds were).
pub fn different_builds(a: &RunRecord, b: &RunRecord) -> Option<String> {
    let build = |run: &RunRecord| run.build.clone().unwrap_or_else(|| "none recorded".into());
    (a.build != b.build).then(|| {
        format!(
            "run {} (build {}) and run {} (build {}) are of different builds: their images and times are \
             not one build's",
            a.run_id,
            build(a),
            b.run_id,
            build(b)
        )
    })
}

pub fn load_run(path: &std::path::Path) -> Result<(RunRecord, std::path::PathBuf), String> {
    let record = crate::files::json::read_versioned(&run_file(path), RUN_SCHEMA)?;
    Ok((record, run_folder(path)))
}

/// The run.json that `path` names: the file itself, or the one in the folder.
fn run_file(path: &std::path::Path) -> std::path::PathBuf {
    let is_file = path.extension().is_some_and(|ext| ext == "json") && !path.is_dir();
    if is_file { path.to_path_buf() } else { path.join("run.json") }
}

/// The folder of the run that `path` names (its folder or its run.json).
pub fn run_folder(path: &std::path::Path) -> std::path::PathBuf {
    run_file(path).parent().map_or_else(|| std::path::PathBuf::from("."), std::path::Path::to_path_buf)
}

/// FNV-1a of a frame's outputs: the display image's code values, then the sample counts if any.
pub fn fingerprint(display: &DisplayImage, sample_counts: Option<&[u8]>) -> String {
    fnv1a(&[&display.bytes(), sample_counts.unwrap_or_default()])
}

/// FNV-1a, 64-bit, over the parts in order: a stable fingerprint of image bytes.
pub fn fnv1a(parts: &[&[u8]]) -> String {
    let mut hash: u64 = 0xcbf2_9ce4_8422_2325;
    for &byte in parts.iter().copied().flatten() {
        hash ^= u64::from(byte);
        hash = hash.wrapping_mul(0x0100_0000_01b3);
    }
    format!("{hash:016x}")
}

/// A list, or (in runs from before) one value or nothing in its place.
fn one_or_many<'de, D, T>(deserializer: D) -> Result<Vec<T>, D::Error>
where
    D: serde::Deserializer<'de>,
    T: Deserialize<'de>,
{
    #[derive(Deserialize)]
    #[serde(untagged)]
    enum OneOrMany<T> {
        Many(Vec<T>),
        One(T),
    }
    Ok(match Option::<OneOrMany<T>>::deserialize(deserializer)? {
        Some(OneOrMany::Many(values)) => values,
        Some(OneOrMany::One(value)) => vec![value],
        None => Vec::new(),
    })
}

/// How a scene's truth was obtained, in run.json.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct TruthRecord {
    /// `truth-8x8`.
    pub id: String,
    pub samples_per_pixel: u32,
    /// SHA-256 of everything the image depends on (see [`crate::run::truth::cache_key`]).
    pub key: String,
    /// True when the image came from the cache and nothing was rendered.
    pub cached: bool,
    /// Wall-clock seconds of the render, read-back included (absent when cached).
    pub render_s: Option<f64>,
    pub tiles: Option<usize>,
    /// The process's peak resident memory during the render (Linux; absent when cached).
    pub peak_rss_bytes: Option<u64>,
    /// The display image, relative to the run folder.
    pub image: Option<String>,
    /// FNV-1a 64 of the display image's code values: what `compare` looks at to say whether the
    /// truth itself changed (its key changes with any edit of the rendering source).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub image_hash: Option<String>,
    /// Why there is no truth, when there is none.
    pub error: Option<String>,
}
