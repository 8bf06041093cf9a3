//! A CPU twin of the per-pixel sample-count metric that the GPU's `evaluate` pass computes: the
//! specification the shader is tested against, in f64 where the shader works in f32.

use super::settings::{AdaptiveSettings, DepthMetric};

/// One G-buffer sample as the metric sees it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct WindowSample {
    /// Linear view depth.
    pub depth: f64,
    /// World-space normal, not necessarily unit length (the G-buffer stores it in f16).
    pub normal: [f64; 3],
    /// False where no geometry covers the sample.
    pub covered: bool,
}

/// The luma cross of the shade-first image around a pixel: centre, left, right, up, down, each
/// from [`metric_luma`] (borders clamp to the edge pixel).
pub type LumaCross = [f64; 5];

/// The shading metric's perceptual luma of a linear HDR colour: the square root (a gamma-2
/// stand-in for sRGB, without `pow`) of the Rec. 709 luminance of the exposed colour clamped
/// to [0, 1]. The colour is sanitized first ([`crate::color::sanitize`]), as on the GPU.
pub fn metric_luma(rgb: [f64; 3], exposure: f64) -> f64 {
    let c = rgb.map(|v| (crate::color::sanitize(v) * exposure).clamp(0.0, 1.0));
    crate::color::luminance(c).sqrt()
}

/// The luma cross of pixel (x, y) of a `width`×`height` linear HDR image (the shade-first
/// image S), borders clamped.
pub fn luma_cross(image: &[[f32; 4]], width: u32, height: u32, x: u32, y: u32, exposure: f64) -> LumaCross {
    let luma = |dx: i64, dy: i64| {
        let px = (i64::from(x) + dx).clamp(0, i64::from(width) - 1) as usize;
        let py = (i64::from(y) + dy).clamp(0, i64::from(height) - 1) as usize;
        let p = image[py * width as usize + px];
        metric_luma([p[0], p[1], p[2]].map(f64::from), exposure)
    };
    [luma(0, 0), luma(-1, 0), luma(1, 0), luma(0, -1), luma(0, 1)]
}

/// A sample's texture footprint in G-buffer texels when n samples share an M×M window:
/// sqrt((1 + M²/n) / 2). Spread over the window in dither order, n samples filtered this wide
/// have together the same variance as the reference's M² samples of one texel each; it is 1 at
/// n = M² and sqrt((1 + M²)/2) for S (2.9 texels at M = 4, not the naive M/sqrt(n) = 4, which
/// blurs textures against the reference).
pub fn footprint(m: u32, n: u32) -> f64 {
    (0.5 + 0.5 * f64::from(m * m) / f64::from(n)).sqrt()
}

/// Which metrics take part: the paper's method uses both.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct MetricSet {
    pub geometry: bool,
    pub shading: bool,
}

/// Samples to shade for one pixel, S included: 1 + round(k), clamped to [1, M²].
pub fn sample_count(
    window: &[WindowSample],
    luma: &LumaCross,
    m: u32,
    settings: &AdaptiveSettings,
    metrics: MetricSet,
) -> u32 {
    if settings.force_all_samples {
        return m * m;
    }
    clamp_count(metric_k(window, luma, m, settings, metrics), m * m)
}

/// k before rounding: the largest of the selected metrics, each scaled by its C and by M².
/// Infinite on silhouettes against the background, whatever the constants: every sample, as
/// the GPU's finite k = 1 also gives. Never NaN: every term is finite or +∞.
pub fn metric_k(
    window: &[WindowSample],
    luma: &LumaCross,
    m: u32,
    settings: &AdaptiveSettings,
    metrics: MetricSet,
) -> f64 {
    let scale = f64::from(m * m);
    let mut k: f64 = 0.0;
    if metrics.geometry {
        let (variance, cone) = geometry_metric(window, settings.depth_metric);
        if variance.is_infinite() {
            return f64::INFINITY;
        }
        k = k
            .max(f64::from(settings.c_depth) * scale * variance)
            .max(f64::from(settings.c_normal) * scale * cone);
    }
    if metrics.shading {
        k = k.max(f64::from(settings.c_shading) * scale * shading_metric(luma, settings));
    }
    k
}

/// 1 + round(k) in [1, total]. k is never NaN (see [`metric_k`]); if it were, this last guard
/// would take every sample: shading too much is slow, shading too little is wrong.
pub fn clamp_count(k: f64, total: u32) -> u32 {
    let max_extra = f64::from(total - 1);
    let extra = if k >= 0.0 {
        (k + 0.5).floor().min(max_extra)
    } else if k.is_nan() {
        max_extra
    } else {
        0.0
    };
    1 + extra as u32
}

/// Depth variance and normal cone of an M×M window.
///
/// - A window partly covered by geometry sits on a silhouette against the background: both
///   metrics are infinite there. A wholly uncovered window has nothing to anti-alias: zero.
/// - The variance is computed in two passes (mean, then mean squared deviation), which cannot
///   go negative or cancel the way `E[d²] − E[d]²` does at large depths. The shader uses the
///   equally stable shifted form, Σ(d − d₀)² − (Σ(d − d₀))²/n, in one pass.
/// - The mean normal of opposite normals is zero: the cone is then the widest possible (1).
/// - 1 − min |n̄·n| is clamped at zero before the square root.
/// - [`DepthMetric::Relative`] divides the variance by the squared mean depth (which is at
///   least the near plane, so never zero).
pub fn geometry_metric(window: &[WindowSample], depth_metric: DepthMetric) -> (f64, f64) {
    let covered = window.iter().filter(|s| s.covered).count();
    if covered == 0 {
        return (0.0, 0.0);
    }
    if covered < window.len() {
        return (f64::INFINITY, f64::INFINITY);
    }
    let n = window.len() as f64;
    let mean = window.iter().map(|s| s.depth).sum::<f64>() / n;
    let variance = window.iter().map(|s| (s.depth - mean).powi(2)).sum::<f64>() / n;
    let variance = match depth_metric {
        DepthMetric::Relative => variance / (mean * mean),
        DepthMetric::World => variance,
    };

    let unit = |v: [f64; 3]| {
        let length = (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
        if length > 1e-6 { v.map(|c| c / length) } else { [0.0; 3] }
    };
    let normals: Vec<[f64; 3]> = window.iter().map(|s| unit(s.normal)).collect();
    let sum = normals.iter().fold([0.0; 3], |acc, v| [acc[0] + v[0], acc[1] + v[1], acc[2] + v[2]]);
    let sum_length = (sum[0] * sum[0] + sum[1] * sum[1] + sum[2] * sum[2]).sqrt();
    // The mean normal is only meaningful if the normals do not nearly cancel.
    if sum_length < 1e-3 * n {
        return (variance, 1.0);
    }
    let mean_normal = sum.map(|c| c / sum_length);
    let min_cos = normals
        .iter()
        .map(|v| (v[0] * mean_normal[0] + v[1] * mean_normal[1] + v[2] * mean_normal[2]).abs())
        .fold(1.0_f64, f64::min);
    (variance, (1.0 - min_cos).max(0.0).sqrt())
}

/// The luminance range r of the cross, or 0 below the thresholds. The centre pixel is included
/// (the paper names only the four neighbours): without it, a lone bright pixel among dark
/// neighbours would read as flat.
pub fn shading_metric(luma: &LumaCross, settings: &AdaptiveSettings) -> f64 {
    let l_max = luma.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    let l_min = luma.iter().copied().fold(f64::INFINITY, f64::min);
    let range = l_max - l_min;
    let threshold = f64::from(settings.t_min).max(l_max * f64::from(settings.t_edge));
    if range < threshold { 0.0 } else { range }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn flat(depth: f64, m: u32) -> Vec<WindowSample> {
        vec![WindowSample { depth, normal: [0.0, 0.0, 1.0], covered: true }; (m * m) as usize]
    }

    const BOTH: MetricSet = MetricSet { geometry: true, shading: true };

    #[test]
    fn a_flat_window_needs_one_sample() {
        let luma = [0.5; 5];
        for m in 2..=4 {
            assert_eq!(sample_count(&flat(3.0, m), &luma, m, &AdaptiveSettings::default(), BOTH), 1);
        }
    }

    #[test]
    fn variance_survives_large_depths() {
        // At depth 1e9, d² is 1e18 and f64 resolves it only to 128: E[d²] − E[d]² loses the
        // 0.25 of a ±0.5 split entirely, the two-pass variance keeps it exactly.
        let mut window = flat(1e9, 2);
        window[0].depth += 0.5;
        window[1].depth += 0.5;
        window[2].depth -= 0.5;
        window[3].depth -= 0.5;
        let (variance, _) = geometry_metric(&window, DepthMetric::World);
        assert_eq!(variance, 0.25);
        let naive = window.iter().map(|s| s.depth * s.depth).sum::<f64>() / 4.0
            - (window.iter().map(|s| s.depth).sum::<f64>() / 4.0).powi(2);
        assert!(
            (naive - 0.25).abs() > 0.1,
            "the naive formula should show the cancellation this guards against: {naive}"
        );
    }

    #[test]
    fn the_relative_depth_metric_ignores_the_scenes_unit() {
        let window = |scale: f64| -> Vec<WindowSample> {
            [4.0, 4.2, 5.0, 9.0]
                .map(|d| WindowSample { depth: d * scale, normal: [0.0, 0.0, 1.0], covered: true })
                .to_vec()
        };
        let metre = geometry_metric(&window(1.0), DepthMetric::Relative).0;
        for scale in [1e-3, 1e3, 1e6] {
            let scaled = geometry_metric(&window(scale), DepthMetric::Relative).0;
            assert!((scaled / metre - 1.0).abs() < 1e-12, "×{scale}: {scaled} vs {metre}");
            let world = geometry_metric(&window(scale), DepthMetric::World).0;
            let world_metre = geometry_metric(&window(1.0), DepthMetric::World).0;
            assert!((world / world_metre / (scale * scale) - 1.0).abs() < 1e-9);
        }
    }

    #[test]
    fn opposite_normals_give_the_widest_cone_not_nan() {
        let mut window = flat(1.0, 2);
        window[1].normal = [0.0, 0.0, -1.0];
        window[3].normal = [0.0, 0.0, -1.0];
        let (_, cone) = geometry_metric(&window, DepthMetric::World);
        assert_eq!(cone, 1.0);
    }

    #[test]
    fn degenerate_and_slightly_long_normals_stay_finite() {
        let mut window = flat(1.0, 2);
        window[0].normal = [0.0, 0.0, 0.0];
        window[1].normal = [0.0, 0.0, 1.0 + 1e-7];
        let (variance, cone) = geometry_metric(&window, DepthMetric::World);
        assert!(variance.is_finite() && cone.is_finite(), "{variance} {cone}");
        // A normal a hair longer than 1 must not push 1 − |n̄·n| below zero into sqrt.
        let mut window = flat(1.0, 2);
        window[2].normal = [0.0, 1e-9, 1.0 + 1e-6];
        assert!(geometry_metric(&window, DepthMetric::World).1 >= 0.0);
    }

    #[test]
    fn silhouettes_against_the_background_take_every_sample() {
        let mut window = flat(2.0, 3);
        window[4].covered = false;
        assert_eq!(sample_count(&window, &[0.0; 5], 3, &AdaptiveSettings::default(), BOTH), 9);
        let empty = vec![WindowSample { depth: 0.0, normal: [0.0; 3], covered: false }; 9];
        assert_eq!(sample_count(&empty, &[0.0; 5], 3, &AdaptiveSettings::default(), BOTH), 1);
    }

    #[test]
    fn shading_metric_respects_both_thresholds() {
        let settings = AdaptiveSettings::default();
        // Range 0.02 is below t_min = 1/32.
        assert_eq!(shading_metric(&[0.5, 0.52, 0.5, 0.5, 0.5], &settings), 0.0);
        // Range 0.1 is below l_max · t_edge = 0.9 · 1/8.
        assert_eq!(shading_metric(&[0.8, 0.9, 0.8, 0.8, 0.8], &settings), 0.0);
        // Range 0.5 counts.
        assert_eq!(shading_metric(&[0.0, 0.5, 0.0, 0.0, 0.0], &settings), 0.5);
        // A lone bright centre counts too.
        assert_eq!(shading_metric(&[1.0, 0.0, 0.0, 0.0, 0.0], &settings), 1.0);
    }

    #[test]
    fn footprint_matches_the_reference_at_full_sampling() {
        for m in 2..=4 {
            assert_eq!(footprint(m, m * m), 1.0);
            assert!(footprint(m, 1) < f64::from(m));
        }
        assert!((footprint(4, 1) - 8.5f64.sqrt()).abs() < 1e-12);
    }

    #[test]
    fn luma_clamps_and_takes_the_square_root() {
        assert_eq!(metric_luma([1.0, 1.0, 1.0], 1.0), 1.0);
        assert_eq!(metric_luma([8.0, 8.0, 8.0], 1.0), 1.0);
        assert_eq!(metric_luma([0.25, 0.25, 0.25], 1.0), 0.5);
        assert_eq!(metric_luma([0.5, 0.5, 0.5], 0.5), 0.5);
        assert_eq!(metric_luma([-1.0, 0.0, 0.0], 1.0), 0.0);
    }

    #[test]
    fn counts_are_clamped_to_the_window() {
        assert_eq!(clamp_count(0.0, 16), 1);
        assert_eq!(clamp_count(0.49, 16), 1);
        assert_eq!(clamp_count(0.5, 16), 2);
        assert_eq!(clamp_count(1e30, 16), 16);
        assert_eq!(clamp_count(f64::INFINITY, 4), 4);
        assert_eq!(clamp_count(f64::NAN, 9), 9);
    }

    #[test]
    fn silhouettes_take_every_sample_even_with_zero_constants() {
        // 0 · ∞ is NaN, which a max() fold would silently drop; the GPU returns "all samples"
        // before applying any constant, and so must the twin.
        let mut window = flat(2.0, 2);
        window[1].covered = false;
        let settings = AdaptiveSettings { c_depth: 0.0, c_normal: 0.0, ..Default::default() };
        let geometry = MetricSet { geometry: true, shading: false };
        assert_eq!(metric_k(&window, &[0.0; 5], 2, &settings, geometry), f64::INFINITY);
        assert_eq!(sample_count(&window, &[0.0; 5], 2, &settings, BOTH), 4);
    }

    #[test]
    fn force_all_samples_overrides_the_metrics() {
        let settings = AdaptiveSettings { force_all_samples: true, ..Default::default() };
        assert_eq!(sample_count(&flat(1.0, 4), &[0.0; 5], 4, &settings, BOTH), 16);
    }

    #[test]
    fn ablations_use_one_metric_each() {
        let mut window = flat(1.0, 2);
        window[0].depth = 2.0;
        let luma = [0.5; 5];
        let settings = AdaptiveSettings::default();
        let geometry_only = MetricSet { geometry: true, shading: false };
        let shading_only = MetricSet { geometry: false, shading: true };
        assert!(sample_count(&window, &luma, 2, &settings, geometry_only) > 1);
        assert_eq!(sample_count(&window, &luma, 2, &settings, shading_only), 1);
    }
}
