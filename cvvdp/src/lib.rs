//! ColorVideoVDP (Mantiuk, Hanji, Ashraf, Asano and Chapiro, "ColorVideoVDP: A visual
//! difference predictor for image, video and display distortions", ACM TOG 43(4), SIGGRAPH
//! 2024) in Rust: how visible the difference between a test and a reference image or video
//! is, in just-objectionable differences (JOD; 10 is no visible difference, one JOD less is a
//! difference 75 % of observers would choose the reference over).
//!
//! A port of the reference implementation, `cvvdp` 0.5.7 (MIT licence; its calibrated model
//! and tables are vendored under `data/`), step for step and in single precision as it
//! computes, so that a score is the reference's within 0.01 JOD (`tests/reference.rs`, on
//! fixtures the reference scored):
//!
//! 1. display model: code values → luminance (`display.rs`), → DKL colour (`colour.rs`);
//! 2. temporal channels: 250 ms filters, sustained and transient (`temporal.rs`);
//! 3. a Laplacian pyramid in Weber contrast (`pyramid.rs`);
//! 4. castleCSF sensitivity (`csf.rs`), mutual masking across channels and a soft clamp,
//!    pooled over each band's pixels (`masking.rs`);
//! 5. pooling over bands, channels and frames, and the mapping to JOD (here);
//! 6. where asked, the per-pixel distortion map (`heatmap.rs`).
//!
//! Only the base model is ported: no colour rendering of the map, no HLG display, no temporal
//! resampling; frames are streamed one at a time (`Video::push`).
//!
//! One addition to the reference: a video may be given a warm-up ([`Video::measured_from`]).
//! Its frames pass the temporal filters, so that the first measured frame's 250 ms of history
//! is real footage rather than the first frame repeated into the past, but only the measured
//! frames are pooled. Without one, a video is scored exactly as the reference scores it.

pub mod colour;
pub mod csf;
pub mod display;
mod error;
pub mod heatmap;
pub mod masking;
pub mod parameters;
pub mod pyramid;
pub mod temporal;

pub use display::{Display, Eotf};
pub use error::Error;
pub use masking::safe_pow;

use csf::CastleCsf;
use masking::{Model, PhaseBlur};
use parameters::Parameters;
use pyramid::Plane;
use temporal::{Filters, Window};

/// A frame of display-encoded RGB: interleaved, row by row, values in [0, 1] (clamped, as the
/// reference does).
#[derive(Debug, Clone, Copy)]
pub struct Frame<'a> {
    pub width: usize,
    pub height: usize,
    pub rgb: &'a [f32],
}

/// The fewest pixels a side of a frame the metric scores.
pub const MIN_SIDE: usize = 4;

/// ColorVideoVDP with a display model.
#[derive(Debug, Clone)]
pub struct Cvvdp {
    parameters: Parameters,
    csf: CastleCsf,
    blur: PhaseBlur,
    display: Display,
}

/// A comparison's result.
#[derive(Debug, Clone, PartialEq)]
pub struct Score {
    /// Just-objectionable differences, at most 10.
    pub jod: f64,
    /// Each frame's pooled difference per channel and band, `[frame][channel][band]` (the
    /// reference's `Q_per_ch`), the baseband last; a video's warm-up frames included, though
    /// only the measured ones are pooled into `jod`.
    pub per_channel: Vec<Vec<Vec<f32>>>,
    /// Each band's peak frequency, cycles a degree; the baseband's is 0.1.
    pub band_frequencies: Vec<f64>,
    /// Where asked for ([`Video::with_worst_map`]): the measured frame whose pooled difference
    /// is the largest, and its distortion map.
    pub worst: Option<Worst>,
}

/// A frame and its distortion map: per pixel 1 − JOD/10, 0 where no difference shows (the
/// reference's "raw" heat map).
#[derive(Debug, Clone, PartialEq)]
pub struct Worst {
    pub frame: usize,
    pub map: Plane,
}

impl Cvvdp {
    pub fn new(display: Display) -> Self {
        let parameters = Parameters::embedded();
        let blur = PhaseBlur::new(parameters.pu_dilate);
        Cvvdp { parameters, csf: CastleCsf::embedded(), blur, display }
    }

    pub fn display(&self) -> &Display {
        &self.display
    }

    pub fn parameters(&self) -> &Parameters {
        &self.parameters
    }

    /// The score of a test image against its reference.
    pub fn image(&self, test: Frame, reference: Frame) -> Result<Score, Error> {
        let (score, _) = self.image_and_map(test, reference, false)?;
        Ok(score)
    }

    /// The score of a test image against its reference, and its distortion map.
    pub fn image_with_map(&self, test: Frame, reference: Frame) -> Result<(Score, Plane), Error> {
        let (score, map) = self.image_and_map(test, reference, true)?;
        Ok((score, map.expect("a map was asked for")))
    }

    fn image_and_map(
        &self,
        test: Frame,
        reference: Frame,
        map: bool,
    ) -> Result<(Score, Option<Plane>), Error> {
        check_frame(&test, test.width, test.height)?;
        check_frame(&reference, test.width, test.height)?;
        let planes =
            |frame: &Frame| colour::dkl_planes(&self.display, frame.width, frame.height, frame.rgb).to_vec();
        let (per_channel, map) = self.frame(&planes(&test), &planes(&reference), map.then_some(true));
        Ok((self.score(vec![per_channel], [test.width, test.height], Pooled::Image), map))
    }

    /// A video comparison of `width` × `height` frames at `fps` frames a second, fed a frame
    /// pair at a time.
    pub fn video(&self, width: usize, height: usize, fps: f64) -> Result<Video<'_>, Error> {
        if !(fps.is_finite() && fps > 0.0) {
            return Err(Error::FrameRate(fps));
        }
        if width < MIN_SIDE || height < MIN_SIDE {
            return Err(Error::TooSmall { width, height });
        }
        let filters = Filters::new(&self.parameters, fps);
        let len = filters.len();
        Ok(Video {
            metric: self,
            width,
            height,
            filters,
            test: Window::new(len),
            reference: Window::new(len),
            per_frame: Vec::new(),
            measured_from: 0,
            worst_map: None,
        })
    }

    /// One frame's pooled difference per channel and band, from its channels' planes (test
    /// and reference, in [`csf::Channel::ALL`]'s order), and its distortion map where `map`
    /// says whether the frame is an image or a video's.
    fn frame(
        &self,
        test: &[Plane],
        reference: &[Plane],
        map: Option<bool>,
    ) -> (Vec<Vec<f32>>, Option<Plane>) {
        let (width, height) = (test[0].width, test[0].height);
        let frequencies = pyramid::band_frequencies(width, height, self.display.pixels_per_degree);
        let levels = frequencies.len() - 1;
        let bands = pyramid::weber_contrast(test, reference, levels);
        let model = Model { parameters: &self.parameters, csf: &self.csf, blur: &self.blur };
        let differences: Vec<Vec<Plane>> =
            bands.iter().enumerate().map(|(b, band)| model.band(band, frequencies[b], b == levels)).collect();
        let per_band: Vec<Vec<f32>> = differences.iter().map(|d| model.pool(d)).collect();
        let per_channel = (0..test.len()).map(|c| per_band.iter().map(|band| band[c]).collect()).collect();
        let map = map.map(|is_image| {
            heatmap::distortion_map(&differences, &self.parameters, is_image, |q| self.to_jod(q))
        });
        (per_channel, map)
    }

    /// A frame's difference pooled over its bands (the baseband weighted) and its channels
    /// (weighted).
    fn frame_quality(&self, channels: &[Vec<f32>]) -> f32 {
        let p = &self.parameters;
        let weights = p.channel_weights();
        let pooled: Vec<f32> = channels
            .iter()
            .enumerate()
            .map(|(c, bands)| {
                let last = bands.len() - 1;
                let weighted = bands
                    .iter()
                    .enumerate()
                    .map(|(b, &q)| q * weights[c] * if b == last { p.baseband_weight[c] } else { 1.0 });
                lp_norm(weighted, p.beta_sch, 1)
            })
            .collect();
        lp_norm(pooled.into_iter(), p.beta_tch, 1)
    }

    /// Pools frames' differences into a score: each frame's (`frame_quality`), then over the
    /// frames from `first` on (a video's measured window), or for an image scaled by its
    /// integration correction; then maps to JOD.
    fn score(&self, per_channel: Vec<Vec<Vec<f32>>>, [width, height]: [usize; 2], pooled: Pooled) -> Score {
        let p = &self.parameters;
        let quality = match pooled {
            Pooled::Image => self.frame_quality(&per_channel[0]) * p.image_int,
            Pooled::From(first) => {
                let measured = &per_channel[first..];
                lp_norm(
                    measured.iter().map(|channels| self.frame_quality(channels)),
                    p.beta_t,
                    measured.len(),
                )
            }
        };
        let mut band_frequencies = pyramid::band_frequencies(width, height, self.display.pixels_per_degree);
        *band_frequencies.last_mut().expect("a pyramid has a baseband") = 0.1;
        Score { jod: f64::from(self.to_jod(quality)), per_channel, band_frequencies, worst: None }
    }

    /// The pooled difference in JOD: 10 − a·Q^e, linear below Q = 0.1 (the reference's
    /// `met2jod`).
    pub fn to_jod(&self, quality: f32) -> f32 {
        let p = &self.parameters;
        let knee = 0.1f32;
        if quality <= knee {
            10.0 - p.jod_a * knee.powf(p.jod_exp - 1.0) * quality
        } else {
            10.0 - p.jod_a * quality.powf(p.jod_exp)
        }
    }
}

/// How a score pools its frames: an image's one frame, or a video's frames from the first
/// measured one on.
#[derive(Debug, Clone, Copy)]
enum Pooled {
    Image,
    From(usize),
}

/// The reference's p-norm with its guarded powers: (Σ safe_pow(x, p) / n)^(1/p), guarded.
fn lp_norm(values: impl Iterator<Item = f32>, p: f32, n: usize) -> f32 {
    let power = masking::SafePow::new(p);
    let sum: f64 = values.map(|v| f64::from(power.of(v))).sum();
    safe_pow((sum / n as f64) as f32, 1.0 / p)
}

fn check_frame(frame: &Frame, width: usize, height: usize) -> Result<(), Error> {
    let expected = width * height * 3;
    if frame.width != width || frame.height != height || frame.rgb.len() != expected {
        return Err(Error::FrameSize { width, height, expected, got: frame.rgb.len() });
    }
    if width < MIN_SIDE || height < MIN_SIDE {
        return Err(Error::TooSmall { width, height });
    }
    Ok(())
}

/// A video comparison under way: frames in, a [`Score`] at the end.
#[derive(Debug)]
pub struct Video<'a> {
    metric: &'a Cvvdp,
    width: usize,
    height: usize,
    filters: Filters,
    test: Window,
    reference: Window,
    per_frame: Vec<Vec<Vec<f32>>>,
    /// The first frame pooled: those before it are the warm-up, history for the filters only.
    measured_from: usize,
    /// Where a map was asked for: the worst measured frame so far, its pooled difference and
    /// its map.
    worst_map: Option<Option<(usize, f32, Plane)>>,
}

impl Video<'_> {
    /// Keeps the distortion map of the frame whose pooled difference is the largest, for the
    /// score's `worst`.
    pub fn with_worst_map(mut self) -> Self {
        self.worst_map = Some(None);
        self
    }

    /// Makes the first `warmup` frames a warm-up: they pass the temporal filters, so that the
    /// frames after them are judged with a real history, as a viewer who has been watching
    /// would judge them, but only the frames after them are pooled into the score (and
    /// searched for the worst). Without it the first frame is repeated into the past, as the
    /// reference does, and a short clip is mostly judged as its first frame.
    pub fn measured_from(mut self, warmup: usize) -> Self {
        self.measured_from = warmup;
        self
    }

    /// Takes the next test frame and reference frame.
    pub fn push(&mut self, test: Frame, reference: Frame) -> Result<(), Error> {
        check_frame(&test, self.width, self.height)?;
        check_frame(&reference, self.width, self.height)?;
        let display = &self.metric.display;
        self.test.push(colour::dkl_planes(display, self.width, self.height, test.rgb));
        self.reference.push(colour::dkl_planes(display, self.width, self.height, reference.rgb));
        let (test, reference) = (self.test.channels(&self.filters), self.reference.channels(&self.filters));
        let measured = self.per_frame.len() >= self.measured_from;
        let map = self.worst_map.as_ref().filter(|_| measured).map(|_| false);
        let (per_channel, map) = self.metric.frame(&test, &reference, map);
        if let (Some(worst), Some(map)) = (&mut self.worst_map, map) {
            let quality = self.metric.frame_quality(&per_channel);
            if worst.as_ref().is_none_or(|(_, most, _)| quality > *most) {
                *worst = Some((self.per_frame.len(), quality, map));
            }
        }
        self.per_frame.push(per_channel);
        Ok(())
    }

    /// Frames taken so far.
    pub fn frames(&self) -> usize {
        self.per_frame.len()
    }

    /// The score of the frames taken, at least two (the reference scores a single frame as an
    /// image, without temporal channels: [`Cvvdp::image`]), of which at least one is measured.
    pub fn finish(self) -> Result<Score, Error> {
        let frames = self.per_frame.len();
        if frames < 2 || frames <= self.measured_from {
            return Err(Error::TooFewFrames { frames, warmup: self.measured_from });
        }
        let worst = self.worst_map.flatten().map(|(frame, _, map)| Worst { frame, map });
        let pooled = Pooled::From(self.measured_from);
        Ok(Score { worst, ..self.metric.score(self.per_frame, [self.width, self.height], pooled) })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn jod_is_linear_below_the_knee_and_continuous_at_it() {
        let metric = Cvvdp::new(Display::standard_fhd());
        let p = metric.parameters();
        let slope = p.jod_a * 0.1f32.powf(p.jod_exp - 1.0);
        assert_eq!(metric.to_jod(0.0), 10.0);
        assert!((metric.to_jod(0.05) - (10.0 - slope * 0.05)).abs() < 1e-6);
        let (below, above) = (metric.to_jod(0.1), metric.to_jod(0.100_001));
        assert!((below - above).abs() < 1e-5, "{below} against {above}");
        assert!((metric.to_jod(2.0) - (10.0 - p.jod_a * 2f32.powf(p.jod_exp))).abs() < 1e-6);
    }
}
