//! Raw CLI arguments → a checked [`RunPlan`], before any GPU work: manifests found and parsed
//! (a bad one becomes a failed scene, not a failed run), modes resolved, tier settings fixed.
//! Beside it: how many timed rounds a mode takes (`repetitions.rs`) and the content hashes of
//! what determines a scene's images (`inputs.rs`).

pub mod inputs;
pub mod repetitions;

use std::path::{Path, PathBuf};
use std::time::Duration;

use aabench_renderer::{ExtraSamples, Mode};
use serde::{Deserialize, Serialize};

use crate::manifest::{Manifest, ManifestError};
use repetitions::{Confidence, DECIDING_ROUNDS, Repetitions};

/// One slice of a run: scene k of the plan (in manifest order) belongs to shard k mod N + 1.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub struct Shard {
    /// 1-based.
    pub index: u32,
    pub count: u32,
}

/// Longest a single frame may take unless `--frame-timeout` says.
pub fn default_frame_timeout() -> Duration {
    Duration::from_secs(120)
}

#[derive(Debug, clap::Args)]
pub struct RunArgs {
    /// Manifests or folders of manifests [default: scenes/].
    pub paths: Vec<PathBuf>,
    /// quick: 256×192 unless a manifest says (the stiff scenes: 160×120), up to 15 rounds (the
    /// suite and the CI gate); nightly: 1024×768, up to 7 rounds.
    #[arg(long, value_enum, default_value = "quick")]
    pub tier: Tier,
    /// Comma-separated mode ids or groups: baseline, adaptive, ablation, variant, stable [default: the tier's].
    #[arg(long)]
    pub modes: Option<String>,
    /// Folder that receives the run's folder.
    #[arg(long, default_value = "reports")]
    pub out: PathBuf,
    /// Timed rounds per mode, 1 to 10 000 [default: by confidence: each mode's rounds until its
    /// median frame time is known to ±5 %, or its scene's frames took 20 s, at least 9 and
    /// at most the tier's 15 (nightly 7)].
    #[arg(long, allow_negative_numbers = true, value_parser = clap::value_parser!(u32).range(1..=10_000))]
    pub repetitions: Option<u32>,
    /// Untimed rounds before timing (lavapipe compiles shaders at the first draw); at most 100.
    #[arg(long, default_value_t = 1, allow_negative_numbers = true, value_parser = clap::value_parser!(u32).range(0..=100))]
    pub warmup: u32,
    /// How adaptive modes shade their extra samples: compact (a dense list, the default) or
    /// loop (inside each pixel's invocation, the paper's simplest variant).
    #[arg(long, value_enum, default_value = "compact")]
    pub extra_samples: ExtraSamplesArg,
    /// Render only this slice of the scenes: `I/N` takes scenes I, I+N, I+2N, … (in manifest
    /// order). `aabench merge` joins the N shard runs into one.
    #[arg(long, value_name = "I/N", allow_hyphen_values = true)]
    pub shard: Option<String>,
    /// Folder that caches ground truths [default: cache/truth/ beside each manifest].
    #[arg(long, value_name = "DIR")]
    pub truth_cache: Option<PathBuf>,
    /// Memory the render targets of one scene's modes may take together, in GiB; a mode that
    /// would pass it fails before allocating, with its estimate [default: 90% of the memory
    /// available after the scene's upload].
    #[arg(long, value_name = "GIB", allow_negative_numbers = true)]
    pub memory_limit: Option<f64>,
    /// Whether scenes with a camera path (`motion`) are also rendered as sequences after their
    /// stills: off renders the stills alone (the gate's timing processes).
    #[arg(long, value_enum, default_value = "on")]
    pub sequences: Switch,
    /// Whether each mode's image is measured (against the ground truth and the mode it is
    /// compared with) and written: off times the modes alone, without the truth, TAA's stills,
    /// images, quality or sequences (the gate's timing processes after its first).
    #[arg(long, value_enum, default_value = "on")]
    pub quality: Switch,
    /// The display ColorVideoVDP judges every scene's JOD on, one of its named models
    /// (standard_fhd, standard_4k, standard_hdr_pq, …) [default: each manifest's
    /// `display.jod_display`: standard_fhd, or standard_hdr_pq for a pq display]
    #[arg(long, value_name = "MODEL")]
    pub jod_display: Option<String>,
    /// Write every frame of each sequence that ColorVideoVDP saw (the warm-up's first),
    /// display-encoded, as `<scene>/frames/<sequence>/<mode>/<NNN>.png` (the truth's as `truth`),
    /// with sequence.json beside them, for a video metric or an encoder of your own
    #[arg(long)]
    pub keep_frames: bool,
    /// Longest a single frame may take, in seconds.
    #[arg(
        long,
        value_name = "SECONDS",
        allow_negative_numbers = true,
        default_value_t = default_frame_timeout().as_secs_f64()
    )]
    pub frame_timeout: f64,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum Switch {
    On,
    Off,
}

#[derive(Debug, Clone, Copy, clap::ValueEnum)]
pub enum ExtraSamplesArg {
    Compact,
    Loop,
}

impl From<ExtraSamplesArg> for ExtraSamples {
    fn from(arg: ExtraSamplesArg) -> ExtraSamples {
        match arg {
            ExtraSamplesArg::Compact => ExtraSamples::Compact,
            ExtraSamplesArg::Loop => ExtraSamples::Loop,
        }
    }
}

impl RunArgs {
    /// The checked plan, its run folder created, and how many temporaries of killed runs were
    /// removed from `--out` first.
    pub fn plan(&self) -> Result<(RunPlan, usize), String> {
        let args = self;
        let modes = match &args.modes {
            Some(list) => parse_modes(list)?,
            None => args.tier.default_modes(),
        };
        // A day bounds it: `Duration` cannot hold every f64, and no frame takes longer.
        let frame_timeout = Duration::try_from_secs_f64(args.frame_timeout)
            .ok()
            .filter(|t| !t.is_zero() && *t <= Duration::from_secs(86_400))
            .ok_or_else(|| {
                format!(
                    "--frame-timeout {} must be a positive number of seconds, at most 86400",
                    args.frame_timeout
                )
            })?;
        let repetitions = args
            .repetitions
            .map_or_else(|| Repetitions::Confidence(args.tier.confidence()), Repetitions::Count);
        let memory_limit = args
            .memory_limit
            .map(|gib| {
                (gib.is_finite() && gib > 0.0 && gib <= 1e6)
                    .then(|| (gib * f64::from(1u32 << 30)) as u64)
                    .ok_or_else(|| format!("--memory-limit {gib} must be a positive number of GiB"))
            })
            .transpose()?;
        let shard = args.shard.as_deref().map(parse_shard).transpose()?;
        if let Some(name) = &args.jod_display {
            aabench_cvvdp::Display::named(name).map_err(|error| {
                format!("--jod-display: {error}; one of: {}", aabench_cvvdp::Display::names().join(", "))
            })?;
        }
        if args.keep_frames && (args.sequences == Switch::Off || args.quality == Switch::Off) {
            let off = if args.quality == Switch::Off { "--quality off" } else { "--sequences off" };
            return Err(format!(
                "--keep-frames keeps the frames of the camera paths' sequences, which {off} leaves out: drop one of the two"
            ));
        }
        let manifests = find_manifests(&args.paths)?;
        // Temporaries of killed runs (run folder, scene folders, sequence spools) go before this
        // run adds its own.
        let stale = remove_stale_temporaries(&args.out, RUN_DEPTH + 1);
        let (run_id, run_dir) = create_run_dir(&args.out, &new_run_id(args.tier, shard))?;
        Ok((
            RunPlan {
                tier: args.tier,
                scenes: select_shard(load_scenes(&manifests), shard),
                modes,
                repetitions,
                warmup: args.warmup,
                frame_timeout,
                extra_samples: args.extra_samples.into(),
                sequences: args.sequences == Switch::On && args.quality == Switch::On,
                quality: args.quality == Switch::On,
                jod_display: args.jod_display.clone(),
                keep_frames: args.keep_frames,
                truth_cache: args.truth_cache.clone(),
                shard,
                memory_limit,
                run_dir,
                run_id,
            },
            stale,
        ))
    }
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, clap::ValueEnum)]
#[serde(rename_all = "lowercase")]
pub enum Tier {
    /// Small resolution, many repetitions: the CI gate.
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

    /// The output resolution a manifest asks for in this tier.
    pub fn resolution(self, manifest: &crate::manifest::Manifest) -> [u32; 2] {
        match self {
            Tier::Quick => manifest.resolution.quick,
            Tier::Nightly => manifest.resolution.nightly,
        }
    }

    /// The speeds in pixels a frame that a camera path lists for this tier, if it lists any.
    pub fn speeds(self, motion: &crate::manifest::motion::MotionSpec) -> Option<&[f64]> {
        let speeds = motion.pixels_per_frame.as_ref()?;
        Some(match self {
            Tier::Quick => &speeds.quick,
            Tier::Nightly => &speeds.nightly,
        })
    }

    /// The sequences of a camera path in this tier: one per speed it lists, or one at its rate.
    pub fn paces(
        self,
        manifest: &crate::manifest::Manifest,
        fov_y: f64,
    ) -> Vec<crate::manifest::motion::Pace> {
        let Some(motion) = &manifest.motion else { return Vec::new() };
        motion.paces(self.speeds(motion), fov_y, self.resolution(manifest)[1])
    }

    /// The frames of a camera path's sequence in this tier.
    pub fn sequence_frames(self, motion: &crate::manifest::motion::MotionSpec) -> u32 {
        match self {
            Tier::Quick => motion.frames.quick,
            Tier::Nightly => motion.frames.nightly,
        }
    }

    /// The most timed rounds of a mode when the run takes them by confidence. The quick tier
    /// is the default suite's and the one the gate compares with the baselines; its time
    /// against the base build the gate decides from processes of its own, 3 rounds each
    /// (`docs/gate.md`). Where time is gated by one run against the baselines of the machine
    /// that blessed them (no git history), `ci/gate.sh` times 25 rounds: one frame's time
    /// varies by about 10 % from the next on these machines.
    pub fn most_rounds(self) -> u32 {
        match self {
            Tier::Quick => 15,
            Tier::Nightly => 7,
        }
    }

    /// How the suite takes its rounds when `--repetitions` does not say: until each mode's
    /// median is known to ±5 % (its interval no wider than the gate's 10 % time tolerance, so
    /// that a change of that size shows), or its scene's timed frames
    /// took 20 s (four of criterion's 5 s measurement times: most quick scenes time their 15
    /// rounds within it, the heaviest stop early), at least the 9 from which the rankings and
    /// fronts compare two modes past one round out of line ([`DECIDING_ROUNDS`]; the 5 a time
    /// check needs, [`crate::manifest::tolerances::MIN_FRAMES`], decide only where every round agrees) and at
    /// most [`Tier::most_rounds`]. On the suite's own
    /// recorded rounds this keeps all but about 3 % of the front's memberships that 15 rounds
    /// decide (`docs/measuring.md`).
    pub fn confidence(self) -> Confidence {
        Confidence {
            floor: DECIDING_ROUNDS.min(self.most_rounds()),
            most: self.most_rounds(),
            width: 0.10,
            budget_s: 20.0,
        }
    }

    /// The modes run when `--modes` is not given: baselines, adaptive, the unstalled `-area`
    /// and `-cells` variants and `adaptive-4x4-stable` (whose stills are the paper's: the gate
    /// guards its sequences); the nightly tier adds the unstalled ablations, the stalled
    /// `-cells` modes (which shade other samples than the paper's, so their stalled time is
    /// their own, where `-area` differs from the paper only in `gather`), `-coverage`, plain
    /// and stalled (its fixed passes cost more than it saves at the quick tier's size, so it is
    /// measured where it can pay), and every unstalled `-stable` mode.
    pub fn default_modes(self) -> Vec<Mode> {
        use aabench_renderer::Reconstruction::{Cells, Coverage, Equal};
        let mut modes = Mode::baseline_modes();
        modes.extend(Mode::adaptive_modes());
        let nightly = self == Tier::Nightly;
        modes.extend(Mode::variant_modes().into_iter().filter(|m| match m.reconstruction() {
            Coverage => nightly,
            Cells => !m.stalled || nightly,
            _ => !m.stalled,
        }));
        if nightly {
            modes.extend(Mode::ablation_modes().into_iter().filter(|m| !m.stalled));
        }
        modes.extend(
            Mode::stable_modes()
                .into_iter()
                .filter(|m| !m.stalled && (nightly || (m.m == 4 && m.reconstruction() == Equal))),
        );
        modes
    }

    /// The modes that the gate's timing processes time (`aabench modes --tier T --timed-by-gate`):
    /// the paper's and the competitors' unstalled modes at every size, each adaptive variant at
    /// its largest size, and the cheapest stalled mode. A variant's own code (another metric,
    /// reconstruction or count rule) is the same shader at every M and takes the largest share
    /// of the frame at the largest, where the gate sees a slowdown of it best; the passes it
    /// shares with the paper's mode are timed there at every size. A stalled mode renders its
    /// unstalled twin's image from the samples its twin shades (both gated exactly, with every
    /// process's output hash), each shaded with the stall loop on top; what its time adds to its
    /// twin's is that loop, which `deferred-1x1-stalled` times for all of them.
    pub fn gate_timed_modes(self) -> Vec<Mode> {
        use aabench_renderer::Technique;
        let sentinel = Mode::new(Technique::Deferred, 1, true);
        let modes = self.default_modes();
        let largest =
            |technique: Technique| modes.iter().filter(|m| m.technique == technique).map(|m| m.m).max();
        let timed = |mode: &Mode| match mode.technique {
            _ if mode.stalled => *mode == sentinel,
            Technique::Adaptive(..) if mode.technique != Technique::PAPER => {
                Some(mode.m) == largest(mode.technique)
            }
            _ => true,
        };
        modes.iter().copied().filter(timed).collect()
    }
}

/// Parses `--modes`: comma-separated mode ids or the groups `baseline`, `adaptive`, `ablation`,
/// `variant`, `stable`.
pub fn parse_modes(list: &str) -> Result<Vec<Mode>, String> {
    let mut modes: Vec<Mode> = Vec::new();
    for item in list.split(',').map(str::trim).filter(|s| !s.is_empty()) {
        let group = match Mode::groups().into_iter().find(|(name, _)| *name == item) {
            Some((_, modes)) => modes,
            None => vec![item.parse::<Mode>().map_err(|e| e.to_string())?],
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
    pub repetitions: Repetitions,
    pub warmup: u32,
    pub frame_timeout: Duration,
    pub extra_samples: ExtraSamples,
    /// Whether scenes with a camera path are rendered as sequences too.
    pub sequences: bool,
    /// Whether each mode's image is measured and written (`--quality`); without it the run
    /// holds frame and pass times, adaptive costs and the output hashes of the modes without
    /// history alone.
    pub quality: bool,
    /// ColorVideoVDP's display for every scene (`--jod-display`); `None`: each manifest's.
    pub jod_display: Option<String>,
    /// Whether each sequence's frames are written as PNGs (`--keep-frames`).
    pub keep_frames: bool,
    /// Where ground truths are cached; `None`: `cache/truth/` beside each manifest.
    pub truth_cache: Option<PathBuf>,
    /// The slice of the scenes this run renders, if not all.
    pub shard: Option<Shard>,
    /// Bytes the render targets of one scene's modes may take together; `None`: 90% of the
    /// memory available after the scene's upload.
    pub memory_limit: Option<u64>,
    /// `reports/<run-id>`, created by [`create_run_dir`].
    pub run_dir: PathBuf,
    pub run_id: String,
}

impl RunPlan {
    /// The ColorVideoVDP display `manifest`'s JOD is judged on, or why the one `--jod-display`
    /// names cannot decode its display images.
    pub fn jod_display(&self, manifest: &Manifest) -> Result<String, String> {
        match &self.jod_display {
            Some(name) => crate::manifest::check_jod_display(name, manifest.display.transfer)
                .map(|()| name.clone())
                .map_err(|why| format!("--jod-display: {why}")),
            None => Ok(manifest.display.jod_display().to_string()),
        }
    }

    /// The folder that caches `manifest`'s ground truths.
    pub fn truth_cache_dir(&self, manifest: &Manifest) -> PathBuf {
        self.truth_cache
            .clone()
            .unwrap_or_else(|| manifest.path.parent().unwrap_or(Path::new(".")).join("cache").join("truth"))
    }
}

/// Parses `--shard I/N` (cargo-nextest's `--partition count:I/N` convention): 1 ≤ I ≤ N.
pub fn parse_shard(text: &str) -> Result<Shard, String> {
    let bad = || format!("--shard {text}: expected I/N with 1 ≤ I ≤ N, e.g. 2/4");
    let (index, count) = text.split_once('/').ok_or_else(bad)?;
    let (index, count) =
        (index.trim().parse::<u32>().map_err(|_| bad())?, count.trim().parse::<u32>().map_err(|_| bad())?);
    if index == 0 || index > count {
        return Err(bad());
    }
    Ok(Shard { index, count })
}

/// The scenes of one shard: scene k (0-based, in manifest order, failed manifests included)
/// belongs to shard k mod N + 1. A scene's modes stay together: they are compared with each
/// other in the run (ratios to deferred-1x1, adaptive against reference) and share its truth.
pub fn select_shard<T>(scenes: Vec<T>, shard: Option<Shard>) -> Vec<T> {
    let Some(Shard { index, count }) = shard else { return scenes };
    scenes
        .into_iter()
        .enumerate()
        .filter(|(k, _)| *k as u32 % count == index - 1)
        .map(|(_, scene)| scene)
        .collect()
}

/// Finds the manifests named by `paths`: files as given, folders by their `*.json` files in
/// name order. Nothing given means `scenes/`.
pub fn find_manifests(paths: &[PathBuf]) -> Result<Vec<PathBuf>, String> {
    let paths = if paths.is_empty() { vec![PathBuf::from("scenes")] } else { paths.to_vec() };
    let mut found = Vec::new();
    for path in paths {
        if path.is_dir() {
            let files = crate::files::files_in(&path)?;
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

/// A run id that sorts by time: `20261122T101503Z-quick` (`…-quick-shard2of4` for a shard),
/// with a suffix when taken.
pub fn new_run_id(tier: Tier, shard: Option<Shard>) -> String {
    let stamp =
        humantime::format_rfc3339_seconds(std::time::SystemTime::now()).to_string().replace(['-', ':'], "");
    let shard = shard.map_or(String::new(), |s| format!("-shard{}of{}", s.index, s.count));
    format!("{stamp}-{}{shard}", tier.name())
}

/// Creates the run's folder `out/<id>`, or `out/<id>-2`, `-3`, … when another run holds the
/// name: creation itself is the test, so two runs started in the same second never share one.
/// Returns the id taken and the folder.
pub fn create_run_dir(out: &Path, id: &str) -> Result<(String, PathBuf), String> {
    crate::files::output_folder(out).map_err(|e| format!("--out {e}"))?;
    for n in 1..10_000 {
        let candidate = if n == 1 { id.to_string() } else { format!("{id}-{n}") };
        let dir = out.join(&candidate);
        match std::fs::create_dir(&dir) {
            Ok(()) => return Ok((candidate, dir)),
            Err(e) if e.kind() == std::io::ErrorKind::AlreadyExists => continue,
            Err(e) => return Err(format!("--out {}: cannot create a run folder: {e}", out.display())),
        }
    }
    Err(format!("--out {}: 10 000 runs named {id} already", out.display()))
}

/// How deep under a run's folder its temporaries lie: `<scene>/path/.spool.tmp-<pid>`.
pub const RUN_DEPTH: u32 = 2;

/// A temporary file written to this recently is left alone even when its owner looks dead: a
/// writer in another PID namespace (a container sharing the folder) is not in our /proc.
const STALE_AFTER: std::time::Duration = std::time::Duration::from_secs(60);

/// Removes the temporary files and staging folders (`<name>.tmp-<pid>`) that killed processes
/// left under `dir`, down to `depth` folders; those of live processes, and any written to in
/// the last `STALE_AFTER`, are left alone. Returns how many went.
pub fn remove_stale_temporaries(dir: &Path, depth: u32) -> usize {
    let Ok(entries) = std::fs::read_dir(dir) else {
        return 0;
    };
    let mut removed = 0;
    for entry in entries.flatten() {
        let path = entry.path();
        let Ok(kind) = entry.file_type() else { continue };
        let stale = || {
            temporary_owner(&path).is_some_and(|pid| !Path::new("/proc").join(pid.to_string()).exists())
                && entry
                    .metadata()
                    .and_then(|m| m.modified())
                    .is_ok_and(|t| t.elapsed().unwrap_or_default() > STALE_AFTER)
        };
        // Folders named like temporaries are a killed bless's or merge's staging folders.
        let gone = if kind.is_dir() && stale() {
            std::fs::remove_dir_all(&path).is_ok()
        } else if kind.is_dir() && depth > 0 {
            removed += remove_stale_temporaries(&path, depth - 1);
            false
        } else {
            kind.is_file() && stale() && std::fs::remove_file(&path).is_ok()
        };
        removed += usize::from(gone);
    }
    removed
}

/// The process id in a temporary file's name (`run.json.tmp-4242` → 4242, and
/// `a.exr.tmp-4242.exr`: the EXR writer keeps the extension).
fn temporary_owner(path: &Path) -> Option<u32> {
    let name = path.file_name()?.to_str()?;
    let (_, rest) = name.rsplit_once(".tmp-")?;
    let digits = rest.split('.').next()?;
    digits.parse().ok()
}

/// The scene name that a manifest path would have, for failed manifests.
pub fn fallback_name(path: &Path) -> String {
    path.file_stem().map_or_else(|| "unnamed".into(), |s| s.to_string_lossy().into_owned())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn run_folders_are_created_once_each() {
        let out = std::env::temp_dir().join(format!("aabench-plan-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&out);
        let (a, dir_a) = create_run_dir(&out, "20260101T000000Z-quick").unwrap();
        let (b, dir_b) = create_run_dir(&out, "20260101T000000Z-quick").unwrap();
        assert_eq!((a.as_str(), b.as_str()), ("20260101T000000Z-quick", "20260101T000000Z-quick-2"));
        assert!(dir_a.is_dir() && dir_b.is_dir());

        // A dead process's old temporary goes; a live one's (ours) and a fresh one stay.
        let old = |path: std::path::PathBuf| {
            std::fs::write(&path, "x").unwrap();
            let file = std::fs::File::options().write(true).open(&path).unwrap();
            file.set_modified(std::time::SystemTime::now() - 2 * STALE_AFTER).unwrap();
            path
        };
        old(dir_a.join("run.json.tmp-4294967295"));
        old(dir_a.join("mode.exr.tmp-4294967295.exr"));
        let ours = old(dir_b.join(format!("run.json.tmp-{}", std::process::id())));
        let fresh = dir_b.join("other.json.tmp-4294967295");
        std::fs::write(&fresh, "x").unwrap();
        std::fs::write(dir_b.join("run.json"), "{}").unwrap();
        // A killed sequence's spool, three folders down: a folder named as a dead process's
        // temporary, untouched for a while.
        let path = dir_a.join("thin").join("path");
        let spool = crate::run::spool::folder(&path).with_file_name(".spool.tmp-4294967295");
        std::fs::create_dir_all(&spool).unwrap();
        std::fs::write(spool.join("0.rgba"), "x").unwrap();
        std::fs::File::open(&spool)
            .unwrap()
            .set_modified(std::time::SystemTime::now() - 2 * STALE_AFTER)
            .unwrap();
        assert_eq!(remove_stale_temporaries(&out, 2), 2, "a spool lies deeper than a run's own temporaries");
        assert_eq!(
            remove_stale_temporaries(&dir_a, RUN_DEPTH),
            1,
            "a report or compare of the run removes it"
        );
        assert!(!spool.exists() && path.exists());
        assert!(ours.exists() && fresh.exists() && dir_b.join("run.json").exists());
        std::fs::remove_dir_all(&out).unwrap();
    }

    #[test]
    fn groups_and_ids_combine_without_duplicates() {
        let modes = parse_modes("baseline, deferred-1x1,adaptive-2x2-geometry").unwrap();
        let baseline = Mode::baseline_modes();
        // The group in its order, then the one id it did not already hold.
        assert_eq!(&modes[..baseline.len()], &baseline[..]);
        let rest: Vec<String> = modes[baseline.len()..].iter().map(Mode::to_string).collect();
        assert_eq!(rest, ["adaptive-2x2-geometry"]);
        assert!(parse_modes("reference-9x9").unwrap_err().contains("M must be"));
        assert!(parse_modes(" , ").is_err());
    }

    #[test]
    fn shards_split_scenes_round_robin_and_cover_them_once() {
        assert_eq!(parse_shard("2/4"), Ok(Shard { index: 2, count: 4 }));
        for bad in ["0/4", "5/4", "2", "a/b", "1/0"] {
            assert!(parse_shard(bad).is_err(), "{bad}");
        }
        let scenes: Vec<u32> = (0..7).collect();
        assert_eq!(select_shard(scenes.clone(), Some(Shard { index: 2, count: 3 })), vec![1, 4]);
        let mut union: Vec<u32> =
            (1..=3).flat_map(|index| select_shard(scenes.clone(), Some(Shard { index, count: 3 }))).collect();
        union.sort();
        assert_eq!(union, scenes);
        assert_eq!(select_shard(scenes.clone(), None), scenes);
    }

    #[test]
    fn quick_leaves_out_the_ablations_and_nightly_adds_them() {
        let quick = Tier::Quick.default_modes();
        let nightly = Tier::Nightly.default_modes();
        for modes in [&quick, &nightly] {
            for (i, mode) in modes.iter().enumerate() {
                assert!(!modes[..i].contains(mode), "{mode} twice");
            }
        }
        assert!(quick.iter().all(|m| nightly.contains(m)), "the quick tier is a subset of the nightly");
        // Every technique the paper is compared with, and the paper's modes, in both.
        for mode in Mode::baseline_modes().iter().chain(&Mode::adaptive_modes()) {
            assert!(quick.contains(mode), "{mode} not in the quick tier");
        }
        let has = |modes: &[Mode], test: &dyn Fn(&Mode) -> bool| modes.iter().filter(|m| test(m)).count();
        let ablation = |m: &Mode| matches!(m.technique, aabench_renderer::Technique::Adaptive(metrics, ..) if metrics != aabench_renderer::Metrics::Both);
        assert_eq!(has(&quick, &ablation), 0);
        assert!(has(&nightly, &ablation) > 0 && nightly.iter().filter(|m| ablation(m)).all(|m| !m.stalled));
        let area: Vec<String> = quick.iter().map(Mode::to_string).filter(|id| id.contains("area")).collect();
        assert_eq!(area, ["adaptive-2x2-area", "adaptive-3x3-area", "adaptive-4x4-area"]);
        // Nightly-only: the stalled -cells modes, every -coverage mode, the -stable modes but
        // adaptive-4x4-stable.
        let stalled_cells =
            |m: &Mode| m.stalled && m.reconstruction() == aabench_renderer::Reconstruction::Cells;
        let coverage = |m: &Mode| m.reconstruction() == aabench_renderer::Reconstruction::Coverage;
        for nightly_only in [&stalled_cells as &dyn Fn(&Mode) -> bool, &coverage] {
            assert_eq!(has(&quick, nightly_only), 0);
            assert!(Mode::variant_modes().iter().filter(|m| nightly_only(m)).all(|m| nightly.contains(m)));
        }
        let stable: Vec<String> = quick
            .iter()
            .filter(|m| m.counts() == aabench_renderer::Counts::Stable)
            .map(Mode::to_string)
            .collect();
        assert_eq!(stable, ["adaptive-4x4-stable"]);
        assert!(Mode::stable_modes().iter().filter(|m| !m.stalled).all(|m| nightly.contains(m)));
    }

    #[test]
    fn the_gate_times_the_papers_and_the_competitors_modes_each_variant_once_and_one_stalled() {
        use aabench_renderer::Technique;
        for tier in [Tier::Quick, Tier::Nightly] {
            let all = tier.default_modes();
            let timed = tier.gate_timed_modes();
            let stalled: Vec<String> = timed.iter().filter(|m| m.stalled).map(Mode::to_string).collect();
            assert_eq!(stalled, ["deferred-1x1-stalled"]);
            assert!(timed.iter().all(|m| all.contains(m)));
            let variant =
                |m: &Mode| matches!(m.technique, Technique::Adaptive(..)) && m.technique != Technique::PAPER;
            let unstalled = all.iter().filter(|m| !m.stalled);
            assert!(unstalled.clone().filter(|m| !variant(m)).all(|m| timed.contains(m)), "{tier:?}");
            // Every variant of the tier is timed, at its largest size alone.
            for mode in unstalled.filter(|m| variant(m)) {
                let sizes: Vec<u32> =
                    timed.iter().filter(|t| t.technique == mode.technique).map(|t| t.m).collect();
                assert_eq!(sizes, [4], "{mode}");
            }
        }
        let quick: Vec<String> = Tier::Quick.gate_timed_modes().iter().map(Mode::to_string).collect();
        assert!(quick.contains(&"adaptive-4x4-cells".into()) && !quick.contains(&"adaptive-2x2-area".into()));
        assert_eq!(quick.len(), 15, "{quick:?}");
    }
}
