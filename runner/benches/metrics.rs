//! CPU costs that grow with image size: quality metrics over a 1024×768 image pair (with and
//! without the perceptual ones), sample statistics, and the CPU twin of the adaptive metric over
//! every window of a 4×4 G-buffer.

use aabench::measure::pixels;
use aabench_renderer::adaptive::{self, MetricSet, WindowSample};
use aabench_renderer::{AdaptiveSettings, Counts, DisplayImage, Metrics, Mode, Reconstruction, Technique};
use criterion::{Criterion, criterion_group, criterion_main};
use std::hint::black_box;

const WIDTH: usize = 1024;
const HEIGHT: usize = 768;

/// A deterministic 8-bit image with gradients and a hard edge.
fn image(seed: u8) -> DisplayImage {
    let bytes: Vec<u8> = (0..WIDTH * HEIGHT)
        .flat_map(|p| {
            let (x, y) = (p % WIDTH, p / WIDTH);
            let edge = if x * 3 + y > 2000 { 200 } else { 30 };
            [(x / 4) as u8 ^ seed, (y / 3) as u8, edge, 255]
        })
        .collect();
    DisplayImage::from_rgba8(&bytes)
}

/// adaptive-4x4, the paper's mode.
const ADAPTIVE_4X4: Mode =
    Mode::new(Technique::Adaptive(Metrics::Both, Reconstruction::Equal, Counts::PerFrame), 4, false);

fn quality(c: &mut Criterion) {
    let (a, b) = (image(0), image(1));
    c.bench_function("quality 1024x768 (MSE, PSNR, max diff)", |bench| {
        bench.iter(|| pixels::quality(black_box(&a), black_box(&b), "reference"))
    });
    // What each mode of a run adds against the truth: MSE, FLIP with its error map, SSIM and
    // ColorVideoVDP's JOD, the truth's share of SSIM prepared once per scene as a run prepares it.
    let jod = aabench::measure::perceptual::Jod::new(aabench_cvvdp::display::STANDARD_FHD).unwrap();
    let truth = pixels::Truth::new(b.clone(), WIDTH as u32, HEIGHT as u32, jod);
    c.bench_function("quality_vs_truth 1024x768 (MSE, PSNR, FLIP, SSIM, JOD)", |bench| {
        bench.iter(|| pixels::quality_vs_truth(black_box(&a), &truth, "truth"))
    });
    let counts: Vec<u8> = (0..WIDTH * HEIGHT).map(|p| 1 + (p % 16) as u8).collect();
    c.bench_function("sample_stats 1024x768 at 4x4", |bench| {
        bench.iter(|| pixels::sample_stats(black_box(&counts), ADAPTIVE_4X4, true).unwrap())
    });
}

fn metric_twin(c: &mut Criterion) {
    // One 4×4 window per pixel of 1024×768: a sloped surface with a depth step every 37 pixels.
    let windows: Vec<[WindowSample; 16]> = (0..WIDTH * HEIGHT)
        .map(|p| {
            std::array::from_fn(|i| {
                let depth = 5.0 + (p % WIDTH) as f64 * 0.01 + if (p + i) % 37 == 0 { 3.0 } else { 0.0 };
                WindowSample { depth, normal: [0.0, 0.3 * (i as f64 * 0.01).sin(), 1.0], covered: true }
            })
        })
        .collect();
    let luma = [0.4, 0.42, 0.41, 0.9, 0.4];
    let settings = AdaptiveSettings::default();
    let both = MetricSet { geometry: true, shading: true };
    c.bench_function("CPU metric twin, 1024x768 windows at 4x4", |bench| {
        bench.iter(|| {
            windows
                .iter()
                .map(|w| adaptive::sample_count(black_box(w), &luma, 4, &settings, both))
                .sum::<u32>()
        })
    });
}

criterion_group! {
    name = cpu;
    config = Criterion::default().sample_size(20);
    targets = quality, metric_twin
}
criterion_main!(cpu);
