//! The `aabench` command line: its arguments (clap), the dispatch to one file per command, and
//! the output rules they share. `main.rs` calls [`main`].
//!
//! Commands, in the order a user meets them: `run.rs` (`aabench run`), `inspect.rs` (the
//! scenes, the modes, the pass graph and the machine: `gen-scenes`, `modes`, `graph`, `info`),
//! `compare.rs` (`compare`, `merge-verdicts`), `bless.rs` (`bless`, `upgrade`), `report.rs`
//! (`report`) and `merge.rs` (`merge`).

use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::sync::atomic::{AtomicBool, Ordering};

use clap::{Parser, Subcommand};

use crate::exit;
use crate::plan::{self, ExtraSamplesArg, RunArgs, Tier};
use crate::record::RunRecord;

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
    ($($arg:tt)*) => { $crate::cli::out(format_args!("{}\n", format_args!($($arg)*))) };
}

/// A line on stderr (see [`note`]).
macro_rules! tell {
    ($($arg:tt)*) => { $crate::cli::note(format_args!("{}\n", format_args!($($arg)*))) };
}

mod bless;
mod compare;
mod inspect;
mod merge;
mod report;
mod run;

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
    Compare(compare::CompareArgs),
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

/// Parses the command line, runs the command and returns its exit code.
pub fn main() -> ExitCode {
    quiet_mesa_device_select();
    let cli = Cli::parse();
    let code = match cli.command {
        Command::Run(args) => run::run_command(args),
        Command::GenScenes { paths, force } => inspect::gen_scenes(&paths, force),
        Command::Bless { runs, baseline, force, why } => {
            bless::bless(&runs, &baseline, crate::baseline::Consent { force, why: why.as_deref() })
        }
        Command::Upgrade { baseline } => bless::upgrade(&baseline),
        Command::Compare(args) => compare::compare(&args),
        Command::Report { runs, markdown: true, figures, .. } => {
            report::markdown_report(&runs, figures.as_deref())
        }
        Command::Report { runs, history, verdict, .. } => {
            report::report(&runs, history.as_deref(), verdict.as_deref())
        }
        Command::Merge { runs, out } => merge::merge(&runs, &out),
        Command::MergeVerdicts { verdicts, out } => compare::merge_verdicts(&verdicts, &out),
        Command::Graph { manifest, mode, tier, extra_samples, dot } => {
            match inspect::print_graph(&manifest, &mode, tier, extra_samples.into(), dot) {
                Ok(()) => exit::OK,
                Err(error) => fail(format!("{error:#}")),
            }
        }
        Command::Info => inspect::info(),
        Command::Modes { tier, timed_by_gate } => inspect::modes(tier, timed_by_gate),
    };
    // Output the reader never got is a failure, whatever the command decided.
    if STDOUT_FAILED.load(Ordering::SeqCst) { ExitCode::from(exit::ERROR) } else { ExitCode::from(code) }
}

fn fail(message: impl std::fmt::Display) -> u8 {
    tell!("aabench: {message}");
    exit::ERROR
}

/// A run read back, after removing what killed processes left in its folder (a sequence's
/// spool of a killed run, temporaries of a killed report).
fn load_run_tidied(path: &Path) -> Result<(RunRecord, PathBuf), String> {
    let (record, dir) = crate::record::load_run(path)?;
    plan::remove_stale_temporaries(&dir, plan::RUN_DEPTH);
    Ok((record, dir))
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
