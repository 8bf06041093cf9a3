//! Perceptual error of a display image against the truth: mean FLIP (Andersson et al. 2020,
//! LDR-FLIP, through `nv-flip`, which binds NVIDIA's reference implementation), SSIM (Wang
//! et al. 2004, computed here and checked against scikit-image in `tests/perceptual.rs`) and
//! ColorVideoVDP (Mantiuk et al. 2024, the workspace's `aabench-cvvdp`, checked against its
//! reference implementation), of stills and of a path's frames as a video.
//!
//! All read the display's code values, as MSE and PSNR do. FLIP takes them as 8-bit sRGB (a
//! 10-bit image is rounded to 8 bits first; on a PQ-encoded image FLIP's sRGB model is a
//! proxy); SSIM scales them to [0, 1]; ColorVideoVDP decodes them through the scene's display
//! model (`display.jod_display`) into light, as a viewer would see them.

use aabench_renderer::DisplayImage;

/// FLIP's own default viewing distance, in pixels per degree: a 0.7 m wide 4K display seen from
/// 0.7 m. aabench judges at its viewer's instead ([`Jod::pixels_per_degree`]); FLIP's reference
/// values in the tests are at this one.
pub const FLIP_DEFAULT_PIXELS_PER_DEGREE: f64 = nv_flip::DEFAULT_PIXELS_PER_DEGREE as f64;

/// FLIP's per-pixel error of an image against the truth, in [0, 1], row by row.
#[derive(Debug)]
pub struct FlipMap {
    pub width: u32,
    pub height: u32,
    pub errors: Vec<f32>,
}

impl FlipMap {
    /// The mean error over the image: FLIP's summary of a comparison.
    pub fn mean(&self) -> f64 {
        self.errors.iter().map(|&e| f64::from(e)).sum::<f64>() / self.errors.len().max(1) as f64
    }

    /// The error map in FLIP's own colour scale (magma, black for no error), as RGBA bytes.
    pub fn magma_rgba(&self) -> Vec<u8> {
        magma_rgba(&self.errors)
    }
}

/// Values in [0, 1] (clamped) in FLIP's colour scale (magma: black at 0, yellow at 1), as RGBA
/// bytes.
pub fn magma_rgba(values: &[f32]) -> Vec<u8> {
    let lut = nv_flip::magma_lut().to_vec();
    values
        .iter()
        .flat_map(|&e| {
            let i = 3 * (e.clamp(0.0, 1.0) * 255.0).round() as usize;
            [lut[i], lut[i + 1], lut[i + 2], 255]
        })
        .collect()
}

/// FLIP of `image` against `truth`, both `width` × `height`, seen at `pixels_per_degree`.
pub fn flip(
    image: &DisplayImage,
    truth: &DisplayImage,
    [width, height]: [u32; 2],
    pixels_per_degree: f64,
) -> FlipMap {
    let rgba8 = crate::files::images::display_rgba8;
    flip_rgba8(&rgba8(image), &rgba8(truth), [width, height], pixels_per_degree)
}

/// FLIP of an RGBA8 display image (alpha ignored) against the truth's, both `width` × `height`,
/// seen at `pixels_per_degree` (the viewer's: [`Jod::pixels_per_degree`]).
pub fn flip_rgba8(image: &[u8], truth: &[u8], [width, height]: [u32; 2], pixels_per_degree: f64) -> FlipMap {
    let rgb = |rgba: &[u8]| -> Vec<u8> { rgba.chunks_exact(4).flat_map(|p| [p[0], p[1], p[2]]).collect() };
    let reference = nv_flip::FlipImageRgb8::with_data(width, height, &rgb(truth));
    let test = nv_flip::FlipImageRgb8::with_data(width, height, &rgb(image));
    let errors = nv_flip::flip(reference, test, pixels_per_degree as f32).to_vec();
    FlipMap { width, height, errors }
}

/// ColorVideoVDP on one display model: a still's JOD against the truth, and a video's.
#[derive(Debug, Clone)]
pub struct Jod {
    metric: aabench_cvvdp::Cvvdp,
}

impl Jod {
    /// The metric on ColorVideoVDP's display model `name` (checked when the manifest loaded).
    pub fn new(name: &str) -> Result<Self, String> {
        let display = aabench_cvvdp::Display::named(name).map_err(|error| error.to_string())?;
        Ok(Jod { metric: aabench_cvvdp::Cvvdp::new(display) })
    }

    /// The display model it judges on.
    pub fn display(&self) -> &aabench_cvvdp::Display {
        self.metric.display()
    }

    /// How many of a frame's pixels a degree of the viewer's sight spans: ColorVideoVDP's
    /// display model's, and FLIP's too, so that both metrics judge what one viewer sees.
    pub fn pixels_per_degree(&self) -> f64 {
        self.metric.display().pixels_per_degree
    }

    /// The JOD of `image` against `truth`, both `width` × `height`.
    pub fn image(&self, image: &DisplayImage, truth: &DisplayImage, width: u32, height: u32) -> f64 {
        let max = f32::from(image.max_code());
        let (test, reference) = (code_values(&image.rgba, max), code_values(&truth.rgba, max));
        let size = [width, height];
        self.metric.image(frame(&test, size), frame(&reference, size)).map_or(f64::NAN, |score| score.jod)
    }

    /// The JOD of display frames against the truth's, shown at `fps` frames a second, the first
    /// `warmup` of them history for the temporal filters and the rest pooled, and the distortion
    /// map of the measured frame that differs most (counted from the first after the warm-up);
    /// `None` for fewer than two frames, none measured, or a frame of the wrong size.
    pub fn video<'a>(
        &self,
        frames: impl Iterator<Item = (&'a DisplayImage, &'a DisplayImage)>,
        [width, height]: [u32; 2],
        fps: f64,
        warmup: usize,
    ) -> Option<VideoJod> {
        let video = self.metric.video(width as usize, height as usize, fps).ok()?;
        let mut video = video.with_worst_map().measured_from(warmup);
        for (image, truth) in frames {
            let max = f32::from(image.max_code());
            let (test, reference) = (code_values(&image.rgba, max), code_values(&truth.rgba, max));
            video.push(frame(&test, [width, height]), frame(&reference, [width, height])).ok()?;
        }
        let score = video.finish().ok()?;
        let worst = score.worst.expect("a map was asked for");
        let worst_frame = (worst.frame - warmup) as u32;
        Some(VideoJod { jod: score.jod, worst_frame, map: worst.map.data, width, height })
    }
}

/// A video's JOD, and where it differs most: the frame whose difference is largest and its
/// distortion map, per pixel 1 − JOD/10 (0 where no difference shows; above 1 where it is
/// beyond 10 JOD).
#[derive(Debug, Clone, PartialEq)]
pub struct VideoJod {
    pub jod: f64,
    pub worst_frame: u32,
    pub map: Vec<f32>,
    pub width: u32,
    pub height: u32,
}

fn frame(rgb: &[f32], [width, height]: [u32; 2]) -> aabench_cvvdp::Frame<'_> {
    aabench_cvvdp::Frame { width: width as usize, height: height as usize, rgb }
}

/// The RGB of RGBA code values (8- or 10-bit, `max` the largest) as values in [0, 1].
fn code_values<T: Copy + Into<f32>>(rgba: &[T], max: f32) -> Vec<f32> {
    rgba.chunks_exact(4).flat_map(|p| [p[0], p[1], p[2]].map(|v| v.into() / max)).collect()
}

/// SSIM's window: a Gaussian of σ 1.5 truncated at 3.5σ, 11 taps.
const SSIM_SIGMA: f64 = 1.5;
const SSIM_RADIUS: usize = 5;
/// The stabilizing constants' factors for a data range of 1.
const SSIM_K1: f64 = 0.01;
const SSIM_K2: f64 = 0.03;

/// Mean SSIM of `image` against `truth` over their R, G and B channels, each scaled to
/// [0, 1]: local means, variances and covariance under the Gaussian window (population
/// moments, edges mirrored), the map averaged over pixels at least the window's radius from
/// the border (all pixels in an image too small for that). This is scikit-image's
/// `structural_similarity(gaussian_weights=True, sigma=1.5, use_sample_covariance=False,
/// data_range=1)`, the form of Wang et al.'s paper.
pub fn ssim(image: &DisplayImage, truth: &DisplayImage, width: u32, height: u32) -> f64 {
    SsimTruth::new(truth, width, height).ssim(image)
}

/// The truth's side of SSIM, computed once for every mode compared with it: per channel its
/// values, local means and local means of squares. An image is then three blurs per channel
/// from its score instead of five.
#[derive(Debug)]
pub struct SsimTruth {
    width: usize,
    height: usize,
    channels: [TruthChannel; 3],
}

#[derive(Debug)]
struct TruthChannel {
    values: Vec<f64>,
    mean: Vec<f64>,
    square_mean: Vec<f64>,
}

impl SsimTruth {
    pub fn new(truth: &DisplayImage, width: u32, height: u32) -> Self {
        let (w, h) = (width as usize, height as usize);
        let window = gaussian_window();
        let channels = std::array::from_fn(|c| {
            let values = channel(truth, c);
            let squares: Vec<f64> = values.iter().map(|v| v * v).collect();
            TruthChannel {
                mean: blur(&values, w, h, &window),
                square_mean: blur(&squares, w, h, &window),
                values,
            }
        });
        Self { width: w, height: h, channels }
    }

    /// Mean SSIM of `image` against the truth (`ssim`).
    pub fn ssim(&self, image: &DisplayImage) -> f64 {
        let scores =
            self.channels.iter().enumerate().map(|(c, truth)| self.ssim_channel(&channel(image, c), truth));
        scores.sum::<f64>() / 3.0
    }

    fn ssim_channel(&self, x: &[f64], truth: &TruthChannel) -> f64 {
        let (w, h) = (self.width, self.height);
        let window = gaussian_window();
        let mu_x = blur(x, w, h, &window);
        let xx = blur(&x.iter().map(|v| v * v).collect::<Vec<_>>(), w, h, &window);
        let xy = blur(&x.iter().zip(&truth.values).map(|(a, b)| a * b).collect::<Vec<_>>(), w, h, &window);
        let (mu_y, yy) = (&truth.mean, &truth.square_mean);
        let (c1, c2) = (SSIM_K1 * SSIM_K1, SSIM_K2 * SSIM_K2);
        let inset = if w > 2 * SSIM_RADIUS && h > 2 * SSIM_RADIUS { SSIM_RADIUS } else { 0 };
        let mut sum = 0.0;
        for row in inset..h - inset {
            for col in inset..w - inset {
                let i = row * w + col;
                let (mx, my) = (mu_x[i], mu_y[i]);
                let (vx, vy, cov) = (xx[i] - mx * mx, yy[i] - my * my, xy[i] - mx * my);
                sum += (2.0 * mx * my + c1) * (2.0 * cov + c2) / ((mx * mx + my * my + c1) * (vx + vy + c2));
            }
        }
        sum / ((w - 2 * inset) * (h - 2 * inset)) as f64
    }
}

/// Channel `c` of a display image, scaled to [0, 1].
fn channel(image: &DisplayImage, c: usize) -> Vec<f64> {
    let max = f64::from(image.max_code());
    image.rgba.chunks_exact(4).map(|p| f64::from(p[c]) / max).collect()
}

/// The normalized Gaussian taps, −radius…radius.
fn gaussian_window() -> Vec<f64> {
    let taps: Vec<f64> = (-(SSIM_RADIUS as i64)..=SSIM_RADIUS as i64)
        .map(|i| (-0.5 * (i * i) as f64 / (SSIM_SIGMA * SSIM_SIGMA)).exp())
        .collect();
    let total: f64 = taps.iter().sum();
    taps.into_iter().map(|t| t / total).collect()
}

/// The index `i` (which may lie outside 0…n) mirrored into 0…n the way scipy's `reflect`
/// does: … c b a | a b c … (the edge sample repeated).
fn mirror(i: i64, n: usize) -> usize {
    let n = n as i64;
    let period = 2 * n;
    let i = i.rem_euclid(period);
    (if i < n { i } else { period - 1 - i }) as usize
}

/// `plane` filtered by the separable `window` along rows, then columns, edges mirrored.
fn blur(plane: &[f64], w: usize, h: usize, window: &[f64]) -> Vec<f64> {
    let r = (window.len() / 2) as i64;
    // Where each tap of each output lands, mirrored once here rather than per tap.
    let sources = |n: usize| -> Vec<usize> { (-r..n as i64 + r).map(|i| mirror(i, n)).collect() };
    let (across, down) = (sources(w), sources(h));
    let mut rows = vec![0.0; plane.len()];
    for (line, out) in plane.chunks_exact(w).zip(rows.chunks_exact_mut(w)) {
        for (x, value) in out.iter_mut().enumerate() {
            *value = window.iter().zip(&across[x..]).map(|(t, &i)| t * line[i]).sum();
        }
    }
    let mut out = vec![0.0; plane.len()];
    for (y, line) in out.chunks_exact_mut(w).enumerate() {
        for (t, &source) in window.iter().zip(&down[y..]) {
            for (value, v) in line.iter_mut().zip(&rows[source * w..(source + 1) * w]) {
                *value += t * v;
            }
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn mirroring_repeats_the_edge_sample() {
        let mirrored: Vec<usize> = (-3..7).map(|i| mirror(i, 4)).collect();
        assert_eq!(mirrored, [2, 1, 0, 0, 1, 2, 3, 3, 2, 1]);
    }

    #[test]
    fn the_window_sums_to_one_and_is_symmetric() {
        let window = gaussian_window();
        assert_eq!(window.len(), 11);
        assert!((window.iter().sum::<f64>() - 1.0).abs() < 1e-12);
        assert!(window.iter().zip(window.iter().rev()).all(|(a, b)| a == b));
    }
}
