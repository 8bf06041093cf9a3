//! Image-quality and sample-count metrics, in f64 on the display image's code values scaled to
//! [0, 1] (8- or 10-bit), averaged over pixels and the R, G, B channels.
//!
//! They are taken after dither and quantization, on the image a display would show: every mode
//! of a scene and its ground truth get the same grain at the same pixel, so two modes whose
//! linear images agree give identical code values (an infinite PSNR stays infinite), and the
//! dither turns quantization into unbiased noise instead of banding that would shift with
//! the anti-aliasing.

use aabench_renderer::color::luminance;
use aabench_renderer::{DisplayImage, FrameImages, Mode};

use crate::measure::perceptual::{self, FlipMap};
use serde::{Deserialize, Serialize, Serializer};

/// 20·log10(255): the paper reports PSNR with peak 255 over an MSE taken on [0, 1] values.
pub const PAPER_PSNR_OFFSET_DB: f64 = 48.130_803_608_679_1;

/// A PSNR in decibels. Identical images have an infinite PSNR; JSON has no infinity, so it is
/// written as the string `"inf"` (which Python's `float()` reads back as infinity).
#[derive(Debug, Clone, Copy, PartialEq, Deserialize)]
#[serde(untagged)]
pub enum Decibels {
    Finite(f64),
    Infinite(InfinityTag),
}

#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub enum InfinityTag {
    #[serde(rename = "inf")]
    Inf,
}

impl Decibels {
    pub fn from_f64(db: f64) -> Decibels {
        if db.is_finite() { Decibels::Finite(db) } else { Decibels::Infinite(InfinityTag::Inf) }
    }

    pub fn value(self) -> f64 {
        match self {
            Decibels::Finite(db) => db,
            Decibels::Infinite(_) => f64::INFINITY,
        }
    }
}

impl Serialize for Decibels {
    fn serialize<S: Serializer>(&self, serializer: S) -> Result<S::Ok, S::Error> {
        match self {
            Decibels::Finite(db) => serializer.serialize_f64(*db),
            Decibels::Infinite(_) => serializer.serialize_str("inf"),
        }
    }
}

/// Error of an image against another.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Quality {
    /// The mode compared against.
    pub against: String,
    pub mse: f64,
    /// MSE × 10⁵, the unit of the paper's Table 1.
    pub mse_e5: f64,
    /// PSNR with peak 1 over the same MSE.
    pub psnr_db: Decibels,
    /// Paper-comparable PSNR: peak 255 over the MSE on [0, 1] values (psnr_db + 48.13 dB).
    pub psnr_paper_db: Decibels,
    /// Largest per-channel difference, in code steps of the images' bit depth.
    pub max_abs_diff: u16,
    /// Mean FLIP error in [0, 1], 0 for identical images (`perceptual::flip`). Against the
    /// truth only; absent from records from before it.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub flip: Option<f64>,
    /// Mean SSIM over R, G and B, 1 for identical images (`perceptual::ssim`). Against the
    /// truth only; absent from records from before it.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub ssim: Option<f64>,
    /// ColorVideoVDP's score of the image against the truth, in JOD (10: no visible
    /// difference), on the scene's `jod_display` (`perceptual::Jod`). Against the truth only;
    /// absent from records from before it.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub jod: Option<f64>,
}

/// Compares two display images of the same size and bit depth (alpha ignored).
pub fn quality(image: &DisplayImage, reference: &DisplayImage, against: &str) -> Quality {
    assert_eq!(image.rgba.len(), reference.rgba.len(), "images of different sizes");
    assert_eq!(image.bits, reference.bits, "images of different bit depths");
    let scale = f64::from(image.max_code());
    // Squared code steps summed exactly in integers (at most 1023² × 3 per pixel, far from
    // u64's range), divided once: a running f64 sum drifted by 3·10⁻¹⁰ over a 4096² image.
    let mut sum = 0u64;
    let mut max_abs_diff = 0u16;
    for (a, b) in image.rgba.chunks_exact(4).zip(reference.rgba.chunks_exact(4)) {
        for c in 0..3 {
            let step = a[c].abs_diff(b[c]);
            sum += u64::from(step) * u64::from(step);
            max_abs_diff = max_abs_diff.max(step);
        }
    }
    let mse = sum as f64 / (scale * scale) / (image.rgba.len() / 4 * 3).max(1) as f64;
    let psnr = -10.0 * mse.log10();
    Quality {
        against: against.to_string(),
        mse,
        mse_e5: mse * 1e5,
        psnr_db: Decibels::from_f64(psnr),
        psnr_paper_db: Decibels::from_f64(psnr + PAPER_PSNR_OFFSET_DB),
        max_abs_diff,
        flip: None,
        ssim: None,
        jod: None,
    }
}

/// A scene's truth, with what the perceptual metrics compute of it once for all its modes.
#[derive(Debug)]
pub struct Truth {
    pub image: DisplayImage,
    width: u32,
    height: u32,
    ssim: perceptual::SsimTruth,
    jod: perceptual::Jod,
}

impl Truth {
    pub fn new(image: DisplayImage, width: u32, height: u32, jod: perceptual::Jod) -> Self {
        let ssim = perceptual::SsimTruth::new(&image, width, height);
        Self { image, width, height, ssim, jod }
    }
}

/// `quality` against the truth with the perceptual metrics added, and FLIP's error map.
pub fn quality_vs_truth(image: &DisplayImage, truth: &Truth, against: &str) -> (Quality, FlipMap) {
    let size = [truth.width, truth.height];
    let map = perceptual::flip(image, &truth.image, size, truth.jod.pixels_per_degree());
    let quality = Quality {
        flip: Some(map.mean()),
        ssim: Some(truth.ssim.ssim(image)),
        jod: Some(truth.jod.image(image, &truth.image, truth.width, truth.height)),
        ..quality(image, &truth.image, against)
    };
    (quality, map)
}

/// How many samples an adaptive mode shaded.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SampleStats {
    /// Samples that make up the image over M²·w·h, in percent: the paper's "Samples %".
    pub shaded_percent: f64,
    /// Σ n over pixels.
    pub shaded: u64,
    /// M²·w·h.
    pub total: u64,
    /// Pixels that took all M² samples. In a scene with textures their S is shaded again at
    /// the reference's footprint (so they equal the reference), one sample of work that
    /// `shaded` does not count; without textures S is that sample and is reused.
    pub full_pixels: u64,
    /// Pixels whose S was shaded again, one sample of work each that `shaded` does not count:
    /// the full pixels of a textured scene, and under `-cells` and `-coverage` every pixel of
    /// more than one sample.
    #[serde(default)]
    pub reshaded: u64,
    /// Every shading evaluation over M²·w·h, in percent: (shaded + reshaded) / total.
    pub work_percent: f64,
    /// `histogram[i]`: pixels that shaded i + 1 samples, for i + 1 in 1…M².
    pub histogram: Vec<u64>,
}

/// Statistics of a sample-count map of `mode` in a scene with or without textures (which
/// decides whether full windows shade S again). Counts outside [1, M²] are a bug upstream:
/// `Err` says so.
pub fn sample_stats(counts: &[u8], mode: Mode, textured: bool) -> Result<SampleStats, String> {
    let m = mode.m;
    let window = (m * m) as usize;
    let mut histogram = vec![0u64; window];
    for (pixel, &n) in counts.iter().enumerate() {
        if n == 0 || n as usize > window {
            return Err(format!("pixel {pixel} has sample count {n}, outside 1..={window}"));
        }
        histogram[n as usize - 1] += 1;
    }
    let shaded: u64 = counts.iter().map(|&n| u64::from(n)).sum();
    let full_pixels = histogram[window - 1];
    let reshaded = (1..=window as u32)
        .filter(|&n| mode.reshades_first(n, textured))
        .map(|n| histogram[n as usize - 1])
        .sum();
    let total = (window * counts.len()) as u64;
    let percent = |count: u64| 100.0 * count as f64 / total.max(1) as f64;
    Ok(SampleStats {
        shaded_percent: percent(shaded),
        shaded,
        total,
        full_pixels,
        reshaded,
        work_percent: percent(shaded + reshaded),
        histogram,
    })
}

/// The blur that separates coarse error from fine: σ 2 px passes periods of about 8 px and
/// more, near the eye's peak sensitivity at the standard display's 38 pixels per degree, and
/// takes out the pixel-scale detail it barely sees.
pub const COARSE_SIGMA_PX: f64 = 2.0;

/// The share of the error's energy (luma of the code values' difference, over the frames)
/// that a Gaussian blur of σ [`COARSE_SIGMA_PX`] keeps: near 1 for a smooth error (a blob, a
/// lag), near 0 for one that alternates pixel by pixel. The frames are RGBA8 rows `width`
/// pixels wide (the flicker region's crops). `None` without error or frames, or where the
/// two disagree in size.
pub fn coarse_share(truth: &[Vec<u8>], mode: &[Vec<u8>], width: usize) -> Option<f64> {
    let (mut coarse, mut total) = (0.0, 0.0);
    for (t, m) in truth.iter().zip(mode) {
        if m.len() != t.len() || width == 0 || t.len() % (4 * width) != 0 {
            return None;
        }
        let luma = |p: &[u8]| luminance([p[0], p[1], p[2]].map(f64::from));
        let error: Vec<f64> =
            t.chunks_exact(4).zip(m.chunks_exact(4)).map(|(p, q)| (luma(q) - luma(p)) / 255.0).collect();
        total += error.iter().map(|e| e * e).sum::<f64>();
        coarse += gaussian_blur(&error, width, error.len() / width).iter().map(|e| e * e).sum::<f64>();
    }
    (total > 0.0).then(|| coarse / total)
}

/// A separable Gaussian blur of σ [`COARSE_SIGMA_PX`], edges clamped.
fn gaussian_blur(values: &[f64], width: usize, height: usize) -> Vec<f64> {
    let radius = (3.0 * COARSE_SIGMA_PX).ceil() as isize;
    let weights: Vec<f64> =
        (-radius..=radius).map(|i| (-((i * i) as f64) / (2.0 * COARSE_SIGMA_PX.powi(2))).exp()).collect();
    let sum: f64 = weights.iter().sum();
    let blur_line = |line: &[f64]| -> Vec<f64> {
        let last = line.len() as isize - 1;
        (0..=last)
            .map(|i| {
                let taps = (-radius..=radius).zip(&weights);
                taps.map(|(o, w)| w * line[(i + o).clamp(0, last) as usize]).sum::<f64>() / sum
            })
            .collect()
    };
    let rows: Vec<f64> = values.chunks(width).flat_map(blur_line).collect();
    let mut out = vec![0.0; values.len()];
    for x in 0..width {
        let column: Vec<f64> = (0..height).map(|y| rows[y * width + x]).collect();
        for (y, value) in blur_line(&column).into_iter().enumerate() {
            out[y * width + x] = value;
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use aabench_renderer::{Counts, Metrics, Reconstruction, Technique};
    use proptest::prelude::*;

    fn frames(pixel: impl Fn(usize, usize) -> u8) -> Vec<Vec<u8>> {
        let frame: Vec<u8> = (0..32 * 32).flat_map(|i| [pixel(i % 32, i / 32); 4]).collect();
        vec![frame.clone(), frame]
    }

    #[test]
    fn a_smooth_error_is_coarse_and_a_pixel_checkerboard_is_not() {
        let truth = frames(|_, _| 100);
        let blob = coarse_share(
            &truth,
            &frames(|x, y| if (8..24).contains(&x) && (8..24).contains(&y) { 160 } else { 100 }),
            32,
        );
        let checker = coarse_share(&truth, &frames(|x, y| if (x + y) % 2 == 0 { 160 } else { 40 }), 32);
        let (blob, checker) = (blob.unwrap(), checker.unwrap());
        assert!(blob > 0.6, "a 16-px square's error is mostly coarse: {blob}");
        assert!(checker < 0.01, "a checkerboard's error is all fine: {checker}");
        assert_eq!(coarse_share(&truth, &truth, 32), None, "no error, no share");
        let constant = coarse_share(&truth, &frames(|_, _| 110), 32).unwrap();
        assert!((constant - 1.0).abs() < 1e-9, "a constant error survives any blur: {constant}");
        assert_eq!(coarse_share(&truth, &frames(|_, _| 110), 31), None, "rows of another width");
    }

    #[test]
    fn a_black_frame_is_told_it_may_be_unlit_and_a_coloured_one_is_not() {
        let display = DisplayImage::from_rgba8(&[0; 64]);
        let black = blank_image(&[0.0; 64], &display).unwrap();
        assert!(black.contains("nothing in view is lit") && black.contains("no sample hit"), "{black}");
        let sky: Vec<f32> = [0.2, 0.3, 0.5, 1.0].repeat(16);
        let background = blank_image(&sky, &display).unwrap();
        assert!(
            !background.contains("nothing in view is lit") && background.contains("no sample hit"),
            "{background}"
        );
    }

    /// MSE over a 4096² image equals an exact integer computation within a relative 10⁻¹², at 8
    /// and at 10 bits. A running f64 sum had drifted by 3·10⁻¹⁰ here; squared code steps are
    /// now summed in integers.
    #[test]
    fn mse_over_a_large_image_matches_exact_integer_arithmetic() {
        // 4096² pixels: the f64 running sum against an exact integer sum of squared code steps,
        // at both bit depths.
        let pixels = 4096 * 4096;
        let code = |i: usize, salt: u32, max: u32| {
            (aabench_renderer::color::hash(i as u32 ^ salt.wrapping_mul(0x9e37_79b9)) % (max + 1)) as u16
        };
        for (bits, max) in [(8, 255u32), (10, 1023)] {
            let a = DisplayImage { bits, rgba: (0..pixels * 4).map(|i| code(i, 1, max)).collect() };
            let b = DisplayImage { bits, rgba: (0..pixels * 4).map(|i| code(i, 2, max)).collect() };
            let exact: u64 = a
                .rgba
                .chunks_exact(4)
                .zip(b.rgba.chunks_exact(4))
                .flat_map(|(p, q)| (0..3).map(move |c| u64::from(p[c].abs_diff(q[c])).pow(2)))
                .sum();
            let expected = exact as f64 / f64::from(max * max) / (pixels * 3) as f64;
            let q = quality(&a, &b, "x");
            assert!((q.mse / expected - 1.0).abs() < 1e-12, "{bits} bits: {} vs {expected}", q.mse);
        }
    }

    proptest! {
        #[test]
        fn quality_is_symmetric_bounded_and_finite_or_infinite(
            a in prop::collection::vec(any::<u8>(), 4..256),
            b_seed in any::<u8>(),
        ) {
            let pixels = a.len() / 4 * 4;
            let a = DisplayImage::from_rgba8(&a[..pixels]);
            let b = DisplayImage::from_rgba8(&a.rgba.iter().map(|&v| (v as u8).wrapping_add(b_seed)).collect::<Vec<_>>());
            let (ab, ba) = (quality(&a, &b, "b"), quality(&b, &a, "a"));
            prop_assert_eq!(ab.mse, ba.mse);
            prop_assert!((0.0..=1.0).contains(&ab.mse));
            prop_assert!(ab.psnr_db.value() >= 0.0 && !ab.psnr_db.value().is_nan());
            prop_assert_eq!(ab.psnr_db.value().is_infinite(), ab.mse == 0.0);
            prop_assert!(ab.max_abs_diff <= 255);
        }
    }

    #[test]
    fn identical_images_have_infinite_psnr_written_as_inf() {
        let image = DisplayImage::from_rgba8(&[10, 20, 30, 255, 40, 50, 60, 255]);
        let q = quality(&image, &image, "reference-2x2");
        assert_eq!(q.mse, 0.0);
        assert_eq!(q.psnr_db.value(), f64::INFINITY);
        let json = serde_json::to_value(&q).unwrap();
        assert_eq!(json["psnr_db"], "inf");
        let back: Quality = serde_json::from_value(json).unwrap();
        assert_eq!(back, q);
    }

    #[test]
    fn one_step_everywhere_is_48_db_and_the_paper_offset_is_20_log10_255() {
        let a = DisplayImage::from_rgba8(&[0, 0, 0, 255]);
        let b = DisplayImage::from_rgba8(&[1, 1, 1, 0]);
        let q = quality(&a, &b, "x");
        assert!((q.mse - 1.0 / 65025.0).abs() < 1e-18);
        assert!((q.psnr_db.value() - 48.1308036).abs() < 1e-6);
        assert!((PAPER_PSNR_OFFSET_DB - 20.0 * 255f64.log10()).abs() < 1e-12);
        assert_eq!(q.max_abs_diff, 1);
        // At 10 bits one step is a quarter of an 8-bit step: 16 times less MSE.
        let ten = |v: u16| DisplayImage { bits: 10, rgba: vec![v, v, v, 1023] };
        let q10 = quality(&ten(0), &ten(1), "x");
        assert!((q10.mse - 1.0 / (1023.0 * 1023.0)).abs() < 1e-18);
    }

    #[test]
    fn alpha_is_ignored() {
        let q = quality(
            &DisplayImage::from_rgba8(&[5, 5, 5, 0]),
            &DisplayImage::from_rgba8(&[5, 5, 5, 255]),
            "x",
        );
        assert_eq!(q.mse, 0.0);
    }

    #[test]
    fn sample_stats_count_and_reject_out_of_range() {
        let adaptive = |reconstruction| {
            Mode::new(Technique::Adaptive(Metrics::Both, reconstruction, Counts::PerFrame), 2, false)
        };
        let stats = sample_stats(&[1, 1, 4, 2], adaptive(Reconstruction::Equal), true).unwrap();
        assert_eq!(stats.histogram, vec![2, 1, 0, 1]);
        assert_eq!((stats.shaded, stats.total, stats.full_pixels, stats.reshaded), (8, 16, 1, 1));
        assert_eq!((stats.shaded_percent, stats.work_percent), (50.0, 56.25));
        // Without textures the full pixel reuses S: no work beyond its samples.
        let plain = sample_stats(&[1, 1, 4, 2], adaptive(Reconstruction::Equal), false).unwrap();
        assert_eq!((plain.full_pixels, plain.reshaded, plain.work_percent), (1, 0, 50.0));
        // `-cells` shades S again in every pixel of more than one sample, textures or not.
        for textured in [true, false] {
            let cells = sample_stats(&[1, 1, 4, 2], adaptive(Reconstruction::Cells), textured).unwrap();
            assert_eq!((cells.shaded, cells.full_pixels, cells.reshaded), (8, 1, 2));
            assert_eq!(cells.work_percent, 100.0 * 10.0 / 16.0);
        }
        // MSAA shades a pixel of four samples four times, not five.
        let msaa = sample_stats(&[1, 1, 4, 4], Mode::new(Technique::Msaa, 2, false), true).unwrap();
        assert_eq!((msaa.shaded, msaa.reshaded, msaa.work_percent), (10, 0, msaa.shaded_percent));
        assert!(sample_stats(&[0], adaptive(Reconstruction::Equal), true).is_err());
        assert!(sample_stats(&[5], adaptive(Reconstruction::Equal), true).is_err());
    }
}

/// The one value every item has, or `None` when two differ (or there is none).
fn flat<T: PartialEq + Copy>(mut items: impl Iterator<Item = T>) -> Option<T> {
    let first = items.next()?;
    items.all(|item| item == first).then_some(first)
}

/// Frames smaller than this many pixels are not judged blank: one pixel is always flat.
pub const BLANK_MIN_PIXELS: usize = 16;

/// Why a frame shows nothing, or `None`: every pixel's HDR colour the same (no sample hit
/// visible geometry: back faces only, geometry far below a pixel, a camera that sees only the
/// background), or every display pixel the same code (an exposure or a transfer function that
/// rounds everything to one code). Alpha is left out: it carries the stall's result.
pub fn blank_frame(images: &FrameImages) -> Option<String> {
    blank_image(&images.hdr, &images.display)
}

/// [`blank_frame`] of a frame's HDR image (RGBA, flattened) and display image.
pub fn blank_image(hdr: &[f32], display: &DisplayImage) -> Option<String> {
    if display.rgba.len() / 4 < BLANK_MIN_PIXELS {
        return None;
    }
    let hdr = flat(hdr.chunks_exact(4).map(|p| [p[0].to_bits(), p[1].to_bits(), p[2].to_bits()]));
    if let Some([r, g, b]) = hdr {
        let [r, g, b] = [r, g, b].map(f32::from_bits);
        // Black everywhere: geometry in view that no light reaches looks like no geometry.
        let unlit = if [r, g, b] == [0.0; 3] {
            "nothing in view is lit (no light and no ambient reach it), or "
        } else {
            ""
        };
        return Some(format!(
            "blank frame: every pixel has the same HDR colour ({r}, {g}, {b}): {unlit}no sample hit visible \
             geometry (only back faces, geometry far below a pixel, everything nearer than the camera's near \
             plane or beyond its far plane, or nothing in view); declare the scene \
             `\"empty\": true` if that is meant"
        ));
    }
    let display = flat(display.rgba.chunks_exact(4).map(|p| [p[0], p[1], p[2]].map(u32::from)));
    display.map(|[r, g, b]| {
        format!(
            "blank frame: every display pixel has the code ({r}, {g}, {b}): the exposure, tonemap or transfer \
             function leaves nothing to see; check the manifest's `tonemap.exposure` and `display` sections"
        )
    })
}

/// What every frame of every mode is checked for: NaN and infinite values in the HDR output
/// (the display passes sanitize them, so they would otherwise go unseen) and sample counts
/// outside [1, M²].
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct FrameChecks {
    /// Frames checked.
    pub frames: u32,
    /// NaN channel values, all frames together.
    pub nan: u64,
    /// ±Inf channel values, all frames together.
    pub inf: u64,
    /// Pixels whose sample count is 0 or above M², all frames together.
    pub counts_out_of_range: u64,
}

impl FrameChecks {
    /// The checks of one frame: its HDR RGBA values and, for adaptive modes, its sample counts.
    pub fn of(hdr: &[f32], counts: Option<&[u8]>, m: u32) -> FrameChecks {
        let full = m * m;
        FrameChecks {
            frames: 1,
            nan: hdr.iter().filter(|v| v.is_nan()).count() as u64,
            inf: hdr.iter().filter(|v| v.is_infinite()).count() as u64,
            counts_out_of_range: counts
                .unwrap_or_default()
                .iter()
                .filter(|&&n| n == 0 || u32::from(n) > full)
                .count() as u64,
        }
    }

    pub fn add(&mut self, other: FrameChecks) {
        self.frames += other.frames;
        self.nan += other.nan;
        self.inf += other.inf;
        self.counts_out_of_range += other.counts_out_of_range;
    }

    /// What failed, in words, or `None`.
    pub fn problem(&self, m: u32) -> Option<String> {
        let mut problems = Vec::new();
        if self.nan + self.inf > 0 {
            problems.push(format!("{} NaN and {} infinite HDR values", self.nan, self.inf));
        }
        if self.counts_out_of_range > 0 {
            problems.push(format!("{} sample counts outside [1, {}]", self.counts_out_of_range, m * m));
        }
        (!problems.is_empty()).then(|| format!("{} in {} frames", problems.join(" and "), self.frames))
    }
}
