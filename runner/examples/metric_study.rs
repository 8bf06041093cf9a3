//! What the adaptive metric spends, and where adaptive images' error comes from (`docs/adaptive.md`, "What
//! the metric does, measured"). For each M it renders the scene's adaptive mode once, reads
//! back the G-buffer, the shade-first image S and the sample counts, recomputes each term of
//! the metric with the CPU twin, and compares the display image with the ground truth:
//!
//! - **flat planes**: pixels whose M² samples all lie on one plane of one material (normals
//!   within 0.5°, 1/depth affine in the sample position to 10⁻⁵). Such a window has no edge,
//!   yet its depth varies, more the more grazing and the farther the plane. The extra samples
//!   there beyond what the shading metric asks are spent on depth variance alone;
//! - **error by sample count**: the share of the squared error (8-bit display codes, against
//!   the 8×8 truth) carried by pixels shaded with n samples, next to their share of pixels.
//!
//! `cargo run --release --example metric_study -- scenes/atrium.json [quick|nightly] [VARIANT]`
//!
//! VARIANT (`area`, `cells`) studies `adaptive-MxM-VARIANT` instead of the paper's mode.

use std::path::Path;
use std::sync::Arc;

use aabench::manifest::Manifest;
use aabench::plan::Tier;
use aabench::run::render_settings;
use aabench::run::scenes;
use aabench::run::truth::{TILE_BYTES, TRUTH_M};
use aabench_renderer::adaptive::{self, MetricSet, WindowSample};
use aabench_renderer::{ExtraSamples, Gpu, SceneRenderer, color};
use anyhow::Context;

/// Normals closer than this cone (sqrt(1 − cos), 0.5°) count as one plane's: the G-buffer
/// keeps them in f16.
const FLAT_CONE: f64 = 0.007;
/// 1/depth is affine in screen position across a plane; residuals below this share of the
/// mean come from the depth buffer's f32 precision.
const PLANE_RESIDUAL: f64 = 1e-5;

fn main() -> anyhow::Result<()> {
    let mut args = std::env::args().skip(1);
    let path = args.next().context("usage: metric_study MANIFEST [quick|nightly] [VARIANT]")?;
    let tier = match args.next().as_deref() {
        Some("nightly") => Tier::Nightly,
        _ => Tier::Quick,
    };
    let suffix = args.next().map(|variant| format!("-{variant}")).unwrap_or_default();
    let manifest = Manifest::load(Path::new(&path))?;
    let loaded = scenes::load(&manifest)?;
    let settings = render_settings(&manifest, tier, ExtraSamples::Compact);
    let gpu = Arc::new(Gpu::new()?);
    let mut renderer =
        SceneRenderer::new(gpu, &loaded.scene, &loaded.camera, &loaded.lighting, settings.clone())?;
    if manifest.tonemap.exposure.is_none() {
        renderer.meter_exposure(color::EXPOSURE_KEY, color::METERED_EXPOSURE_RANGE)?;
    }
    let exposure = f64::from(renderer.exposure());
    let truth = renderer.render_truth(TRUTH_M, TILE_BYTES)?.images.display;
    println!("# {} ({}, {}×{}){suffix}\n", manifest.name, tier.name(), settings.width, settings.height);
    for m in 2..=4 {
        let prepared = renderer.prepare(format!("adaptive-{m}x{m}{suffix}").parse()?)?;
        prepared.render()?;
        let images = prepared.read_images()?;
        let counts = images.sample_counts.context("an adaptive mode has counts")?;
        let gbuffer = prepared.read_gbuffer()?;
        let first = prepared.read_first()?.context("an adaptive mode has S")?;
        let (w, h) = (settings.width, settings.height);

        let mut study = Study::new(m);
        for p in 0..w * h {
            let (x, y) = (p % w, p / w);
            let window = gbuffer.window(m, x, y);
            let materials: Vec<f32> =
                gbuffer.window_indices(m, x, y).map(|s| gbuffer.normal_material[s][3]).collect();
            let cross = adaptive::luma_cross(&first, w, h, x, y, exposure);
            let shading_only = MetricSet { geometry: false, shading: true };
            let n_shading = adaptive::sample_count(&window, &cross, m, &settings.adaptive, shading_only);
            let error: f64 = (0..3)
                .map(|c| {
                    let i = p as usize * 4 + c;
                    (f64::from(images.display.rgba[i]) - f64::from(truth.rgba[i])).powi(2)
                })
                .sum();
            let n = u32::from(counts[p as usize]);
            study.add(n, n_shading, is_flat_plane(&window, &materials, m), error);
        }
        study.print();
    }
    Ok(())
}

/// All samples covered, one material, one normal, and depths on one plane.
fn is_flat_plane(window: &[WindowSample], materials: &[f32], m: u32) -> bool {
    if !window.iter().all(|s| s.covered) || materials.iter().any(|&id| id != materials[0]) {
        return false;
    }
    let (_, cone) = adaptive::geometry_metric(window, adaptive::DepthMetric::Relative);
    cone < FLAT_CONE && plane_residual(window, m) < PLANE_RESIDUAL
}

/// The largest residual of the least-squares fit of 1/depth = a + b·i + c·j over the window's
/// sample grid (i, j), relative to the mean of 1/depth. On a regular grid centred on zero the
/// normal equations decouple: a is the mean, b and c the covariances over the variances.
fn plane_residual(window: &[WindowSample], m: u32) -> f64 {
    let centre = f64::from(m - 1) / 2.0;
    let points: Vec<(f64, f64, f64)> = window
        .iter()
        .enumerate()
        .map(|(k, s)| {
            (k as f64 % f64::from(m) - centre, (k as f64 / f64::from(m)).floor() - centre, 1.0 / s.depth)
        })
        .collect();
    let count = points.len() as f64;
    let a = points.iter().map(|p| p.2).sum::<f64>() / count;
    let spread = points.iter().map(|p| p.0 * p.0).sum::<f64>();
    let b = points.iter().map(|p| p.0 * p.2).sum::<f64>() / spread;
    let c = points.iter().map(|p| p.1 * p.2).sum::<f64>() / spread;
    let worst = points.iter().map(|p| (p.2 - (a + b * p.0 + c * p.1)).abs()).fold(0.0, f64::max);
    worst / a
}

/// Tallies of one M.
struct Study {
    m: u32,
    /// Per n (index n − 1): pixels, squared error.
    pixels: Vec<u64>,
    squared_error: Vec<f64>,
    flat_pixels: u64,
    /// Extra samples (n − 1) over all pixels, and those a flat plane took beyond what the
    /// shading metric asked.
    extra: u64,
    extra_on_planes: u64,
}

impl Study {
    fn new(m: u32) -> Study {
        let cells = (m * m) as usize;
        Study {
            m,
            pixels: vec![0; cells],
            squared_error: vec![0.0; cells],
            flat_pixels: 0,
            extra: 0,
            extra_on_planes: 0,
        }
    }

    fn add(&mut self, n: u32, n_shading: u32, flat: bool, squared_error: f64) {
        self.pixels[n as usize - 1] += 1;
        self.squared_error[n as usize - 1] += squared_error;
        self.extra += u64::from(n - 1);
        if flat {
            self.flat_pixels += 1;
            self.extra_on_planes += u64::from(n.saturating_sub(n_shading));
        }
    }

    fn print(&self) {
        let pixels: u64 = self.pixels.iter().sum();
        let error: f64 = self.squared_error.iter().sum();
        let percent = |part: f64, whole: f64| if whole > 0.0 { 100.0 * part / whole } else { 0.0 };
        println!("## {m}×{m}\n", m = self.m);
        println!(
            "- extra samples: {} ({:.1} % of the reference's); on flat planes for depth variance alone: {} = {:.1} % of them",
            self.extra,
            percent(self.extra as f64, (pixels * u64::from(self.m * self.m - 1)) as f64),
            self.extra_on_planes,
            percent(self.extra_on_planes as f64, self.extra as f64)
        );
        println!(
            "- flat-plane pixels: {:.1} % of the image\n",
            percent(self.flat_pixels as f64, pixels as f64)
        );
        println!("| n | pixels | share of pixels | share of squared error | mean squared error (codes²) |");
        println!("|---|---|---|---|---|");
        for (i, (&count, &se)) in self.pixels.iter().zip(&self.squared_error).enumerate() {
            if count > 0 {
                println!(
                    "| {} | {count} | {:.1} % | {:.1} % | {:.2} |",
                    i + 1,
                    percent(count as f64, pixels as f64),
                    percent(se, error),
                    se / (3 * count) as f64
                );
            }
        }
        println!();
    }
}
