//! What a sequence measures of each mode, frame by frame, against the truth's frames: the
//! error (MSE per frame; FLIP per frame once the path is rendered, from the spool), the error
//! along the truth's motion (flicker) and what lag costs (`temporal.rs`), the uncompensated
//! change of error and of the image, sample counts and frame times in motion; and the truth's
//! own change. `sequence.rs` renders the frames and hands each here.
//!
//! **Flicker** is measured along the truth's own motion (`temporal.rs`): each pixel followed
//! back to where its surface point lay in the frame before, by the scene's geometry probe
//! rendered at every frame, and the mode's error compared there. An error that travels with the
//! surface does not count; one that crawls, shimmers or stays put while the scene moves does.
//! Beside it, what lag costs: the error on the pixels the frame before did not see
//! (disoccluded), at silhouettes that moved, and elsewhere.
//!
//! **Temporal instability** is kept for the gate: the mean over pixels, channels and
//! consecutive frame pairs of ((A_f − A_{f−1}) − (T_f − T_{f−1}))², with A and T the mode's and
//! the truth's display images (code values scaled to [0, 1]), without motion compensation. It
//! rewards lag and blur: an image that never changes scores the truth's own change.
//! `change_ratio` sets the mode's own mean squared frame-to-frame change against the truth's.

use std::path::Path;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};

use aabench_renderer::{DisplayImage, Mode};

use super::path_metrics::{
    Accumulate, CountChanges, Flicker, FlipAlong, FrameError, Instability, JodAlong, LagError, ModeFrame,
    OwnChange, PathPsnr, Shading, Step,
};
use crate::measure::perceptual::VideoJod;
use crate::measure::pixels::FrameChecks;
use crate::measure::temporal::{self, Flow, Geometry, per_value, squared_difference};
use crate::record::{ModeSequence, SequenceRecord, fingerprint};
use crate::run::spool::Spool;

/// What a mode's sequence gave: its record (absent where it failed or was cut short), the checks
/// of its frames, and its error.
#[derive(Debug)]
pub(super) struct ModeOutcome {
    pub sequence: Option<ModeSequence>,
    pub checks: FrameChecks,
    pub error: Option<String>,
}

impl ModeOutcome {
    /// The outcome of a mode that takes the frames of `twin`, whose outcome this is: its
    /// sequence without a time of its own.
    pub(super) fn of_twin(&self, twin: Mode) -> ModeOutcome {
        let sequence = self.sequence.clone().map(|sequence| ModeSequence {
            frame_ms: None,
            frames_of: Some(twin.to_string()),
            ..sequence
        });
        let error = self.error.as_ref().map(|error| format!("{twin}, whose frames it takes: {error}"));
        ModeOutcome { sequence, checks: self.checks, error }
    }
}

/// The truth's frame and the frame before, and how the pixels of one follow back into the
/// other.
pub(super) struct TruthPair<'a> {
    pub now: &'a DisplayImage,
    pub then: Option<&'a DisplayImage>,
    pub flow: Option<&'a Flow>,
}

/// What the sequence keeps of a mode between frames: its frame before, each path metric's
/// accumulator (`path_metrics.rs`), and the frames' hashes and times.
#[derive(Default)]
pub(super) struct ModeState {
    previous: Option<ModeFrame>,
    frame_error: FrameError,
    flicker: Flicker,
    lag: LagError,
    instability: Instability,
    own_change: OwnChange,
    count_changes: CountChanges,
    shading: Shading,
    /// FLIP and ColorVideoVDP along the path: filled in once the path is rendered.
    pub flip: FlipAlong,
    pub jod: JodAlong,
    /// The share of its error that is coarse where the modes flicker most: filled in with the
    /// flicker region.
    pub coarse_share: Option<f64>,
    hashes: Vec<String>,
    frame_seconds: Vec<f64>,
    checks: FrameChecks,
    pub error: Option<String>,
}

/// The truth's side of a sequence: its frame and geometry before, and its own changes so far.
#[derive(Default)]
pub(super) struct TruthTrack {
    pub previous: Option<(DisplayImage, Geometry)>,
    /// Σ of the squared frame-to-frame change, in squared code steps, over the pairs so far.
    change: u64,
    pairs: usize,
    /// Σ of the squared change along the motion, and its count of values.
    along_motion: (f64, u64),
    /// How fast the truth's content moved over the pairs so far.
    speeds: temporal::Speeds,
}

impl TruthTrack {
    /// Takes the next frame's truth and geometry, followed back into the frame before by
    /// `flow`, and records the truth's own changes and its content's speed so far.
    pub fn advance(
        &mut self,
        truth: DisplayImage,
        geometry: Geometry,
        flow: Option<&Flow>,
        record: &mut SequenceRecord,
    ) {
        if let Some((before, _)) = &self.previous {
            self.speeds.add(&geometry);
            record.measured_speed = self.speeds.measured();
            self.change += squared_difference(&truth, before);
            self.pairs += 1;
            record.truth_change = Some(per_value(self.change, &truth, self.pairs));
            if let Some(flow) = flow {
                let (sum, count) = flow.own_change(&truth, before);
                self.along_motion = (self.along_motion.0 + sum, self.along_motion.1 + count);
                record.blank_flicker = temporal::mean(self.along_motion);
            }
        }
        self.previous = Some((truth, geometry));
    }
}

impl ModeState {
    /// Adds a frame to every path metric: its error against the truth's frame and, from the
    /// frame before, its error along the truth's motion (each pixel's flicker also added to
    /// `flicker`), and the change of its error, of its image and of its sample counts.
    pub fn add(
        &mut self,
        mode: Mode,
        frame: ModeFrame,
        truth: &TruthPair,
        flicker: &mut [f64],
        textured: bool,
    ) {
        self.checks.add(frame.checks);
        self.frame_seconds.push(frame.seconds);
        self.hashes.push(fingerprint(&frame.display, frame.counts.as_deref()));
        let before = self.previous.as_ref().zip(truth.then);
        let followed = before.zip(truth.flow).map(|((before, truth_before), flow)| {
            let pair = [&frame.display, truth.now];
            (flow.error(pair, [&before.display, truth_before], flicker), flow)
        });
        let step = Step {
            mode,
            textured,
            now: &frame,
            truth: truth.now,
            before,
            followed: followed.as_ref().map(|(error, flow)| (error, *flow)),
        };
        let metrics: [&mut dyn Accumulate; 7] = [
            &mut self.frame_error,
            &mut self.flicker,
            &mut self.lag,
            &mut self.instability,
            &mut self.own_change,
            &mut self.count_changes,
            &mut self.shading,
        ];
        for metric in metrics {
            metric.add(&step);
        }
        self.previous = Some(frame);
    }

    /// The mode's outcome over the `frames` frames every mode rendered: no record where it
    /// failed, where fewer than two frames were rendered, or where it rendered a frame more
    /// than the others (the sequence stopped in the middle of a frame).
    pub fn conclude(self, frames: usize, truth_change: Option<f64>) -> ModeOutcome {
        let complete = self.error.is_none() && self.frame_error.frames() == frames && frames > 1;
        let (Some(last), true) = (self.previous, complete) else {
            return ModeOutcome { sequence: None, checks: self.checks, error: self.error };
        };
        let (last, pairs) = (&last.display, frames - 1);
        let PathPsnr { mse, psnr_db, mean_psnr_db } = self.frame_error.conclude();
        let (flip, mean_flip) = self.flip.conclude(frames);
        let worst = self.jod.worst;
        let sequence = ModeSequence {
            mse,
            psnr_db,
            mean_psnr_db,
            flip,
            mean_flip,
            jod: self.jod.jod,
            jod_worst_frame: worst.as_ref().map(|(frame, _)| *frame),
            jod_map: worst.and_then(|(_, map)| map),
            instability: self.instability.conclude(last, pairs),
            change_ratio: self.own_change.conclude(last, pairs, truth_change),
            count_changes: self.count_changes.conclude(),
            shaded_percent: self.shading.conclude(),
            frame_ms: crate::measure::stats::Summary::new(
                self.frame_seconds.iter().map(|s| s * 1e3).collect(),
            ),
            frames_of: None,
            flicker: self.flicker.conclude(),
            ghosting: self.lag.conclude(),
            coarse_share: self.coarse_share,
            hashes: self.hashes,
        };
        ModeOutcome { sequence: Some(sequence), checks: self.checks, error: None }
    }
}

/// Per stream of the spool, each of its first `frames` frames' mean FLIP against the truth's
/// frame (stream 0's); empty for the truth's and for a stream that holds fewer frames (its mode
/// failed on the way). Frames identical to another (a stalled mode's and its twin's) are
/// compared once; the comparisons of a frame run on every core.
pub(super) fn flip_along(
    spool: &Spool,
    frames: usize,
    pixels_per_degree: f64,
    cancel: &AtomicBool,
) -> Result<Vec<Vec<f64>>, String> {
    let size = spool.size();
    let complete: Vec<usize> = (1..spool.streams()).filter(|&s| spool.frames(s) >= frames).collect();
    let mut flips = vec![Vec::with_capacity(frames); spool.streams()];
    let threads = std::thread::available_parallelism().map_or(1, usize::from);
    for frame in 0..frames {
        // A signal stops the comparisons between images, not after the path's last.
        let stopped = || format!("interrupted: FLIP stopped at frame {frame} of {frames}");
        if cancel.load(Ordering::SeqCst) {
            return Err(stopped());
        }
        let truth = spool.frame(0, frame)?;
        let images = complete.iter().map(|&s| spool.frame(s, frame)).collect::<Result<Vec<_>, _>>()?;
        let mut seen = std::collections::HashSet::new();
        let distinct: Vec<&[u8]> =
            images.iter().map(Vec::as_slice).filter(|image| seen.insert(*image)).collect();
        let next = std::sync::atomic::AtomicUsize::new(0);
        let compare = || {
            let mut done = Vec::new();
            loop {
                let i = next.fetch_add(1, Ordering::Relaxed);
                let Some(image) = distinct.get(i).filter(|_| !cancel.load(Ordering::SeqCst)) else {
                    return done;
                };
                done.push((
                    *image,
                    crate::measure::perceptual::flip_rgba8(image, &truth, size, pixels_per_degree).mean(),
                ));
            }
        };
        let values: std::collections::HashMap<&[u8], f64> = std::thread::scope(|scope| {
            let workers: Vec<_> = (0..threads).map(|_| scope.spawn(compare)).collect();
            workers.into_iter().flat_map(|w| w.join().expect("a FLIP thread panicked")).collect()
        });
        if values.len() < distinct.len() {
            return Err(stopped());
        }
        for (&stream, image) in complete.iter().zip(&images) {
            flips[stream].push(values[image.as_slice()]);
        }
    }
    Ok(flips)
}

/// Per stream of the spool, ColorVideoVDP of its warm-up and the first `frames` frames of its
/// window as a video against the truth's (stream 0's) at `fps`, pooled over the window alone,
/// with the distortion map of its worst frame; `None` for the truth's, for a stream that holds
/// fewer frames and for a window of no frame. Streams whose frames equal another's (a stalled
/// mode's and its twin's) are scored once; the streams are scored on every core, each reading
/// its frames as it goes.
pub(super) fn jod_along(
    spool: &Spool,
    frames: usize,
    fps: f64,
    jod: &crate::measure::perceptual::Jod,
    cancel: &AtomicBool,
) -> Result<Vec<Option<Arc<VideoJod>>>, String> {
    use std::hash::{Hash, Hasher};
    let (warmup, seen) = (spool.warmup(), spool.warmup() + frames);
    let truth = (0..seen).map(|f| spool.seen_image(0, f)).collect::<Result<Vec<_>, _>>()?;
    let complete: Vec<usize> =
        (1..spool.streams()).filter(|&s| frames > 0 && seen > 1 && spool.frames(s) >= frames).collect();
    let mut first_of = std::collections::HashMap::new();
    let mut scored_as = Vec::with_capacity(complete.len());
    for &stream in &complete {
        let mut hasher = std::collections::hash_map::DefaultHasher::new();
        for frame in 0..seen {
            spool.seen_image(stream, frame)?.rgba.hash(&mut hasher);
        }
        scored_as.push(*first_of.entry(hasher.finish()).or_insert(stream));
    }
    let distinct: Vec<usize> = first_of.into_values().collect();
    let next = std::sync::atomic::AtomicUsize::new(0);
    let score = || {
        let mut done = Vec::new();
        while let Some(&stream) = distinct.get(next.fetch_add(1, Ordering::Relaxed)) {
            if cancel.load(Ordering::SeqCst) {
                break;
            }
            let clip = (0..seen).map(|f| spool.seen_image(stream, f)).collect::<Result<Vec<_>, _>>();
            let pairs = clip.iter().flatten().zip(&truth);
            let scored = clip.is_ok().then(|| jod.video(pairs, spool.size(), fps, warmup)).flatten();
            done.push((stream, scored.map(Arc::new)));
        }
        done
    };
    let threads = std::thread::available_parallelism().map_or(1, usize::from);
    let scores: std::collections::HashMap<usize, Option<Arc<VideoJod>>> = std::thread::scope(|scope| {
        let workers: Vec<_> = (0..threads).map(|_| scope.spawn(score)).collect();
        workers.into_iter().flat_map(|w| w.join().expect("a JOD thread panicked")).collect()
    });
    if scores.len() < distinct.len() {
        return Err(format!(
            "interrupted: ColorVideoVDP stopped after {} of {} clips",
            scores.len(),
            distinct.len()
        ));
    }
    let mut out = vec![None; spool.streams()];
    for (&stream, first) in complete.iter().zip(scored_as) {
        out[stream] = scores[&first].clone();
    }
    Ok(out)
}

/// Writes each scored stream's distortion map of its worst frame as `<dir>/<stream>.jod.png`
/// (FLIP's colour scale: black where no difference shows, yellow at 10 JOD below the truth or
/// more): per stream its path relative to `run_dir`, or why it could not be written.
pub(super) fn write_jod_maps(
    spool: &Spool,
    jods: &[Option<Arc<VideoJod>>],
    [run_dir, dir]: [&Path; 2],
) -> Vec<Option<Result<String, String>>> {
    jods.iter()
        .enumerate()
        .map(|(stream, jod)| {
            let jod = jod.as_ref()?;
            let path = dir.join(format!("{}.jod.png", spool.name(stream)));
            let written = crate::files::images::write_png(
                &path,
                jod.width,
                jod.height,
                &crate::measure::perceptual::magma_rgba(&jod.map),
            );
            Some(
                // The write's error names the file already.
                written
                    .map_err(|e| format!("{e:#}"))
                    .map(|()| path.strip_prefix(run_dir).unwrap_or(&path).to_string_lossy().into_owned()),
            )
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A 4×4 frame of one grey `value`, as the renderer's display image.
    fn grey(value: u8) -> DisplayImage {
        DisplayImage::from_rgba8(&[value; 64])
    }

    /// Three frames of an adaptive mode against a truth that brightens by 10 code steps a
    /// frame: every path metric's accumulator sees each frame and concludes with its own value.
    #[test]
    fn every_path_metric_accumulates_the_frames_it_is_shown() {
        let mode: Mode = "adaptive-2x2".parse().unwrap();
        let truth = [grey(10), grey(20), grey(30)];
        let shown = [(12, [1; 16]), (22, [1; 16]), (30, [[1, 2]; 8].concat().try_into().unwrap())];
        let mut state = ModeState::default();
        for (frame, (value, counts)) in shown.into_iter().enumerate() {
            let pair =
                TruthPair { now: &truth[frame], then: frame.checked_sub(1).map(|f| &truth[f]), flow: None };
            let rendered = ModeFrame {
                seconds: 0.01 * (frame + 1) as f64,
                display: grey(value),
                counts: Some(counts.to_vec()),
                checks: FrameChecks::default(),
            };
            state.add(mode, rendered, &pair, &mut [0.0; 16], false);
        }
        let step = 1.0 / 255.0_f64.powi(2);
        let sequence = state.conclude(3, Some(100.0 * step)).sequence.expect("three frames: a sequence");
        assert_eq!(sequence.mse, [4.0 * step, 4.0 * step, 0.0], "MSE per frame");
        assert!((sequence.mean_psnr_db.value() - -10.0 * (8.0 * step / 3.0).log10()).abs() < 1e-12);
        // (ΔA − ΔT)² is 0 over the first pair and 4 over the second, per value of 2 pairs.
        assert!((sequence.instability - 2.0 * step).abs() < 1e-15, "{}", sequence.instability);
        // The mode changes by 10 and 8 steps where the truth changes by 10: 82 against 100.
        assert!((sequence.change_ratio.unwrap() - 0.82).abs() < 1e-12);
        assert_eq!(sequence.count_changes, Some(0.25), "no count changed, then half");
        let shaded = sequence.shaded_percent.unwrap();
        assert!((shaded - (25.0 + 25.0 + 37.5) / 3.0).abs() < 1e-9, "1, 1 and 1.5 of 4 samples: {shaded}");
        assert_eq!(sequence.frame_ms.map(|t| t.samples.len()), Some(3));
        assert_eq!((sequence.flicker, sequence.ghosting), (None, None), "no flow: nothing followed");
        assert_eq!(sequence.hashes.len(), 3);
        let short = ModeState::default().conclude(3, None);
        assert!(short.sequence.is_none(), "a mode that rendered fewer frames than the others has none");
    }

    #[test]
    fn flip_along_the_path_stops_at_a_signal() {
        let dir = std::env::temp_dir().join(format!("aabench-flip-stop-{}", std::process::id()));
        let mut spool =
            Spool::create(dir.join("spool"), [8, 8], 8, 0, vec!["truth".into(), "mode".into()]).unwrap();
        for value in [10, 200] {
            for stream in [0, 1] {
                spool.append(stream, &DisplayImage::from_rgba8(&[value; 256])).unwrap();
            }
        }
        let flips = flip_along(&spool, 2, 67.0, &AtomicBool::new(false)).unwrap();
        assert_eq!((flips[1].len(), flips[1][0]), (2, 0.0), "identical frames: FLIP 0 at each");
        let error = flip_along(&spool, 2, 67.0, &AtomicBool::new(true)).unwrap_err();
        assert!(error.contains("interrupted"), "{error}");
        drop(spool);
        let _ = std::fs::remove_dir_all(&dir);
    }
}
