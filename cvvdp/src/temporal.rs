//! The temporal channels: each DKL channel filtered over the last 250 ms of frames, the
//! achromatic one twice (sustained and transient), as the reference's
//! `get_temporal_filters` and `read_block_of_frames` do, with the first frame repeated into
//! the past (its default "replicate" padding).

use crate::parameters::Parameters;
use crate::pyramid::Plane;

/// The four filters over time, each `len` taps, oldest frame first.
#[derive(Debug, Clone, PartialEq)]
pub struct Filters {
    pub taps: [Vec<f32>; 4],
}

impl Filters {
    /// The filters at `fps` frames a second: their frequency responses (exponential fall-offs
    /// for the sustained channels, a band-pass about 5 Hz for the transient one) sampled on
    /// ⌊N/2⌋ + 1 frequencies and turned into N symmetric taps by an inverse real DFT, N the odd
    /// number of frames in 250 ms.
    pub fn new(parameters: &Parameters, fps: f64) -> Self {
        let n = taps(fps);
        let bins = n / 2 + 1;
        let nyquist = (fps / 2.0) as f32;
        let omega: Vec<f32> = (0..bins).map(|i| linspace(0.0, nyquist, bins, i)).collect();
        let (beta, sigma) = (&parameters.beta_tf, &parameters.sigma_tf);
        let response = |channel: usize| -> Vec<f32> {
            omega
                .iter()
                .map(|&w| match channel {
                    3 => (-(w.powf(beta[3]) - 5f32.powf(beta[3])).powi(2) / sigma[3]).exp(),
                    c => (-w.powf(beta[c]) / sigma[c]).exp(),
                })
                .collect()
        };
        Filters { taps: std::array::from_fn(|channel| centred_inverse_dft(&response(channel), n)) }
    }

    /// Frames each filter spans.
    pub fn len(&self) -> usize {
        self.taps[0].len()
    }

    pub fn is_empty(&self) -> bool {
        self.taps[0].is_empty()
    }
}

/// The frames the filters span at `fps` frames a second: the odd number of frames in 250 ms
/// (17 at 60). A frame's score reads the `taps(fps) - 1` frames before it.
pub fn taps(fps: f64) -> usize {
    ((0.250 * fps / 2.0).ceil() as usize) * 2 + 1
}

/// torch.linspace's `i`-th of `steps` values from `start` to `end`, in single precision: from
/// the start for the first half, from the end for the second.
fn linspace(start: f32, end: f32, steps: usize, i: usize) -> f32 {
    if steps == 1 {
        return start;
    }
    let step = (end - start) / (steps - 1) as f32;
    if i < steps / 2 { start + step * i as f32 } else { end - step * (steps - 1 - i) as f32 }
}

/// The real, even signal of `n` (odd) samples whose DFT's first ⌊n/2⌋ + 1 coefficients are
/// `spectrum` (numpy's `irfft`), shifted so that its peak is in the middle (`fftshift`).
fn centred_inverse_dft(spectrum: &[f32], n: usize) -> Vec<f32> {
    let signal = |t: usize| -> f64 {
        let rest: f64 = spectrum
            .iter()
            .enumerate()
            .skip(1)
            .map(|(k, &r)| {
                2.0 * f64::from(r) * (2.0 * std::f64::consts::PI * (k * t) as f64 / n as f64).cos()
            })
            .sum();
        (f64::from(spectrum[0]) + rest) / n as f64
    };
    (0..n).map(|i| signal((i + n - n / 2) % n) as f32).collect()
}

/// The last `len` frames of each DKL channel of one clip (test or reference), oldest first.
#[derive(Debug)]
pub struct Window {
    frames: Vec<[Plane; 3]>,
    len: usize,
}

impl Window {
    pub fn new(len: usize) -> Self {
        Window { frames: Vec::with_capacity(len), len }
    }

    /// Takes the next frame; the first fills the whole window (the past repeats it).
    pub fn push(&mut self, frame: [Plane; 3]) {
        if self.frames.is_empty() {
            self.frames = vec![frame; self.len];
        } else {
            self.frames.remove(0);
            self.frames.push(frame);
        }
    }

    /// The four temporal channels of the newest frame: achromatic sustained, red–green,
    /// yellow–violet (each filtered by its own filter) and achromatic transient.
    pub fn channels(&self, filters: &Filters) -> Vec<Plane> {
        (0..4)
            .map(|channel| {
                let source = if channel == 3 { 0 } else { channel };
                let first = &self.frames[0][source];
                let mut out = Plane::zeros(first.width, first.height);
                // The reference correlates with the flipped filter: the newest frame meets
                // the first tap.
                for (frame, &tap) in self.frames.iter().zip(filters.taps[channel].iter().rev()) {
                    for (o, &v) in out.data.iter_mut().zip(&frame[source].data) {
                        *o += v * tap;
                    }
                }
                out
            })
            .collect()
    }
}
