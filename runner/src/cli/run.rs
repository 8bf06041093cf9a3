//! `aabench run`: the plan, the async runtime, and the signals that stop a run keeping what it
//! measured.

use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};

use super::fail;
use crate::exit;
use crate::plan::RunArgs;
use crate::record::Status;
use crate::run::{self, progress::Progress};

pub(super) fn run_command(args: RunArgs) -> u8 {
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
                crate::report::closing(&outcome.record, &outcome.run_json).iter().for_each(|l| progress.line(l));
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
