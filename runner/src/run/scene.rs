//! One scene in its phases: load the file, upload it (and meter its exposure), render the
//! ground truth, prepare every mode, run the timed rounds (`rounds.rs`), render the sequence
//! (`sequence.rs`), free the device, then write images and metrics (`results.rs`). A phase that
//! fails ends the scene with its error; the run goes on.

use std::sync::Arc;
use std::time::Instant;

use aabench_renderer::{DisplayImage, color};

use super::context::{ModeRun, SceneRun};
use super::results::finish_modes;
use super::{empty_scene, render_settings, sequence};
use crate::files::images;
use crate::plan::inputs::SceneInputs;
use crate::record::TruthRecord;
use crate::record::{ExposureRecord, GraphRecord, SceneRecord, Status, fingerprint};
use crate::run::scenes;
use crate::run::truth::{self, TRUTH_ID, TRUTH_M};

impl<'a> SceneRun<'a> {
    /// Why JOD goes unmeasured where quality is measured: a frame narrower or lower than
    /// ColorVideoVDP scores.
    fn unscored(&self) -> Option<String> {
        let [width, height] = self.resolution;
        let side = aabench_cvvdp::MIN_SIDE as u32;
        (self.jod.is_some() && (width < side || height < side)).then(|| {
            format!(
                "resolution {width}×{height}: JOD is not measured, since ColorVideoVDP needs at least \
                 {side}×{side} pixels; PSNR, FLIP and SSIM judge its modes"
            )
        })
    }

    /// The scene, phase after phase, into its record.
    pub async fn run(mut self) -> SceneRecord {
        let mut record = empty_scene(self.manifest);
        record.resolution = Some(self.resolution);
        if let Err(error) = std::fs::create_dir_all(&self.dir) {
            return fail(record, format!("{}: {error}", self.dir.display()));
        }
        if self.plan.quality {
            let judged = self.plan.jod_display(self.manifest);
            match judged.and_then(|name| Ok((crate::measure::perceptual::Jod::new(&name)?, name))) {
                Ok((jod, name)) => {
                    record.pixels_per_degree = Some(jod.pixels_per_degree());
                    (self.jod, record.jod_display) = (Some(jod), Some(name));
                }
                Err(error) => return fail(record, error),
            }
        }
        let (loaded, inputs) = match self.load(&mut record).await {
            Ok(loaded) => loaded,
            Err(error) => return fail(record, error),
        };
        if let Some(warning) = self.unscored() {
            self.warn(&warning);
            record.warnings.push(warning);
        }
        let (still_camera, pivot, camera_path) = (loaded.camera, loaded.pivot, loaded.camera_path.clone());
        let timeline = loaded.timeline;
        self.note_scene(&loaded.scene);
        match self.upload(loaded).await {
            Ok((budget, exposure)) => {
                record.memory_limit_bytes = budget;
                record.exposure = Some(exposure);
            }
            Err(error) => return fail(record, error),
        }
        // The truth renders before any mode is prepared, so its peak memory is its own. A run
        // that times its modes alone needs none.
        let truth_image = if self.plan.quality {
            let (truth_record, truth_image) = self.ground_truth(&inputs).await;
            record.truth = Some(truth_record);
            truth_image
        } else {
            None
        };
        if self.cancelled() {
            self.free_scene().await;
            record.status = Status::Interrupted;
            record.error = Some("interrupted while its ground truth rendered: no mode ran".into());
            return record;
        }
        let mut runs = match self.prepare_modes().await {
            Ok((runs, target_bytes, texture_bytes)) => {
                record.target_bytes = Some(target_bytes);
                record.texture_bytes = Some(texture_bytes);
                runs
            }
            Err(error) => return fail(record, error),
        };
        self.timed_rounds(&mut runs).await;
        if self.plan.quality {
            self.temporal_stills(&mut runs).await;
        }
        let view = scenes::View {
            camera: &still_camera,
            camera_path: camera_path.as_ref(),
            timeline: timeline.as_ref(),
        };
        self.sequences(&mut record, &mut runs, (view, pivot), truth_image.as_ref()).await;
        // Free the scene's device memory before the CPU work below.
        self.free_scene().await;
        self.status("writing images and metrics");
        let interrupted = self.cancelled();
        let started = Instant::now();
        let (modes, perceptual_s, cut_short) = finish_modes(&self, runs, truth_image, interrupted).await;
        record.modes = modes;
        record.images_s = Some(started.elapsed().as_secs_f64());
        record.perceptual_s = Some(perceptual_s);
        let cut = "interrupted while its metrics and images were computed";
        record.error = record.error.take().or_else(|| cut_short.then(|| cut.into()));
        conclude(record, self.worker.is_stuck(), interrupted || cut_short)
    }

    /// The scene's sequences along its camera path, where it has one and the plan renders
    /// sequences: one per speed of the tier, from the still camera whose path turns about a
    /// target `pivot` along its view. Each mode's outcome joins its run (a sequence frame is a
    /// frame of the mode like any other: NaN in it fails the mode).
    async fn sequences(
        &mut self,
        record: &mut SceneRecord,
        runs: &mut [ModeRun],
        (view, pivot): (scenes::View<'_>, f64),
        still_truth: Option<&DisplayImage>,
    ) {
        let still_camera = view.camera;
        let Some(motion) = self.manifest.motion.as_ref().filter(|_| self.plan.sequences) else { return };
        let paces = self.plan.tier.paces(self.manifest, still_camera.fov_y);
        let frames = self.plan.tier.sequence_frames(motion);
        let window_s = f64::from(frames) * motion.time_step_s;
        if window_s < crate::manifest::motion::MIN_WINDOW_S {
            let warning = format!(
                "motion.frames.{}: the measured window of {frames} frames lasts {} ms, less than the \
                 {} ms ColorVideoVDP's temporal filters span: its JOD weighs the window's first frames most",
                self.plan.tier.name(),
                crate::manifest::motion::short(window_s * 1e3),
                crate::manifest::motion::MIN_WINDOW_S * 1e3
            );
            self.warn(&warning);
            record.warnings.push(warning);
        }
        let still_key = record.truth.as_ref().map(|truth| truth.key.clone()).unwrap_or_default();
        let animation = self.animation.clone();
        for (index, pace) in paces.iter().enumerate() {
            if self.cancelled() || self.worker.is_stuck() {
                return;
            }
            // Checked when the scene loaded.
            let path = match scenes::path_frames(motion, view, pivot, (frames, pace.rate)) {
                Ok(path) => path,
                Err((field, message)) => return self.warn(&format!("no sequence: {field}: {message}")),
            };
            let modes = sequence::PathMode::of(&self.plan.modes, runs);
            // The first speed's animations in `path/`, the others' in `path-2/`, `path-3/`, ….
            let folder = if index == 0 { "path".into() } else { format!("path-{}", index + 1) };
            let along = sequence::Along {
                motion,
                pace: *pace,
                timeline: view.timeline.expect("a scene with motion has a timeline"),
                frames: &path,
                folder: &folder,
                number: index + 1,
                still_camera,
                still_truth,
                still_key: &still_key,
                animation: animation.as_deref(),
            };
            let (sequence, outcomes) = sequence::run(self, along, &modes).await;
            for (run, outcome) in runs.iter_mut().zip(outcomes) {
                run.checks.add(outcome.checks);
                run.sequences.push(outcome.sequence);
                if let Some(error) = outcome.error {
                    run.error.get_or_insert(format!("sequence ({}): {error}", sequence.speed()));
                }
            }
            record.sequences.push(sequence);
        }
    }

    /// Reads the manifest's glTF file and hashes the scene's inputs, off the async threads; records
    /// what the file holds.
    async fn load(&self, record: &mut SceneRecord) -> Result<(scenes::LoadedScene, SceneInputs), String> {
        let manifest = self.manifest;
        self.status(&format!("loading {}", manifest.gltf_path().display()));
        let owned = manifest.clone();
        let load = move || -> anyhow::Result<_> { Ok((scenes::load(&owned)?, SceneInputs::of(&owned)?)) };
        let (loaded, inputs) = match tokio::task::spawn_blocking(load).await {
            Ok(Ok(loaded)) => loaded,
            Ok(Err(error)) => return Err(format!("{error:#}")),
            Err(panic) => return Err(format!("loading panicked: {panic}")),
        };
        record.load_s = Some(loaded.seconds);
        record.triangles = Some(loaded.scene.triangle_count());
        record.textures = Some(loaded.scene.textures.len());
        record.inputs = Some(inputs.clone());
        for warning in &loaded.scene.warnings {
            self.warn(warning);
        }
        record.warnings = loaded.scene.warnings.clone();
        Ok((loaded, inputs))
    }

    /// Uploads the scene into a new renderer (dropping the previous scene's), sets the memory
    /// budget its modes are prepared under, and meters the exposure where the manifest gives none.
    /// Returns the budget and the exposure every mode and the truth render at.
    async fn upload(&mut self, loaded: scenes::LoadedScene) -> Result<(Option<u64>, ExposureRecord), String> {
        let (plan, manifest) = (self.plan, self.manifest);
        let settings = render_settings(manifest, plan.tier, plan.extra_samples);
        let white = settings.color.tonemap.map_or(1.0, |tonemap| tonemap.hdr_max);
        self.status("uploading");
        let memory_limit = plan.memory_limit;
        let metered = manifest.tonemap.exposure.is_none();
        // A playing animation's still is its pose at the measured window's start.
        let start = loaded.timeline.and_then(|timeline| timeline.animation_time(0));
        let uploaded = self
            .worker
            .call(plan.frame_timeout, move |state| {
                let scenes::LoadedScene { scene, camera, lighting, .. } = loaded;
                state.modes.clear();
                state.geometry = None;
                state.renderer = None;
                let mut renderer = aabench_renderer::SceneRenderer::new(
                    state.gpu.clone(),
                    &scene,
                    &camera,
                    &lighting,
                    settings,
                )?;
                if let Some(start) = start.filter(|_| renderer.is_moving()) {
                    renderer.pose(start, start)?;
                }
                // After the upload, so that the scene's own memory is no longer available.
                let budget =
                    memory_limit.or_else(|| super::memory::available_memory().map(|bytes| bytes / 10 * 9));
                renderer.set_memory_budget(budget);
                if metered {
                    renderer.meter_exposure(color::EXPOSURE_KEY, color::METERED_EXPOSURE_RANGE)?;
                } else {
                    renderer.check_headroom()?;
                }
                let exposure = ExposureRecord { value: renderer.exposure(), metered };
                state.renderer = Some(renderer);
                Ok::<_, aabench_renderer::RenderError>((budget, exposure))
            })
            .await;
        match uploaded {
            Ok(Ok(uploaded)) => {
                color::background_headroom(manifest.background, f64::from(uploaded.1.value), white)
                    .map_err(|error| format!("{}: background: {error}", manifest.path.display()))?;
                Ok(uploaded)
            }
            // What the device refuses of the file's content (too many textures) names the file.
            Ok(Err(error @ aabench_renderer::RenderError::Limit(_))) => {
                Err(format!("{}: {error}", manifest.gltf_path().display()))
            }
            Ok(Err(error)) => Err(error.to_string()),
            Err(error) => Err(error.to_string()),
        }
    }

    /// The scene's ground truth, from the cache or rendered now (untimed; before any mode is
    /// prepared, so the peak memory measured is the truth's own), and written into the run folder.
    /// Returns the record and the display image, or the record with its error.
    async fn ground_truth(&mut self, inputs: &SceneInputs) -> (TruthRecord, Option<DisplayImage>) {
        let (plan, manifest, resolution) = (self.plan, self.manifest, self.resolution);
        let mut record = TruthRecord {
            id: TRUTH_ID.into(),
            samples_per_pixel: TRUTH_M * TRUTH_M,
            key: String::new(),
            cached: false,
            render_s: None,
            tiles: None,
            peak_rss_bytes: None,
            image: None,
            image_hash: None,
            error: None,
        };
        let fail = |mut record: TruthRecord, error: String| {
            record.error = Some(error);
            (record, None)
        };
        match truth::cache_key(inputs, resolution, &self.worker.platform) {
            Ok(key) => record.key = key,
            Err(error) => return fail(record, format!("{error:#}")),
        }
        let cache =
            truth::cache_file(&plan.truth_cache_dir(manifest), &manifest.name, resolution, &record.key);
        let display = match truth::load_cached(&cache, resolution, manifest.display_bits()) {
            Some(display) => {
                record.cached = true;
                display
            }
            None => {
                self.status(&format!("rendering the ground truth ({TRUTH_ID}, untimed)"));
                let measured = truth::peak_memory::reset();
                let start = Instant::now();
                // A signal stops the truth between tiles, not after the last one.
                let timeout = plan.frame_timeout.saturating_mul(16);
                let (truth, not_cached) = match truth::render_and_store(
                    self.worker,
                    timeout,
                    &cache,
                    resolution,
                    Arc::clone(self.cancel),
                )
                .await
                {
                    Ok(rendered) => rendered,
                    Err(error) => return fail(record, error),
                };
                record.render_s = Some(start.elapsed().as_secs_f64());
                record.tiles = Some(truth.tiles);
                record.peak_rss_bytes = if measured { truth::peak_memory::read() } else { None };
                if let Some(error) = not_cached {
                    self.warn(&format!("ground truth not cached: {error}"));
                }
                truth.images.display
            }
        };
        record.image_hash = Some(fingerprint(&display, None));
        let relative = format!("{}/{TRUTH_ID}.png", manifest.name);
        match images::write_display_png(&plan.run_dir.join(&relative), resolution[0], resolution[1], &display)
        {
            Ok(()) => record.image = Some(relative),
            Err(error) => return fail(record, format!("{error:#}")),
        }
        (record, Some(display))
    }

    /// Prepares every mode of the plan; a mode that cannot be prepared fails alone. Returns one
    /// run per mode (its graph, or its error), the scene's target bytes and texture bytes.
    async fn prepare_modes(&mut self) -> Result<(Vec<ModeRun>, u64, u64), String> {
        let (plan, modes) = (self.plan, self.plan.modes.clone());
        self.status(&format!("compiling {} modes", modes.len()));
        let prepared = self
            .worker
            .call(plan.frame_timeout.saturating_mul(modes.len() as u32), move |state| {
                let renderer = state.renderer.as_mut().expect("an uploaded scene");
                let mut outcomes = Vec::new();
                for mode in modes {
                    match renderer.prepare(mode) {
                        Ok(prepared) => {
                            outcomes.push(Ok(GraphRecord::of(prepared.graph())));
                            state.modes.push(Some(prepared));
                        }
                        Err(error) => {
                            state.modes.push(None);
                            outcomes.push(Err(error.to_string()));
                        }
                    }
                }
                (outcomes, renderer.target_bytes(), renderer.texture_bytes())
            })
            .await;
        let (outcomes, target_bytes, texture_bytes) = prepared.map_err(|error| error.to_string())?;
        let runs = outcomes
            .into_iter()
            .map(|outcome| match outcome {
                Ok(graph) => ModeRun { graph: Some(graph), ..Default::default() },
                Err(error) => ModeRun { error: Some(error), ..Default::default() },
            })
            .collect();
        Ok((runs, target_bytes, texture_bytes))
    }

    /// Drops the scene's prepared modes and renderer, freeing its device memory.
    async fn free_scene(&mut self) {
        let _ = self
            .worker
            .call(self.plan.frame_timeout, |state| {
                state.modes.clear();
                state.geometry = None;
                state.renderer = None;
            })
            .await;
    }
}

/// The scene's status from its modes, its truth and the worker.
fn conclude(mut record: SceneRecord, worker_stuck: bool, interrupted: bool) -> SceneRecord {
    let truth_error = record.truth.as_ref().and_then(|t| t.error.clone());
    if let Some(error) = truth_error {
        record.error = Some(format!("ground truth: {error}"));
    } else if worker_stuck {
        record.error = Some("the GPU worker stopped; see the failed mode".into());
    } else if let Some(stopped) = record.sequences.iter().find(|s| s.error.is_some()) {
        // Means over the frames a stopped sequence reached are no measurement of its path.
        let error = stopped.error.as_deref().unwrap_or_default();
        record.error = Some(if stopped.frames_done < stopped.frames {
            format!(
                "sequence ({}): stopped after {} of {} frames: {error}",
                stopped.speed(),
                stopped.frames_done,
                stopped.frames
            )
        } else {
            format!("sequence ({}): {error}", stopped.speed())
        });
    }
    record.status = if record.error.is_none() && record.modes.iter().all(|m| m.status == Status::Ok) {
        Status::Ok
    } else if interrupted {
        Status::Interrupted
    } else {
        Status::Failed
    };
    record
}

fn fail(mut record: SceneRecord, error: String) -> SceneRecord {
    record.status = Status::Failed;
    record.error = Some(error);
    record
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A scene that finished its one sequence of 8 frames.
    fn with_a_sequence() -> SceneRecord {
        let sequence: crate::record::SequenceRecord = serde_json::from_value(serde_json::json!({
            "path": "orbit", "frames": 8, "frames_done": 8, "time_step_s": 0.1, "truth_rendered": 8,
            "truth_render_s": 1.0, "truth_change": null, "seconds": 2.0, "error": null
        }))
        .unwrap();
        let manifest = std::path::Path::new("scenes/wire.json");
        SceneRecord {
            name: "wire".into(),
            sequences: vec![sequence],
            ..super::super::empty_scene_at(manifest)
        }
    }

    #[test]
    fn a_sequence_that_stopped_leaves_its_scene_not_ok() {
        let whole = with_a_sequence();
        assert_eq!(conclude(whole.clone(), false, false).status, Status::Ok);
        let mut cut = whole;
        cut.sequences[0].frames_done = 3;
        cut.sequences[0].error = Some("interrupted after 3 of 8 frames".into());
        let failed = conclude(cut.clone(), false, false);
        assert_eq!(failed.status, Status::Failed);
        assert!(failed.error.unwrap().contains("stopped after 3 of 8 frames"));
        assert_eq!(conclude(cut, false, true).status, Status::Interrupted);
    }
}
