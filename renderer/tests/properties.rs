//! Property tests of the CPU twins of the numerics (no device): the adaptive metric, the luma
//! it reads, sanitizing, the tonemap, the transfer functions and quantization, over huge and
//! tiny magnitudes, cancellation, NaN and infinities. No input may panic or leave the
//! documented range. `tests/color.rs` and `tests/adaptive.rs` check the GPU against the same
//! twins.
//!
//! Each property runs 2000 cases over values from 10⁻³⁰⁰ to 10³⁰⁰ of both signs, zeros,
//! subnormals, NaN and ±Inf. The geometry metric stays finite and in range (cone in [0, 1],
//! relative variance ≤ M⁴) or is infinite exactly on silhouettes; the relative depth metric is
//! unchanged by scaling the depths by 10⁻⁶ to 10⁶; sample counts stay in [1, M²] and k is never
//! NaN for any window, luma cross and constants in [0, 10¹²]; the metric luma is in [0, 1] at
//! any exposure; sanitize is finite; the tonemap maps any sanitized radiance into [0, 1] for a
//! range of curves; every transfer function rises and inverts within 10⁻⁹; quantization stays
//! within the codes, and black (and NaN) stays black under any grain.

use aabench_renderer::adaptive::{
    self, AdaptiveSettings, DepthMetric, MAX_METRIC_CONSTANT, MetricSet, WindowSample,
};
use aabench_renderer::color::{self, ColorSettings, Dither, HALF_MAX, Tonemap, Transfer};
use proptest::prelude::*;

/// Any f64 a file or a shader could hand over: ordinary values across 600 orders of magnitude,
/// zeros, subnormals, the extremes, NaN and both infinities.
fn any_value() -> impl Strategy<Value = f64> {
    prop_oneof![
        4 => (-300.0f64..300.0, any::<bool>()).prop_map(|(e, negative)| if negative { -(10f64.powf(e)) } else { 10f64.powf(e) }),
        1 => Just(0.0),
        1 => Just(-0.0),
        1 => Just(f64::MIN_POSITIVE / 4.0),
        1 => Just(f64::MAX),
        1 => Just(f64::NAN),
        1 => Just(f64::INFINITY),
        1 => Just(f64::NEG_INFINITY),
    ]
}

/// Depths as the G-buffer can hold them: between the nearest near plane and the farthest far
/// plane, 1e-6 to 1e12, log-uniform.
fn depth() -> impl Strategy<Value = f64> {
    (-6.0f64..12.0).prop_map(|e| 10f64.powf(e))
}

fn sample() -> impl Strategy<Value = WindowSample> {
    (depth(), [any_value(), any_value(), any_value()], prop::bool::weighted(0.9))
        .prop_map(|(depth, normal, covered)| WindowSample { depth, normal, covered })
}

fn window(m: u32) -> impl Strategy<Value = Vec<WindowSample>> {
    prop::collection::vec(sample(), (m * m) as usize)
}

fn metric() -> impl Strategy<Value = DepthMetric> {
    prop_oneof![Just(DepthMetric::Relative), Just(DepthMetric::World)]
}

fn constant() -> impl Strategy<Value = f32> {
    prop_oneof![Just(0.0f32), Just(MAX_METRIC_CONSTANT), (-3.0f32..12.0).prop_map(|e| 10f32.powf(e))]
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 2000, ..ProptestConfig::default() })]

    #[test]
    fn the_geometry_metric_stays_in_range(m in 2u32..=4, window in window(4), depth_metric in metric()) {
        let window = &window[..(m * m) as usize];
        let (variance, cone) = adaptive::geometry_metric(window, depth_metric);
        let covered = window.iter().filter(|s| s.covered).count();
        if covered == 0 {
            prop_assert_eq!((variance, cone), (0.0, 0.0));
        } else if covered < window.len() {
            prop_assert!(variance == f64::INFINITY && cone == f64::INFINITY);
        } else {
            prop_assert!(variance.is_finite() && variance >= 0.0, "variance {}", variance);
            prop_assert!((0.0..=1.0).contains(&cone), "cone {}", cone);
            if depth_metric == DepthMetric::Relative {
                // Var(d)/E[d]² ≤ (max/mean − 1)² < n² for positive depths.
                prop_assert!(variance <= f64::from(m * m * m * m));
            }
        }
    }

    #[test]
    fn the_relative_depth_metric_is_unchanged_by_the_scenes_unit(
        depths in prop::collection::vec(depth(), 16),
        exponent in -6i32..=6,
    ) {
        let window = |scale: f64| -> Vec<WindowSample> {
            depths.iter().map(|&d| WindowSample { depth: d * scale, normal: [0.0, 0.0, 1.0], covered: true }).collect()
        };
        let base = adaptive::geometry_metric(&window(1.0), DepthMetric::Relative).0;
        let scaled = adaptive::geometry_metric(&window(10f64.powi(exponent)), DepthMetric::Relative).0;
        prop_assert!((scaled - base).abs() <= 1e-9 * base.max(1e-300), "{} vs {}", scaled, base);
    }

    #[test]
    fn sample_counts_stay_in_the_window_whatever_the_inputs(
        m in 2u32..=4,
        window in window(4),
        luma in [any_value(), any_value(), any_value(), any_value(), any_value()],
        (c_depth, c_normal, c_shading) in (constant(), constant(), constant()),
        depth_metric in metric(),
    ) {
        let window = &window[..(m * m) as usize];
        let settings = AdaptiveSettings { depth_metric, c_depth, c_normal, c_shading, ..AdaptiveSettings::default() };
        for metrics in [(true, true), (true, false), (false, true)] {
            let metrics = MetricSet { geometry: metrics.0, shading: metrics.1 };
            let n = adaptive::sample_count(window, &luma, m, &settings, metrics);
            prop_assert!((1..=m * m).contains(&n), "{} samples", n);
            prop_assert!(!adaptive::metric_k(window, &luma, m, &settings, metrics).is_nan());
        }
    }

    #[test]
    fn the_metric_luma_is_in_the_unit_interval(rgb in [any_value(), any_value(), any_value()], stops in -40.0f64..40.0) {
        let luma = adaptive::metric_luma(rgb, 2f64.powf(stops));
        prop_assert!((0.0..=1.0).contains(&luma), "{}", luma);
    }

    #[test]
    fn sanitize_gives_a_finite_radiance(x in any_value()) {
        let y = color::sanitize(x);
        prop_assert!((0.0..=HALF_MAX).contains(&y), "{} → {}", x, y);
    }

    #[test]
    fn the_tonemap_maps_any_sanitized_radiance_into_the_display(
        rgb in [any_value(), any_value(), any_value()],
        contrast in 1.0f64..1.8,
        mid_out in 0.1f64..0.3,
    ) {
        let tonemap = Tonemap { contrast, mid_out, ..Tonemap::default() };
        let curve = tonemap.curve().expect("a rising curve");
        let out = tonemap.apply(&curve, rgb.map(color::sanitize));
        prop_assert!(out.iter().all(|c| (0.0..=1.0 + 1e-12).contains(c)), "{:?} → {:?}", rgb, out);
    }

    #[test]
    fn transfer_functions_rise_and_invert(x in 0.0f64..=1.0, y in 0.0f64..=1.0, peak in 80.0f64..10_000.0) {
        for transfer in [Transfer::Srgb, Transfer::Rec709, Transfer::Gamma22, Transfer::Pq { peak_nits: peak }] {
            let (ex, ey) = (transfer.encode(x), transfer.encode(y));
            prop_assert!((0.0..=1.0).contains(&ex), "{:?}({}) = {}", transfer, x, ex);
            if x <= y {
                prop_assert!(ex <= ey + 1e-15, "{:?} falls between {} and {}", transfer, x, y);
            }
            let back = transfer.decode(ex);
            prop_assert!((back - x).abs() <= 1e-9, "{:?}: {} → {} → {}", transfer, x, ex, back);
        }
    }

    #[test]
    fn quantization_stays_within_the_codes(linear in any_value(), grain in -1.0f64..=1.0, ten_bits in any::<bool>()) {
        for dither in [Dither::Off, Dither::Symmetric, Dither::Asymmetric] {
            let settings = ColorSettings { bits: if ten_bits { 10 } else { 8 }, dither, ..ColorSettings::default() };
            let code = settings.quantize(linear, grain);
            prop_assert!(code <= settings.max_code(), "{} → {}", linear, code);
            if linear <= 0.0 || linear.is_nan() {
                prop_assert_eq!(code, 0, "black (and NaN) stays black under any grain");
            }
        }
    }
}
