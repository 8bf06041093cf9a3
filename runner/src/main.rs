//! The `aabench` command line.

use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};

use aabench::manifest::Manifest;
use aabench::plan::{self, ExtraSamplesArg, RunArgs, Tier};
use aabench::progress::Progress;
use aabench::record::{RunRecord, Status};
use aabench::{baseline, compare, exit, run, scenes};
use aabench_renderer::{ExtraSamples, Mode};
use clap::{Parser, Subcommand};

/// Set when writing to stdout failed for another reason than a closed pipe (a full disk behind a
/// redirect): the command's output is lost, so it exits 2 whatever it did.
static STDOUT_FAILED: AtomicBool = AtomicBool::new(false);

/// Text on stdout. A closed pipe (`aabench modes | head -1`) is no error: the reader took what
/// it wanted, so the rest is dropped quietly. Any other failure marks the command failed.
fn out(text: std::fmt::Arguments) {
    use std::io::Write as _;
    let mut stdout = std::io::stdout().lock();
    if let Err(error) = stdout.write_fmt(text).and_then(|()| stdout.flush())
        && error.kind() != std::io::ErrorKind::BrokenPipe
        && !STDOUT_FAILED.swap(true, Ordering::SeqCst)
    {
        note(format_args!("aabench: cannot write to standard output: {error}\n"));
    }
}

/// Text on stderr. A closed or full stderr is ignored: messages are a courtesy, the exit code
/// carries the verdict (`aabench compare … 2>&1 | head -1` keeps compare's code).
fn note(text: std::fmt::Arguments) {
    use std::io::Write as _;
    let _ = std::io::stderr().lock().write_fmt(text);
}

/// A line on stdout (see [`out`]).
macro_rules! say {
    ($($arg:tt)*) => { out(format_args!("{}\n", format_args!($($arg)*))) };
}

/// A line on stderr (see [`note`]).
macro_rules! tell {
    ($($arg:tt)*) => { note(format_args!("{}\n", format_args!($($arg)*))) };
}

#[derive(Debug, Parser)]
#[command(
    name = "aabench",
    version,
    about = "Benchmark and regression service for anti-aliasing in a deferred renderer"
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Debug, Subcommand)]
enum Command {
    /// Render every mode of the given scenes on lavapipe; write reports/<run-id>/run.json and images.
    Run(RunArgs),
    /// Generate the glTF files of manifests that say how (`generate`), into their cache folders.
    GenScenes {
        /// Manifests or folders of manifests [default: scenes/].
        paths: Vec<PathBuf>,
        /// Regenerate even files that are current.
        #[arg(long)]
        force: bool,
    },
    /// Write the ok scenes of one or more runs (separate processes of one build, pooled) as
    /// baselines: <baseline>/<platform-key>/<tier>/<scene>.json.
    Bless {
        /// The runs: their folders or run.json files.
        #[arg(required = true)]
        runs: Vec<PathBuf>,
        /// The baselines' root folder.
        #[arg(long, default_value = "baselines")]
        baseline: PathBuf,
        /// Replace baselines of another platform key, tier or schema, and files that are no
        /// baseline.
        #[arg(long)]
        force: bool,
        /// Why the paper's mode (adaptive-MxM) renders other bits than its baseline: required
        /// when it does, and kept in the baselines written.
        #[arg(long, value_name = "TEXT")]
        why: Option<String>,
    },
    /// Rewrite baselines of an older schema in today's, value for value (a tier's folder at
    /// once); baselines of today's schema are left as they are.
    Upgrade {
        /// The baselines' root folder.
        #[arg(long, default_value = "baselines")]
        baseline: PathBuf,
    },
    /// Decide per scene × mode × metric whether a run regressed against its baselines; write
    /// summary.md, junit.xml and verdict.json. Exit 0: nothing regressed, 1: something did, or
    /// the run compared less than its baselines hold, 2: an error.
    Compare(CompareArgs),
    /// Write a static, self-contained index.html beside each run: per scene the modes, error
    /// against run time, images and crops, the gate's verdict, and metrics over past runs.
    Report {
        /// Runs: their folders or run.json files.
        #[arg(required = true)]
        runs: Vec<PathBuf>,
        /// Folder of earlier runs (run.json files, or folders holding one) to plot metrics over.
        #[arg(long)]
        history: Option<PathBuf>,
        /// The verdict to show [default: verdict.json in the run's folder, if there is one].
        #[arg(long)]
        verdict: Option<PathBuf>,
        /// Print the run's results as Markdown instead (one run): where it came from, an
        /// overview of the main modes per scene, then each scene's table; for documentation.
        #[arg(long, conflicts_with_all = ["history", "verdict"])]
        markdown: bool,
        /// With --markdown: also write each scene's error-against-run-time plot
        /// (`<scene>-front.svg`) and a strip of crops (`<scene>-strip.png`) into this folder.
        #[arg(long, requires = "markdown", value_name = "DIR")]
        figures: Option<PathBuf>,
    },
    /// Join the shard runs of one suite (`run --shard I/N`) into one run with their images.
    Merge {
        /// The shard runs: their folders or run.json files.
        #[arg(required = true)]
        runs: Vec<PathBuf>,
        /// The new run's folder.
        #[arg(long)]
        out: PathBuf,
    },
    /// Join the verdicts of a sharded gate (each shard compared on its own machine) into one
    /// summary.md, junit.xml and verdict.json. Exit 0: nothing regressed, 1: something did, or
    /// a baseline's scene was in no shard, 2: the shards do not belong together (one missing or
    /// given twice, another build, base, tier or platform).
    MergeVerdicts {
        /// The shards' verdict folders or verdict.json files.
        #[arg(required = true)]
        verdicts: Vec<PathBuf>,
        /// Folder for the joined summary.md, junit.xml and verdict.json.
        #[arg(long)]
        out: PathBuf,
    },
    /// Print the pass graph of one mode of a scene: passes in order, their ports, the
    /// allocation each port got and its lifetime, and the bytes against one allocation per
    /// output and the lower bound.
    Graph {
        /// The scene's manifest.
        manifest: PathBuf,
        /// The mode id, e.g. adaptive-2x2.
        #[arg(long)]
        mode: String,
        /// Whose resolution to compile for.
        #[arg(long, value_enum, default_value = "quick")]
        tier: Tier,
        /// How adaptive modes shade their extra samples.
        #[arg(long, value_enum, default_value = "compact")]
        extra_samples: ExtraSamplesArg,
        /// Write Graphviz instead of the table (`aabench graph … --dot | dot -Tsvg`).
        #[arg(long)]
        dot: bool,
    },
    /// Print the Vulkan adapter and the platform key that results are filed under.
    Info,
    /// List the mode ids and groups that --modes accepts; with --tier, the modes that the tier
    /// runs, one per line.
    Modes {
        #[arg(long, value_enum)]
        tier: Option<Tier>,
        /// Only the modes of the tier whose time the regression gate compares with the base
        /// build (its timing processes render these).
        #[arg(long, requires = "tier")]
        timed_by_gate: bool,
    },
}

#[derive(Debug, clap::Args)]
struct CompareArgs {
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

fn main() -> ExitCode {
    quiet_mesa_device_select();
    let cli = Cli::parse();
    let code = match cli.command {
        Command::Run(args) => run_command(args),
        Command::GenScenes { paths, force } => gen_scenes(&paths, force),
        Command::Bless { runs, baseline, force, why } => {
            bless(&runs, &baseline, baseline::Consent { force, why: why.as_deref() })
        }
        Command::Upgrade { baseline } => match baseline::upgrade(&baseline) {
            Ok(written) => {
                for path in &written {
                    say!("upgraded {}", path.display());
                }
                if written.is_empty() {
                    say!("every baseline under {} is of today's schema", baseline.display());
                }
                exit::OK
            }
            Err(message) => fail(message),
        },
        Command::Compare(args) => compare(&args),
        Command::Report { runs, markdown: true, figures, .. } => markdown_report(&runs, figures.as_deref()),
        Command::Report { runs, history, verdict, .. } => {
            report(&runs, history.as_deref(), verdict.as_deref())
        }
        Command::Merge { runs, out } => merge(&runs, &out),
        Command::MergeVerdicts { verdicts, out } => merge_verdicts(&verdicts, &out),
        Command::Graph { manifest, mode, tier, extra_samples, dot } => {
            match print_graph(&manifest, &mode, tier, extra_samples.into(), dot) {
                Ok(()) => exit::OK,
                Err(error) => fail(format!("{error:#}")),
            }
        }
        Command::Info => info(),
        Command::Modes { tier: None, .. } => {
            list_modes();
            exit::OK
        }
        Command::Modes { tier: Some(tier), timed_by_gate } => {
            let modes = if timed_by_gate { tier.gate_timed_modes() } else { tier.default_modes() };
            for mode in modes {
                say!("{mode}");
            }
            exit::OK
        }
    };
    // Output the reader never got is a failure, whatever the command decided.
    if STDOUT_FAILED.load(Ordering::SeqCst) { ExitCode::from(exit::ERROR) } else { ExitCode::from(code) }
}

fn fail(message: impl std::fmt::Display) -> u8 {
    tell!("aabench: {message}");
    exit::ERROR
}

fn run_command(args: RunArgs) -> u8 {
    let plan = match args.plan() {
        Ok((plan, stale)) => {
            if stale > 0 {
                tell!(
                    "aabench: removed {stale} temporary file(s) that killed runs left in {}",
                    args.out.display()
                );
            }
            plan
        }
        Err(message) => return fail(message),
    };
    let runtime = match tokio::runtime::Builder::new_multi_thread().enable_all().build() {
        Ok(runtime) => runtime,
        Err(error) => return fail(format!("cannot start the async runtime: {error}")),
    };
    let code = runtime.block_on(async move {
        let progress = Progress::new();
        let cancel = Arc::new(AtomicBool::new(false));
        let flag = Arc::clone(&cancel);
        let hangup = !hangup_ignored();
        tokio::spawn(async move {
            let Some(signal) = interruption(hangup).await else { return };
            flag.store(true, Ordering::SeqCst);
            progress.line(&format!(
                "{signal}: finishing the current frame and writing what was measured (a second signal quits now)"
            ));
            if interruption(hangup).await.is_some() {
                std::process::exit(i32::from(exit::INTERRUPTED));
            }
        });
        match run::execute(&plan, progress, cancel).await {
            Ok(outcome) => {
                // The summary (with the scenes that failed, and why) is the run's last word.
                aabench::report::closing(&outcome.record, &outcome.run_json).iter().for_each(|l| progress.line(l));
                match outcome.record.status {
                    Status::Ok => exit::OK,
                    Status::Interrupted => exit::INTERRUPTED,
                    _ => exit::SCENE_FAILED,
                }
            }
            // Errors print whole; `no Vulkan adapter` prints as its one-line install hint.
            Err(error) => fail(format!("{error:#}")),
        }
    });
    // An image task that a signal cut short may still run: dropping the runtime would wait.
    runtime.shutdown_background();
    code
}

/// Waits for SIGINT, SIGTERM or (when `hangup`) SIGHUP: what a terminal, `kill` and a
/// cancelled CI job send. Returns its name, or `None` if no handler could be installed.
async fn interruption(hangup: bool) -> Option<&'static str> {
    use tokio::signal::unix::{SignalKind, signal};
    let mut terminate = signal(SignalKind::terminate()).ok()?;
    let mut hung_up = if hangup { Some(signal(SignalKind::hangup()).ok()?) } else { None };
    let hung_up = async {
        match &mut hung_up {
            Some(signal) => signal.recv().await,
            None => std::future::pending().await,
        }
    };
    tokio::select! {
        result = tokio::signal::ctrl_c() => result.ok().map(|()| "SIGINT"),
        _ = terminate.recv() => Some("SIGTERM"),
        _ = hung_up => Some("SIGHUP"),
    }
}

/// Whether SIGHUP was ignored when aabench started (`nohup aabench run …`): then it stays
/// ignored, as the user asked, instead of interrupting the run when the terminal closes.
#[allow(unsafe_code)]
fn hangup_ignored() -> bool {
    // SAFETY: sigaction with a null new action only reads the current disposition into a
    // zero-initialized struct that outlives the call.
    unsafe {
        let mut current: libc::sigaction = std::mem::zeroed();
        libc::sigaction(libc::SIGHUP, std::ptr::null(), &mut current) == 0
            && current.sa_sigaction == libc::SIG_IGN
    }
}

fn gen_scenes(paths: &[PathBuf], force: bool) -> u8 {
    let manifests = match plan::find_manifests(paths) {
        Ok(manifests) => manifests,
        Err(message) => return fail(message),
    };
    let mut code = exit::OK;
    for path in manifests {
        let result = Manifest::load(&path).map_err(anyhow::Error::from).and_then(|manifest| {
            if manifest.generate.is_none() {
                return Ok(format!("{}: not generated (no `generate` section)", manifest.name));
            }
            let start = std::time::Instant::now();
            let wrote = scenes::ensure_generated(&manifest, force)?;
            Ok(if wrote {
                format!(
                    "{}: wrote {} in {:.1} s",
                    manifest.name,
                    manifest.gltf_path().display(),
                    start.elapsed().as_secs_f64()
                )
            } else {
                format!("{}: {} is current", manifest.name, manifest.gltf_path().display())
            })
        });
        match result {
            Ok(line) => say!("{line}"),
            Err(error) => code = fail(format!("{error:#}")),
        }
    }
    code
}

fn bless(runs: &[PathBuf], root: &Path, consent: baseline::Consent) -> u8 {
    let loaded: Result<Vec<_>, String> = runs.iter().map(|run| aabench::record::load_run(run)).collect();
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
    let changes = aabench::moved::between(replaced, &written);
    let runs: Vec<&str> = records.iter().map(|r| r.run_id.as_str()).collect();
    let heading = format!(
        "{} scene(s) of `{}/{}` blessed from run(s) `{}`, against the baselines they replace.",
        written.len(),
        run.platform.key,
        run.tier.name(),
        runs.join("`, `")
    );
    let text = aabench::moved::markdown(&changes, &heading);
    say!("{text}");
    let path = folder.join("bless.md");
    aabench::fs::write(&path, text.as_bytes())?;
    say!("(written to {}, for the commit message: `git commit -e -F {0}`)", path.display());
    Ok(())
}

/// A run read back, after removing what killed processes left in its folder (a sequence's
/// spool of a killed run, temporaries of a killed report).
fn load_run_tidied(path: &Path) -> Result<(RunRecord, PathBuf), String> {
    let (record, dir) = aabench::record::load_run(path)?;
    plan::remove_stale_temporaries(&dir, plan::RUN_DEPTH);
    Ok((record, dir))
}

fn compare(args: &CompareArgs) -> u8 {
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
        None => aabench::record::run_folder(&args.runs[0]),
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

/// `report --markdown`: one run's results on stdout, figures into `figures`.
fn markdown_report(runs: &[PathBuf], figures: Option<&Path>) -> u8 {
    let [run] = runs else {
        return fail("--markdown takes one run: its tables name it, and documentation quotes one run");
    };
    let (record, dir) = match aabench::record::load_run(run) {
        Ok(run) => run,
        Err(message) => return fail(message),
    };
    if let Some(folder) = figures {
        match aabench::report::markdown::figures(&dir, &record, folder) {
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
    say!("{}", aabench::report::markdown::document(&dir, &record).trim_end());
    exit::OK
}

fn report(runs: &[PathBuf], history: Option<&Path>, verdict: Option<&Path>) -> u8 {
    if verdict.is_some() && runs.len() > 1 {
        return fail("--verdict belongs to one run; give one run, or let each use its own verdict.json");
    }
    let history = match history.map(aabench::report::load_history).transpose() {
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
        match aabench::report::write(&dir, &record, verdict.as_ref(), &history) {
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
    let verdict: compare::Verdict = aabench::json::read_versioned(&file, compare::VERDICT_SCHEMA)?;
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

fn merge_verdicts(paths: &[PathBuf], out_dir: &Path) -> u8 {
    let read = |path: &PathBuf| {
        let file = if path.is_dir() { path.join("verdict.json") } else { path.clone() };
        aabench::json::read_versioned::<compare::Verdict>(&file, compare::VERDICT_SCHEMA).map(|v| (v, file))
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

fn merge(runs: &[PathBuf], out: &Path) -> u8 {
    // A killed merge's staging folder sits beside `out`.
    let beside = out.parent().filter(|p| !p.as_os_str().is_empty()).unwrap_or(Path::new("."));
    plan::remove_stale_temporaries(beside, 0);
    let shards: Result<Vec<_>, String> = runs.iter().map(|run| load_run_tidied(run)).collect();
    match shards.and_then(|shards| aabench::merge::merge(&shards, out)) {
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

fn print_graph(
    path: &Path,
    mode: &str,
    tier: Tier,
    extra_samples: ExtraSamples,
    dot: bool,
) -> anyhow::Result<()> {
    let mode: Mode = mode.parse().map_err(|e| anyhow::anyhow!("--mode: {e}"))?;
    let manifest = Manifest::load(path)?;
    let loaded = scenes::load(&manifest)?;
    let settings = run::render_settings(&manifest, tier, extra_samples);
    let needs = aabench_renderer::frame::SceneNeeds::of(&loaded.scene, &loaded.lighting);
    // The adaptive list's layout follows the device's limits.
    let limits = aabench_renderer::Gpu::new()?.device.limits();
    let graph = aabench_renderer::frame::describe(&needs, mode, &settings, &limits, dot)?;
    if !dot {
        let [width, height] = [settings.width, settings.height];
        say!("{} {mode} ({} tier, {width}×{height}; {needs})\n", manifest.name, tier.name());
    }
    out(format_args!("{graph}"));
    Ok(())
}

fn info() -> u8 {
    match aabench_renderer::Gpu::new() {
        Ok(gpu) => {
            let p = &gpu.platform;
            say!("adapter      {} ({}, {})", p.adapter, p.backend, p.device_type);
            say!("driver       {} {}", p.driver, p.driver_info);
            say!("cpu          {} ({} cores)", p.cpu_model, p.cpu_cores);
            say!(
                "threads      LP_NUM_THREADS={}",
                p.lp_num_threads.as_deref().unwrap_or("(unset: one per core)")
            );
            say!("build        {}", p.build_profile);
            say!("platform key {}", p.key());
            exit::OK
        }
        Err(error) => fail(error),
    }
}

fn list_modes() {
    for (name, modes) in Mode::groups() {
        say!("{name}:");
        for mode in modes {
            say!("  {mode}");
        }
    }
    say!("also: reference-1x1 (equals deferred-1x1; a self-check)");
    say!(
        "also: adaptive-MxM with any of these words, in this order: geometry or shading (one metric), \
         area, cells or coverage (the reconstruction), stable (the counts; not with coverage); \
         e.g. adaptive-2x2-shading-area-stable"
    );
}

/// Mesa's device-select Vulkan layer prints "error: XDG_RUNTIME_DIR is invalid" on machines
/// without a session, which reads like a failure of aabench. Disabling the layer (it only
/// orders GPUs; aabench picks its adapter itself) silences it, unless the user set it.
#[allow(unsafe_code)]
fn quiet_mesa_device_select() {
    if std::env::var_os("NODEVICE_SELECT").is_none() {
        // SAFETY: called first thing in main, before any other thread exists, so nothing can
        // read the environment concurrently.
        unsafe { std::env::set_var("NODEVICE_SELECT", "1") };
    }
}
