//! The GPU worker: one thread that owns the device and the current scene's renderer, driven by
//! jobs from the async side. Frames block that thread for seconds; keeping them off tokio's
//! threads lets the runner put a timeout on every frame and stay responsive to Ctrl-C.

use std::panic::AssertUnwindSafe;
use std::sync::{Arc, Mutex};
use std::time::Duration;

use aabench_renderer::{Gpu, PlatformInfo, PreparedMode, RenderError, SceneRenderer};
use tokio::sync::oneshot;

/// What the worker thread holds between jobs.
#[derive(Debug)]
pub struct State {
    pub gpu: Arc<Gpu>,
    pub renderer: Option<SceneRenderer>,
    /// The current scene's modes, in the plan's order; `None` where preparing failed.
    pub modes: Vec<Option<PreparedMode>>,
}

type Job = Box<dyn FnOnce(&mut State) + Send>;

#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum WorkerError {
    #[error("timed out after {0:?}; the frame may still be running, so the run stops here")]
    Timeout(Duration),
    #[error("the GPU worker panicked: {0}")]
    Panicked(String),
    #[error("the GPU worker is no longer usable after an earlier timeout or panic")]
    Gone,
}

#[derive(Debug)]
pub struct Worker {
    jobs: std::sync::mpsc::Sender<Job>,
    pub platform: PlatformInfo,
    /// Set after a timeout or a panic: the thread may still be busy, or its state broken.
    stuck: bool,
    /// The message of the last job that panicked.
    panic: Arc<Mutex<Option<String>>>,
}

impl Worker {
    /// Starts the thread and opens the device on it.
    pub async fn start() -> Result<Worker, RenderError> {
        let (jobs, queue) = std::sync::mpsc::channel::<Job>();
        let (ready, opened) = oneshot::channel();
        let panic = Arc::new(Mutex::new(None));
        let panic_sink = Arc::clone(&panic);
        std::thread::Builder::new()
            .name("aabench-gpu".into())
            .spawn(move || {
                let gpu = match Gpu::new() {
                    Ok(gpu) => Arc::new(gpu),
                    Err(error) => {
                        let _ = ready.send(Err(error));
                        return;
                    }
                };
                let _ = ready.send(Ok(gpu.platform.clone()));
                let mut state = State { gpu, renderer: None, modes: Vec::new() };
                while let Ok(job) = queue.recv() {
                    // A panicking job drops its reply; the caller then reads the message here.
                    if let Err(payload) = std::panic::catch_unwind(AssertUnwindSafe(|| job(&mut state))) {
                        let message = payload
                            .downcast_ref::<&str>()
                            .map(|s| s.to_string())
                            .or_else(|| payload.downcast_ref::<String>().cloned())
                            .unwrap_or_else(|| "(no message)".into());
                        *panic_sink.lock().expect("panic slot") = Some(message);
                    }
                }
            })
            .map_err(|e| RenderError::Device(format!("cannot start the GPU thread: {e}")))?;
        let platform = opened
            .await
            .map_err(|_| RenderError::Device("the GPU thread stopped while opening the device".into()))??;
        Ok(Worker { jobs, platform, stuck: false, panic })
    }

    /// True once a job timed out or panicked: timings taken now would not be trustworthy.
    pub fn is_stuck(&self) -> bool {
        self.stuck
    }

    /// Runs `job` on the worker thread, waiting at most `timeout` for it.
    pub async fn call<T: Send + 'static>(
        &mut self,
        timeout: Duration,
        job: impl FnOnce(&mut State) -> T + Send + 'static,
    ) -> Result<T, WorkerError> {
        if self.stuck {
            return Err(WorkerError::Gone);
        }
        let (reply, result) = oneshot::channel();
        let job: Job = Box::new(move |state| {
            let _ = reply.send(job(state));
        });
        self.jobs.send(job).map_err(|_| WorkerError::Gone)?;
        match tokio::time::timeout(timeout, result).await {
            Ok(Ok(value)) => Ok(value),
            Ok(Err(_)) => {
                self.stuck = true;
                let message = self.panic.lock().expect("panic slot").take();
                Err(message.map_or(WorkerError::Gone, WorkerError::Panicked))
            }
            Err(_) => {
                self.stuck = true;
                Err(WorkerError::Timeout(timeout))
            }
        }
    }
}
