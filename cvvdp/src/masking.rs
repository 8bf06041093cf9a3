//! A band's visible difference: contrast scaled by castleCSF's sensitivity, masked by what the
//! test and the reference share (mutual masking across channels, spread by phase uncertainty),
//! soft-clamped, and pooled over the band's pixels; the reference's `process_block_of_frames`
//! and `apply_masking_model` for its "mult-mutual" model.

use crate::csf::{AtFrequency, CastleCsf, Channel};
use crate::parameters::Parameters;
use crate::pyramid::{Background, ContrastBand, Plane};

/// The reference's guard on powers.
const EPSILON: f32 = 0.000_01;

/// The reference's guard on powers: (x + ε)^p − ε^p, ε = 10⁻⁵, which is 0 at 0 and
/// differentiable for any p.
pub fn safe_pow(x: f32, p: f32) -> f32 {
    SafePow::new(p).of(x)
}

/// [`safe_pow`] to one exponent, its ε^p computed once: the metric raises millions of values
/// to a handful of exponents.
#[derive(Debug, Clone, Copy)]
pub struct SafePow {
    p: f32,
    floor: f32,
}

impl SafePow {
    pub fn new(p: f32) -> Self {
        SafePow { p, floor: EPSILON.powf(p) }
    }

    pub fn of(self, x: f32) -> f32 {
        let base = x + EPSILON;
        // A square as torch computes one: a product, not a call to pow.
        let power = if self.p == 2.0 { base * base } else { base.powf(self.p) };
        power - self.floor
    }
}

/// Per channel gains on the contrast after the CSF (the red–green channel's 1.45).
const CHANNEL_GAIN: [f32; 4] = [1.0, 1.45, 1.0, 1.0];

/// The spatial frequency the baseband is judged at, cycles a degree.
const BASEBAND_FREQUENCY: f64 = 0.1;

/// The phase-uncertainty blur: a Gaussian of σ `pu_dilate` (3) px, 13 taps, as torchvision's
/// `GaussianBlur(13, 3)` builds it.
#[derive(Debug, Clone)]
pub struct PhaseBlur {
    taps: Vec<f32>,
}

impl PhaseBlur {
    pub fn new(sigma: f32) -> Self {
        let size = (sigma * 4.0) as usize + 1;
        let half = (size - 1) as f32 * 0.5;
        let pdf: Vec<f32> = (0..size)
            .map(|i| {
                let x = -half + i as f32 * (2.0 * half) / (size - 1) as f32;
                (-0.5 * (x / sigma).powi(2)).exp()
            })
            .collect();
        let sum: f32 = pdf.iter().sum();
        PhaseBlur { taps: pdf.iter().map(|p| p / sum).collect() }
    }

    pub fn taps(&self) -> &[f32] {
        &self.taps
    }

    /// The plane blurred (reflected at the borders) when it is larger than twice σ on both
    /// sides, as the reference requires; otherwise unchanged.
    fn apply(&self, plane: &Plane) -> Plane {
        let pad = self.taps.len() / 2;
        if plane.width <= pad || plane.height <= pad {
            return plane.clone();
        }
        let rows = self.along_rows(plane);
        let columns = self.along_rows(&rows.transposed());
        columns.transposed()
    }

    fn along_rows(&self, plane: &Plane) -> Plane {
        let (w, pad) = (plane.width, self.taps.len() / 2);
        let reflect = |i: isize| -> usize {
            let last = w as isize - 1;
            (if i < 0 {
                -i
            } else if i > last {
                2 * last - i
            } else {
                i
            }) as usize
        };
        let mut out = Plane::zeros(w, plane.height);
        for (row_in, row_out) in plane.data.chunks_exact(w).zip(out.data.chunks_exact_mut(w)) {
            // Inside, tap by tap over the whole run of pixels (the same sums in the same order,
            // which the compiler vectorizes); at the ends, reflected.
            let inside = pad..w.saturating_sub(pad).max(pad);
            for (k, &t) in self.taps.iter().enumerate().filter(|_| !inside.is_empty()) {
                for (o, &v) in row_out[inside.clone()].iter_mut().zip(&row_in[k..]) {
                    *o += t * v;
                }
            }
            for x in (0..w).filter(|x| !inside.contains(x)) {
                row_out[x] = self
                    .taps
                    .iter()
                    .enumerate()
                    .map(|(k, &t)| t * row_in[reflect(x as isize + k as isize - pad as isize)])
                    .sum();
            }
        }
        out
    }
}

/// What the masking model needs beside the band.
#[derive(Debug)]
pub struct Model<'a> {
    pub parameters: &'a Parameters,
    pub csf: &'a CastleCsf,
    pub blur: &'a PhaseBlur,
}

impl Model<'_> {
    /// The band's difference per channel (the first `test.len()` of [`Channel::ALL`]) and
    /// pixel, at its peak frequency `rho`.
    pub fn band(&self, band: &ContrastBand, rho: f64, is_baseband: bool) -> Vec<Plane> {
        let channels = band.test.len();
        let rho = if is_baseband { BASEBAND_FREQUENCY } else { rho };
        let correction = 10f32.powf(self.parameters.sensitivity_correction / 20.0);
        let sensitivity = |channel: usize| -> Plane {
            let column = self.csf.at_frequency(Channel::ALL[channel], rho);
            sensitivity_plane(&column, &band.log_background, &band.test[channel], correction)
        };
        if is_baseband {
            (0..channels)
                .map(|c| {
                    let s = sensitivity(c);
                    let data = (0..s.data.len())
                        .map(|i| (band.test[c].data[i] - band.reference[c].data[i]).abs() * s.data[i])
                        .collect();
                    Plane { data, ..s }
                })
                .collect()
        } else {
            self.masked(band, &(0..channels).map(sensitivity).collect::<Vec<_>>())
        }
    }

    /// Each channel's difference pooled over the band's pixels: their p-norm, normalised.
    pub fn pool(&self, differences: &[Plane]) -> Vec<f32> {
        let beta = self.parameters.beta;
        let power = SafePow::new(beta);
        differences
            .iter()
            .map(|d| {
                let sum: f64 = d.data.iter().map(|&v| f64::from(power.of(v))).sum();
                safe_pow((sum / d.data.len() as f64) as f32, 1.0 / beta)
            })
            .collect()
    }

    /// The mutual-masking model's difference per channel and pixel.
    fn masked(&self, band: &ContrastBand, sensitivity: &[Plane]) -> Vec<Plane> {
        let p = self.parameters;
        let channels = band.test.len();
        let scaled = |contrast: &Plane, c: usize| -> Plane {
            let data = contrast
                .data
                .iter()
                .zip(&sensitivity[c].data)
                .map(|(&v, &s)| v * s * CHANNEL_GAIN[c])
                .collect();
            Plane { data, ..contrast.clone() }
        };
        let test: Vec<Plane> = (0..channels).map(|c| scaled(&band.test[c], c)).collect();
        let reference: Vec<Plane> = (0..channels).map(|c| scaled(&band.reference[c], c)).collect();
        let mask_scale = 10f32.powf(p.mask_c);
        let shared: Vec<Plane> = (0..channels)
            .map(|c| {
                let data =
                    test[c].data.iter().zip(&reference[c].data).map(|(t, r)| t.abs().min(r.abs())).collect();
                let blurred = self.blur.apply(&Plane { data, ..test[c].clone() });
                let power = SafePow::new(p.mask_q[c]);
                blurred.map(|m| power.of((m * mask_scale).abs()))
            })
            .collect();
        let max_difference = 10f32.powf(p.d_max);
        let power = SafePow::new(p.mask_p);
        let cross: Vec<Vec<f32>> =
            (0..channels).map(|k| (0..channels).map(|c| p.cross_channel_weight(k, c)).collect()).collect();
        (0..channels)
            .map(|c| {
                let data = (0..test[c].data.len())
                    .map(|i| {
                        let mask: f32 = (0..channels).map(|k| shared[k].data[i] * cross[k][c]).sum();
                        let unclamped =
                            power.of((test[c].data[i] - reference[c].data[i]).abs()) / (1.0 + mask);
                        max_difference * unclamped / (max_difference + unclamped)
                    })
                    .collect();
                Plane { data, ..test[c].clone() }
            })
            .collect()
    }
}

/// castleCSF's sensitivity at each pixel's background (one value for the baseband), times the
/// model's correction, shaped like `like`.
fn sensitivity_plane(column: &AtFrequency, background: &Background, like: &Plane, correction: f32) -> Plane {
    match background {
        Background::Local(log_background) => log_background.map(|l| column.sensitivity(l) * correction),
        Background::Mean(log_mean) => {
            let s = column.sensitivity(*log_mean) * correction;
            Plane { width: like.width, height: like.height, data: vec![s; like.data.len()] }
        }
    }
}
