//! The GPU worker: one thread that owns the device and the current scene's renderer, driven by
//! jobs from the async side. Frames block that thread for seconds; keeping them off tokio's
//! threads lets the runner put a timeout on every frame and stay responsive to Ctrl-C.

use std::panic::AssertUnwindSafe;
use std::sync::Arc;
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
    /// The current scene's geometry probe, while a sequence follows the truth along it.
    pub geometry: Option<PreparedMode>,
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
    /// None once dropped: closing the channel ends the thread's loop.
    jobs: Option<std::sync::mpsc::Sender<Job>>,
    thread: Option<std::thread::JoinHandle<()>>,
    pub platform: PlatformInfo,
    /// Set after a timeout or a panic: the thread may still be busy, or its state broken.
    stuck: bool,
    /// Set after a timeout: the thread may still be running the frame.
    busy: bool,
}

/// The thread releases the device before the process exits, so the driver is not torn down by
/// `exit` and the worker at once (a run whose worker was still alive at exit crashed once in
/// about seventy, SIGSEGV after its record was written). A thread still running a timed-out
/// frame is not waited for: it may never finish.
impl Drop for Worker {
    fn drop(&mut self) {
        drop(self.jobs.take());
        if let Some(thread) = self.thread.take().filter(|_| !self.busy) {
            let _ = thread.join();
        }
    }
}

impl Worker {
    /// Starts the thread and opens the device on it.
    pub async fn start() -> Result<Worker, RenderError> {
        let (jobs, queue) = std::sync::mpsc::channel::<Job>();
        let (ready, opened) = oneshot::channel();
        let thread = std::thread::Builder::new()
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
                let mut state = State { gpu, renderer: None, modes: Vec::new(), geometry: None };
                while let Ok(job) = queue.recv() {
                    job(&mut state);
                }
            })
            .map_err(|e| RenderError::Device(format!("cannot start the GPU thread: {e}")))?;
        let platform = opened
            .await
            .map_err(|_| RenderError::Device("the GPU thread stopped while opening the device".into()))??;
        Ok(Worker { jobs: Some(jobs), thread: Some(thread), platform, stuck: false, busy: false })
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
        // A panic is caught here and sent as the reply, so the caller always learns why.
        let job: Job = Box::new(move |state| {
            let _ =
                reply.send(std::panic::catch_unwind(AssertUnwindSafe(|| job(state))).map_err(panic_message));
        });
        self.jobs.as_ref().ok_or(WorkerError::Gone)?.send(job).map_err(|_| WorkerError::Gone)?;
        match tokio::time::timeout(timeout, result).await {
            Ok(Ok(Ok(value))) => Ok(value),
            Ok(Ok(Err(message))) => {
                self.stuck = true;
                Err(WorkerError::Panicked(message))
            }
            Ok(Err(_)) => {
                self.stuck = true;
                Err(WorkerError::Gone)
            }
            Err(_) => {
                self.stuck = true;
                self.busy = true;
                Err(WorkerError::Timeout(timeout))
            }
        }
    }
}

fn panic_message(payload: Box<dyn std::any::Any + Send>) -> String {
    payload
        .downcast_ref::<&str>()
        .map(|s| s.to_string())
        .or_else(|| payload.downcast_ref::<String>().cloned())
        .unwrap_or_else(|| "(no message)".into())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[tokio::test]
    async fn a_panicking_job_reports_its_message_and_retires_the_worker() {
        let mut worker = Worker::start().await.expect("a Vulkan adapter (lavapipe)");
        assert_eq!(worker.call(Duration::from_secs(60), |_| 7).await, Ok(7));
        let error = worker.call(Duration::from_secs(60), |_| -> u32 { panic!("boom") }).await;
        assert_eq!(error, Err(WorkerError::Panicked("boom".into())));
        assert!(worker.is_stuck());
        assert_eq!(worker.call(Duration::from_secs(60), |_| 7).await, Err(WorkerError::Gone));
    }

    #[tokio::test]
    async fn a_job_past_its_timeout_retires_the_worker() {
        let mut worker = Worker::start().await.expect("a Vulkan adapter (lavapipe)");
        let slow = |_: &mut State| std::thread::sleep(Duration::from_millis(500));
        let timeout = Duration::from_millis(50);
        assert_eq!(worker.call(timeout, slow).await, Err(WorkerError::Timeout(timeout)));
        assert!(worker.is_stuck());
    }
}
