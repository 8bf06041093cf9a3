//! The timed part of a scene: warm-up and timed rounds interleaved across modes, then the
//! stills of the jittered modes. Timed frames run alone: nothing else is scheduled while one is
//! on the device, and images are read back between frames, never during one.

use aabench_renderer::{FrameImages, FrameTiming, RenderError};

use super::context::{ModeRun, SceneRun};
use crate::measure::pixels::FrameChecks;
use crate::record::fingerprint;
use crate::run::worker::WorkerError;

/// What one rendered frame gave: its timing, its fingerprint (timed frames), the checks of its
/// HDR values and sample counts, and its images (the first timed frame).
struct Frame {
    timing: FrameTiming,
    hash: Option<String>,
    checks: FrameChecks,
    images: Option<FrameImages>,
}

impl SceneRun<'_> {
    /// Warm-up rounds (lavapipe compiles at the first draw), then timed rounds. Each round renders
    /// every mode still taking rounds once: A B C … A B C …, so drift over time hits every mode
    /// alike; after each, a mode whose rounds are enough by the plan's rule stops
    /// ([`crate::plan::repetitions::Repetitions::stop`]). Images are read back after the first timed frame
    /// (every later frame is checked to give the same display image), so an interrupted run
    /// still has them. A worker that stops (a timeout, a panic) ends the rounds of every mode.
    pub(super) async fn timed_rounds(&mut self, runs: &mut [ModeRun]) {
        let plan = self.plan;
        let most = plan.repetitions.most();
        for round in 0..plan.warmup + most {
            let timed = round >= plan.warmup;
            let first_timed = round == plan.warmup;
            for (index, mode) in plan.modes.iter().enumerate() {
                if self.cancelled() {
                    return;
                }
                if runs[index].error.is_some() || runs[index].stopped.is_some() {
                    continue;
                }
                let label = if timed {
                    format!("rep {}/{most}", round - plan.warmup + 1)
                } else {
                    format!("warm-up {}/{}", round + 1, plan.warmup)
                };
                self.status(&format!("{mode} {label}"));
                // A jittered mode's frames differ as its history fills: its image is its still's. A
                // `-stable` mode's frames at one camera are its first frame's, so they are hashed.
                let images = first_timed && !mode.is_jittered();
                let hashed = timed && !mode.is_jittered();
                let result = self.render_frame(index, mode.m, hashed, images).await;
                let run = &mut runs[index];
                match result {
                    Ok(Ok(frame)) => {
                        run.checks.add(frame.checks);
                        if timed {
                            run.timings.push(frame.timing);
                            run.hashes.extend(frame.hash);
                        }
                        if frame.images.is_some() {
                            run.images = frame.images;
                        }
                    }
                    Ok(Err(error)) => run.error = Some(error.to_string()),
                    Err(error) => {
                        run.error = Some(format!("{mode}: {error}"));
                        for other in runs.iter_mut().filter(|r| r.error.is_none()) {
                            other.error = Some(format!("not finished: {error}"));
                        }
                        return;
                    }
                }
            }
            if timed {
                self.stop_modes(runs);
            }
        }
    }

    /// After a timed round, stops every mode whose rounds are enough by the plan's rule, which
    /// weighs its frames and the scene's timed seconds so far.
    fn stop_modes(&self, runs: &mut [ModeRun]) {
        let frames_ms =
            |run: &ModeRun| -> Vec<f64> { run.timings.iter().map(|t| t.seconds() * 1e3).collect() };
        let spent_s: f64 = runs.iter().flat_map(|run| &run.timings).map(FrameTiming::seconds).sum();
        for run in runs.iter_mut().filter(|run| run.error.is_none() && run.stopped.is_none()) {
            run.stopped = self.plan.repetitions.stop(&frames_ms(run), spent_s);
        }
    }

    /// The stills of jittered modes (TAA), after the timed rounds: each rendered twice from a reset
    /// through its warm-up frames ([`aabench_renderer::taa::WARMUP_FRAMES`]), read back and
    /// fingerprinted like a timed frame, so that both must agree.
    pub(super) async fn temporal_stills(&mut self, runs: &mut [ModeRun]) {
        let plan = self.plan;
        for (index, mode) in plan.modes.iter().enumerate().filter(|(_, mode)| mode.is_jittered()) {
            for attempt in 0..2 {
                if self.cancelled() || self.worker.is_stuck() {
                    return;
                }
                if runs[index].error.is_some() {
                    break;
                }
                self.status(&format!("{mode} still {}/2", attempt + 1));
                let m = mode.m;
                let timeout = plan.frame_timeout.saturating_mul(aabench_renderer::taa::WARMUP_FRAMES);
                let still = self
                    .worker
                    .call(timeout, move |state| {
                        let prepared = state.modes[index].as_ref().expect("prepared mode");
                        let timing = prepared.render_still()?;
                        read_frame(prepared, m, timing)
                    })
                    .await;
                let run = &mut runs[index];
                match still {
                    Ok(Ok(frame)) => {
                        run.checks.add(frame.checks);
                        run.hashes.extend(frame.hash);
                        run.images = run.images.take().or(frame.images);
                    }
                    Ok(Err(error)) => run.error = Some(error.to_string()),
                    Err(error) => run.error = Some(format!("{mode}: {error}")),
                }
            }
        }
    }

    /// Renders mode `index` once and reads back what the round needs, between frames, never
    /// during one. Every frame is checked; `hashed` frames' display images and sample counts are
    /// fingerprinted (every timed frame of a mode without history), and all must agree.
    async fn render_frame(
        &mut self,
        index: usize,
        m: u32,
        hashed: bool,
        with_images: bool,
    ) -> Result<Result<Frame, RenderError>, WorkerError> {
        self.worker
            .call(self.plan.frame_timeout, move |state| {
                let prepared = state.modes[index].as_ref().expect("prepared mode");
                let timing = prepared.render()?;
                if with_images {
                    return read_frame(prepared, m, timing);
                }
                let counts = prepared.read_sample_counts()?;
                let checks = FrameChecks::of(prepared.read_hdr()?.as_flattened(), counts.as_deref(), m);
                let hash = if hashed {
                    Some(fingerprint(&prepared.read_display()?, counts.as_deref()))
                } else {
                    None
                };
                Ok(Frame { timing, hash, checks, images: None })
            })
            .await
    }
}

/// The last frame's images, their fingerprint and checks.
fn read_frame(
    prepared: &aabench_renderer::PreparedMode,
    m: u32,
    timing: FrameTiming,
) -> Result<Frame, RenderError> {
    let images = prepared.read_images()?;
    let counts = images.sample_counts.as_deref();
    let hash = Some(fingerprint(&images.display, counts));
    let checks = FrameChecks::of(&images.hdr, counts, m);
    Ok(Frame { timing, hash, checks, images: Some(images) })
}
