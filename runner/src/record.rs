//! The run record, `reports/<run-id>/run.json`: everything a run measured, schema versioned.
//! It is rewritten atomically after every scene, so a killed run leaves what finished.

use aabench_renderer::PlatformInfo;
use serde::{Deserialize, Serialize};

use crate::metrics::{Quality, SampleStats};
use crate::plan::Tier;
use crate::stats::Summary;

pub const RUN_SCHEMA: &str = "aabench.run/1";

#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Status {
    /// Still running (only in a record read while the run is alive, or killed).
    Running,
    Ok,
    Failed,
    /// Stopped by Ctrl-C before it finished.
    Interrupted,
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
    pub platform: Platform,
    pub settings: RunSettings,
    pub scenes: Vec<SceneRecord>,
}

/// The machine: results with the same `key` are comparable in absolute time.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct Platform {
    pub key: String,
    pub adapter: String,
    pub driver: String,
    pub driver_info: String,
    pub backend: String,
    pub device_type: String,
    pub lp_num_threads: Option<String>,
    pub cpu_model: String,
    pub cpu_cores: usize,
    pub build_profile: String,
}

impl From<&PlatformInfo> for Platform {
    fn from(info: &PlatformInfo) -> Platform {
        Platform {
            key: info.key(),
            adapter: info.adapter.clone(),
            driver: info.driver.clone(),
            driver_info: info.driver_info.clone(),
            backend: info.backend.clone(),
            device_type: info.device_type.clone(),
            lp_num_threads: info.lp_num_threads.clone(),
            cpu_model: info.cpu_model.clone(),
            cpu_cores: info.cpu_cores,
            build_profile: info.build_profile.to_string(),
        }
    }
}

#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct RunSettings {
    pub modes: Vec<String>,
    pub repetitions: u32,
    pub warmup: u32,
    pub frame_timeout_s: f64,
    /// How the frames were ordered: every repetition renders each mode once, in this order.
    pub interleaving: String,
    /// How adaptive modes shaded their extra samples: `compact` or `loop`.
    pub extra_samples: String,
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
    /// Bytes of render targets once every mode was prepared.
    pub target_bytes: Option<u64>,
    pub stall_iterations: u32,
    /// The mode whose image is the ground truth: the highest-M reference in the run.
    pub ground_truth: Option<String>,
    pub modes: Vec<ModeRecord>,
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
    /// Per pass, in submission order.
    pub passes: Vec<PassRecord>,
    /// Frame median over deferred-1x1's (same stall): travels between machines.
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
    /// Against the ground truth (every mode but the ground truth itself).
    pub vs_ground_truth: Option<Quality>,
    pub adaptive: Option<AdaptiveCost>,
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
    /// Heatmap of |image − reference| (reference: same-M reference, else the ground truth).
    pub difference: Option<String>,
}

/// An adaptive mode's time against its reference and against its own limit.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct AdaptiveCost {
    /// The reference at the same M and stall.
    pub reference: String,
    /// Reference frame median over this mode's.
    pub speedup: f64,
    /// G-buffer + S + evaluation + (samples shaded after S / M²·w·h) × the reference's
    /// shading pass, all medians: what adaptive would cost if shading scaled exactly with
    /// samples and its other passes were free. S's own share is not counted twice.
    pub limit_ms: f64,
    /// limit_ms over this mode's frame median: 1 means at the limit.
    pub efficiency: f64,
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
