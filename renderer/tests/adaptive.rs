//! Adaptive supersampling on lavapipe: where samples go, that the GPU metric is its CPU twin,
//! and that forcing every sample reproduces the reference.
//!
//! Only pixels along an edge get more than one sample; a flat plane, lit or 5 km away, gets
//! one; sample counts stay in [1, M²] with finite output on the generated scenes, under normal
//! and extreme lighting, and at tiny and odd resolutions. The full method takes the larger of
//! its two ablations per pixel, the `-area` variant reweighs only pixels between one sample and
//! all, and the compact and loop strategies agree. The CPU twin's own cases (adversarial
//! windows, zero constants on a silhouette, the area weights' hand-worked values) are unit
//! tests in `src/technique/adaptive/`, and `tests/properties.rs` checks it over hostile inputs.

use crate::support;

use aabench_renderer::adaptive::{self, MetricSet};
use aabench_renderer::scene::generate::Generator;
use aabench_renderer::scene::{Camera, Light, LightKind, Lighting};
use aabench_renderer::{
    AdaptiveSettings, ExtraSamples, FrameImages, GBufferImages, Mode, PreparedMode, SceneRenderer,
};
use glam::{DVec3, Vec3};
use support::*;

fn counts(image: &FrameImages) -> &[u8] {
    image.sample_counts.as_deref().expect("an adaptive mode reads back its sample counts")
}

/// Per pixel, whether more than one material shows among the G-buffer texels of its M×M window
/// widened by `ring` texels on each side: with ring 0, windows the edge runs through; with ring
/// 1, also those it runs along.
fn edge_pixels(gbuffer: &GBufferImages, m: u32, ring: i64) -> Vec<bool> {
    let (gw, gh) = (i64::from(gbuffer.width), i64::from(gbuffer.height));
    let (w, m) = (gw / i64::from(m), i64::from(m));
    (0..(gw / m) * (gh / m))
        .map(|p| {
            let (x0, y0) = ((p % w) * m, (p / w) * m);
            let mut materials = (y0 - ring..y0 + m + ring)
                .flat_map(|y| (x0 - ring..x0 + m + ring).map(move |x| (x, y)))
                .filter(|&(x, y)| (0..gw).contains(&x) && (0..gh).contains(&y))
                .map(|(x, y)| gbuffer.normal_material[(y * gw + x) as usize][3]);
            let first = materials.next().expect("a window");
            materials.any(|material| material != first)
        })
        .collect()
}

/// At 2×2, 3×3 and 4×4, every window the edge runs through gets all M² samples, and any other
/// pixel with more than one lies next to a window along the edge.
#[test]
fn only_pixels_along_a_straight_edge_get_more_than_one_sample() {
    let (mut renderer, _gpu) = renderer(Generator::Edge, &ambient_only(), settings(96, 64));
    for m in 2..=4 {
        let prepared = renderer.prepare(format!("adaptive-{m}x{m}").parse().unwrap()).unwrap();
        prepared.render().unwrap();
        let image = prepared.read_images().unwrap();
        let gbuffer = prepared.read_gbuffer().unwrap();
        let (through, along) = (edge_pixels(&gbuffer, m, 0), edge_pixels(&gbuffer, m, 1));
        // The shading metric looks one pixel further, at the neighbours' colours.
        let near_edge = |p: usize| {
            let (x, y) = ((p % 96) as i64, (p / 96) as i64);
            (-1..=1).any(|dy| {
                (-1..=1).any(|dx| {
                    let (nx, ny) = (x + dx, y + dy);
                    (0..96).contains(&nx) && (0..64).contains(&ny) && along[(ny * 96 + nx) as usize]
                })
            })
        };
        let counts = counts(&image);
        // The edge crosses all 64 rows; at 2×2 it can pass between two windows in some.
        assert!(through.iter().filter(|&&e| e).count() >= 32, "{m}×{m}: too few windows on the edge");
        for (p, &n) in counts.iter().enumerate() {
            if through[p] {
                assert_eq!(u32::from(n), m * m, "{m}×{m}: edge pixel {p} shaded {n} samples");
            } else if n > 1 {
                assert!(near_edge(p), "{m}×{m}: pixel {p}, away from the edge, shaded {n} samples");
            }
        }
    }
}

/// One point light in front of the plane: smooth shading across the image.
fn softly_lit() -> Lighting {
    Lighting {
        lights: vec![Light {
            kind: LightKind::Point,
            position: Vec3::new(0.6, 0.4, 2.0),
            color: Vec3::ONE,
            intensity: 3.0,
            range: 30.0,
            shadow: None,
        }],
        ambient: Vec3::splat(0.05),
        ..ambient_only()
    }
}

/// A flat, smoothly lit plane takes one sample per pixel and stays within one 8-bit step of
/// the reference at every M.
#[test]
fn a_flat_plane_facing_the_camera_takes_one_sample_and_matches_the_reference() {
    let (mut renderer, _gpu) = renderer(Generator::Plane, &softly_lit(), settings(96, 64));
    for m in 2..=4 {
        let adaptive = render(&mut renderer, &format!("adaptive-{m}x{m}"));
        assert!(counts(&adaptive).iter().all(|&n| n == 1), "{m}×{m}: a flat plane got extra samples");
        let reference = render(&mut renderer, &format!("reference-{m}x{m}"));
        assert!(colours(&reference).len() > 20, "the light should shade the plane smoothly");
        assert!(
            max_step(&adaptive, &reference) <= 1,
            "{m}×{m}: {} steps from the reference",
            max_step(&adaptive, &reference)
        );
    }
}

#[test]
fn one_sample_standing_for_its_cell_is_the_deferred_pixel_at_every_m() {
    // S of `-cells` is shaded at the pixel's centre with the pixel's footprint, where the
    // paper's S sits on the window's rank-0 texel: a quarter of a pixel off at 2×2, an eighth
    // at 4×4. On a smoothly lit plane that takes one sample everywhere, the cells variant is
    // then deferred shading itself.
    let (mut renderer, _gpu) = renderer(Generator::Plane, &softly_lit(), settings(96, 64));
    let deferred = render(&mut renderer, "deferred-1x1");
    for m in 2..=4 {
        let cells = render(&mut renderer, &format!("adaptive-{m}x{m}-cells"));
        assert!(counts(&cells).iter().all(|&n| n == 1), "{m}×{m}: a flat plane got extra samples");
        let steps = max_step(&cells, &deferred);
        assert!(steps <= 1, "{m}×{m}: {steps} steps from deferred-1x1");
    }
    // In linear HDR, where a step of the display encoding does not hide it, the paper's S
    // at 2×2 sits a quarter pixel off (which is what the test above could miss).
    let deviation = |image: &FrameImages| -> f64 {
        let rgb = |hdr: &[f32]| hdr.chunks(4).flat_map(|p| p[..3].to_vec()).collect::<Vec<f32>>();
        rgb(&image.hdr).iter().zip(rgb(&deferred.hdr)).map(|(a, b)| f64::from((a - b).abs())).sum()
    };
    let paper = deviation(&render(&mut renderer, "adaptive-2x2"));
    let cells = deviation(&render(&mut renderer, "adaptive-2x2-cells"));
    assert!(paper > 100.0 * cells, "HDR deviation from deferred: paper {paper}, cells {cells}");
}

#[test]
fn forcing_every_sample_under_cells_reproduces_the_reference_within_one_step() {
    let mut forced = settings(128, 96);
    forced.adaptive.force_all_samples = true;
    let (mut renderer, _gpu) = renderer(Generator::Thin, &lit(), forced);
    for m in 2..=4 {
        let cells = render(&mut renderer, &format!("adaptive-{m}x{m}-cells"));
        let reference = render(&mut renderer, &format!("reference-{m}x{m}"));
        let steps = max_step(&cells, &reference);
        assert!(steps <= 1, "{m}×{m}: {steps} steps from the reference");
    }
}

/// With every sample forced, adaptive-MxM is within one step of reference-MxM on the atrium,
/// thin and specular scenes, with both the compact and the loop strategy, at M = 2, 3 and 4.
#[test]
fn forcing_every_sample_reproduces_the_reference_within_one_step() {
    for generator in [Generator::Atrium, Generator::Thin, Generator::Specular] {
        for strategy in [ExtraSamples::Compact, ExtraSamples::Loop] {
            let mut forced = settings(128, 96);
            forced.adaptive =
                AdaptiveSettings { force_all_samples: true, extra_samples: strategy, ..forced.adaptive };
            let (mut renderer, _gpu) = renderer(generator, &lit(), forced);
            for m in 2..=4 {
                let adaptive = render(&mut renderer, &format!("adaptive-{m}x{m}"));
                assert!(counts(&adaptive).iter().all(|&n| u32::from(n) == m * m));
                let reference = render(&mut renderer, &format!("reference-{m}x{m}"));
                let steps = max_step(&adaptive, &reference);
                assert!(steps <= 1, "{generator} {m}×{m} {strategy:?}: {steps} steps from the reference");
            }
        }
    }
}

/// On every generated scene but the gallery, under normal lighting and under a point light of
/// intensity 10⁶, counts stay in [1, M²] and the HDR output is finite.
#[test]
fn sample_counts_stay_in_the_window_on_every_generated_scene() {
    let harsh = Lighting {
        lights: vec![Light {
            kind: LightKind::Point,
            position: Vec3::new(0.0, 1.0, 1.0),
            color: Vec3::ONE,
            intensity: 1e6,
            range: 50.0,
            shadow: None,
        }],
        ..lit()
    };
    // The gallery (a million triangles, no camera) is measured on its own (`docs/own-scene.md`).
    for generator in Generator::ALL.into_iter().filter(|&g| g != Generator::Gallery) {
        for lighting in [lit(), harsh.clone()] {
            let (mut renderer, _gpu) = renderer(generator, &lighting, settings(96, 72));
            for m in 2..=4 {
                let image = render(&mut renderer, &format!("adaptive-{m}x{m}"));
                assert!(
                    counts(&image).iter().all(|&n| n >= 1 && u32::from(n) <= m * m),
                    "{generator} {m}×{m}"
                );
                assert!(image.hdr.iter().all(|v| v.is_finite()), "{generator} {m}×{m}: non-finite HDR");
            }
        }
    }
}

/// Recomputes the count map on the CPU from the G-buffer and S the GPU used.
fn cpu_counts(
    prepared: &PreparedMode,
    m: u32,
    settings: &AdaptiveSettings,
    exposure: f64,
) -> (Vec<f64>, Vec<bool>) {
    let gbuffer = prepared.read_gbuffer().unwrap();
    let first = prepared.read_first().unwrap().expect("S");
    let (w, h) = (gbuffer.width / m, gbuffer.height / m);
    let metrics = MetricSet { geometry: true, shading: true };
    let mut ks = Vec::new();
    let mut ambiguous = Vec::new();
    for p in 0..w * h {
        let (x, y) = (p % w, p / w);
        let window = gbuffer.window(m, x, y);
        let cross = adaptive::luma_cross(&first, w, h, x, y, exposure);
        let k = adaptive::metric_k(&window, &cross, m, settings, metrics);
        // f32 on the GPU, f64 here: results within a hair of a rounding boundary or of the
        // shading threshold may fall either way.
        let l_max = cross.iter().copied().fold(0.0, f64::max);
        let range = l_max - cross.iter().copied().fold(1.0, f64::min);
        let threshold = f64::from(settings.t_min).max(l_max * f64::from(settings.t_edge));
        let near_rounding = k < f64::from(m * m) && ((k - k.floor()) - 0.5).abs() < 1e-3 * k.max(1.0);
        let near_threshold = (range - threshold).abs() < 1e-3;
        ks.push(k);
        ambiguous.push(near_rounding || near_threshold);
    }
    (ks, ambiguous)
}

/// The GPU's sample counts equal the CPU twin's pixel for pixel, leaving out only pixels whose
/// k lies within a rounding hair of a boundary or of the shading threshold (f32 against f64);
/// more than 95% of pixels are checked.
#[test]
fn gpu_sample_counts_match_the_cpu_twin() {
    let base = settings(128, 96);
    let (mut renderer, _gpu) = renderer(Generator::Atrium, &lit(), base.clone());
    for m in 2..=4 {
        let prepared = renderer.prepare(format!("adaptive-{m}x{m}").parse().unwrap()).unwrap();
        prepared.render().unwrap();
        let image = prepared.read_images().unwrap();
        let (ks, ambiguous) = cpu_counts(&prepared, m, &base.adaptive, f64::from(lit().exposure));
        let mut checked = 0;
        for (p, (&n, (&k, &unsure))) in counts(&image).iter().zip(ks.iter().zip(&ambiguous)).enumerate() {
            if unsure {
                continue;
            }
            checked += 1;
            assert_eq!(u32::from(n), adaptive::clamp_count(k, m * m), "{m}×{m}: pixel {p} (k = {k})");
        }
        assert!(checked > 128 * 96 * 95 / 100, "{m}×{m}: only {checked} pixels unambiguous");
        let extra = counts(&image).iter().filter(|&&n| n > 1).count();
        assert!(extra > 500, "{m}×{m}: the atrium should need extra samples somewhere ({extra} pixels)");
    }
}

/// The compact and loop strategies give the same counts and images within one step, for the
/// paper's average, the area-weighted one and the cells variant.
#[test]
fn compact_and_loop_shading_agree_within_one_step() {
    // Both the paper's average and the area-weighted one, whose weights follow each sample's rank.
    for mode in ["adaptive-3x3", "adaptive-4x4-area", "adaptive-2x2-cells"] {
        let mut images = Vec::new();
        for strategy in [ExtraSamples::Compact, ExtraSamples::Loop] {
            let mut s = settings(128, 96);
            s.adaptive.extra_samples = strategy;
            let (mut renderer, _gpu) = renderer(Generator::Atrium, &lit(), s);
            images.push(render(&mut renderer, mode));
        }
        assert_eq!(counts(&images[0]), counts(&images[1]), "{mode}");
        assert!(max_step(&images[0], &images[1]) <= 1, "{mode}");
    }
}

/// The `-area` variant keeps the sample counts, and every pixel of 1 or M² samples bit for bit.
/// Its two-sample pixels at 3×3 equal 7/9·S + 2/9·x, where x is the extra sample recovered
/// from the paper's (S + x) / 2, within f16 precision.
#[test]
fn area_weights_reweigh_only_pixels_between_one_sample_and_all() {
    let (mut renderer, _gpu) = renderer(Generator::Atrium, &lit(), settings(128, 96));
    let paper = render(&mut renderer, "adaptive-3x3");
    let prepared = renderer.prepare("adaptive-3x3-area".parse().unwrap()).unwrap();
    prepared.render().unwrap();
    let area = prepared.read_images().unwrap();
    let first = prepared.read_first().unwrap().unwrap();
    assert_eq!(counts(&paper), counts(&area), "the weights must not move the sample counts");
    let weights = adaptive::area_weights(3);
    let (mut reweighed, mut checked_pairs) = (0, 0);
    for (p, &n) in counts(&area).iter().enumerate() {
        let (a, b) = (&area.hdr[4 * p..4 * p + 3], &paper.hdr[4 * p..4 * p + 3]);
        if n == 1 || n == 9 {
            assert_eq!(a, b, "pixel {p} of {n} samples is averaged alike either way");
            continue;
        }
        reweighed += usize::from(a != b);
        if n == 2 {
            // The paper's pixel is (S + x) / 2, so the one extra sample is x = 2·paper − S, and
            // the area-weighted pixel must be w₀·S + w₁·x with 3×3's two-sample weights.
            checked_pairs += 1;
            for c in 0..3 {
                let s = f64::from(first[p][c]);
                let x = 2.0 * f64::from(b[c]) - s;
                let expected = f64::from(weights[9]) * s + f64::from(weights[10]) * x;
                // f16 storage of S, the paper's pixel and this one.
                let tolerance = 4e-3 * (s.abs() + x.abs()) + 1e-4;
                assert!(
                    (f64::from(a[c]) - expected).abs() <= tolerance,
                    "pixel {p} channel {c}: {} vs {expected}",
                    a[c]
                );
            }
        }
    }
    assert!(reweighed > 100, "area weights should change the lopsided pixels ({reweighed})");
    assert!(checked_pairs > 20, "too few two-sample pixels to check ({checked_pairs})");
}

#[test]
fn the_full_method_takes_the_larger_of_the_two_ablations() {
    let (mut renderer, _gpu) = renderer(Generator::Atrium, &lit(), settings(128, 96));
    let both = render(&mut renderer, "adaptive-3x3");
    let geometry = render(&mut renderer, "adaptive-3x3-geometry");
    let shading = render(&mut renderer, "adaptive-3x3-shading");
    let mut differ = 0;
    for ((&b, &g), &s) in counts(&both).iter().zip(counts(&geometry)).zip(counts(&shading)) {
        // round(max(a, b)) = max(round(a), round(b)): k = max(k_d, k_n, k_s) is per pixel.
        assert_eq!(b, g.max(s));
        differ += usize::from(g != s);
    }
    assert!(differ > 100, "the two metrics should disagree somewhere ({differ} pixels)");
}

/// A slightly tilted plane 5 km away takes one sample per pixel at every M; catastrophic
/// cancellation in the depth variance would give it all of them.
#[test]
fn a_slightly_tilted_plane_five_kilometres_away_needs_no_extra_samples() {
    // True depth spread per pixel is about a centimetre; E[d²] − E[d]² in f32 at 5000 m
    // would return noise of order one (m²) and take every sample.
    let (gpu, _lock) = gpu();
    let (scene, _) = generated(Generator::Plane);
    let camera = Camera {
        near: 1.0,
        far: 10_000.0,
        ..Camera::look_at(DVec3::new(0.0, 50.0, 5000.0), DVec3::ZERO, 1.5)
    };
    let lighting = Lighting { lights: Vec::new(), ..ambient_only() };
    let mut renderer = SceneRenderer::new(gpu, &scene, &camera, &lighting, settings(96, 64)).unwrap();
    for m in 2..=4 {
        let image = render(&mut renderer, &format!("adaptive-{m}x{m}"));
        assert!(counts(&image).iter().all(|&n| n == 1), "{m}×{m}: far plane got extra samples");
        assert_eq!(colours(&image).len(), 1);
    }
}

/// Every mode but the stalled variants renders finite HDR with counts in [1, M²] at 1×1, 2×3
/// and 317×211.
#[test]
fn tiny_and_odd_resolutions_render_every_mode_finite_with_counts_in_the_window() {
    // 1×1 (a single window), 2×3 (smaller than any 4×4 block), 317×211 (odd, prime-ish sides:
    // the compact list's rows and blocks do not divide evenly).
    let mut modes = Mode::baseline_modes();
    modes.extend(Mode::adaptive_modes());
    modes.extend(Mode::ablation_modes());
    modes.extend(Mode::variant_modes().into_iter().filter(|m| !m.stalled));
    for (width, height) in [(1, 1), (2, 3), (317, 211)] {
        let (mut renderer, _gpu) = renderer(Generator::Thin, &lit(), settings(width, height));
        for &mode in &modes {
            let prepared =
                renderer.prepare(mode).unwrap_or_else(|e| panic!("{mode} at {width}×{height}: {e}"));
            prepared.render().unwrap_or_else(|e| panic!("{mode} at {width}×{height}: {e}"));
            let image = prepared.read_images().unwrap();
            assert_eq!((image.width, image.height), (width, height), "{mode}");
            let bad = image.hdr.iter().filter(|v| !v.is_finite()).count();
            assert_eq!(bad, 0, "{mode} at {width}×{height}: non-finite HDR values");
            if let Some(counts) = &image.sample_counts {
                let full = (mode.m * mode.m) as u8;
                assert!(
                    counts.iter().all(|&n| (1..=full).contains(&n)),
                    "{mode} at {width}×{height}: {counts:?}"
                );
            }
        }
    }
}

/// The loop strategy accepts a stall of exactly `loop_stall_limit(4)` at 4×4 and refuses one
/// step more, saying so; the unstalled mode runs either way.
#[test]
fn the_loop_strategy_refuses_a_stall_it_cannot_honour() {
    // Its gather shades up to M² samples in one invocation: lavapipe's 65 535 loop
    // iterations then cover M² stalls, so 4×4 honours at most loop_stall_limit(4).
    let limit = aabench_renderer::loop_stall_limit(4);
    for (stall, ok) in [(limit, true), (limit + 1, false)] {
        let mut base = settings(16, 12);
        base.stall_iterations = stall;
        base.adaptive.extra_samples = ExtraSamples::Loop;
        let (mut renderer, _gpu) = renderer(Generator::Edge, &lit(), base);
        let prepared = renderer.prepare("adaptive-4x4-stalled".parse().unwrap());
        assert_eq!(prepared.is_ok(), ok, "stall {stall}");
        if let Err(error) = prepared {
            assert!(error.to_string().contains(&format!("at most {limit} stall iterations")), "{error}");
        }
        assert!(renderer.prepare("adaptive-4x4".parse().unwrap()).is_ok(), "the unstalled mode runs");
    }
}

#[test]
fn a_frame_too_wide_for_some_m_names_the_largest_m_that_fits_before_allocating() {
    // 4097 × 4 = 16 388 texels, past lavapipe's 16 384; 3 × 4097 fits.
    let (mut renderer, _gpu) = renderer(Generator::Edge, &lit(), settings(4097, 8));
    let error = renderer.prepare("reference-4x4".parse().unwrap()).unwrap_err().to_string();
    assert!(
        error.contains("reference-4x4 at 4097×8") && error.contains("the largest M that fits is 3"),
        "{error}"
    );
    assert_eq!(renderer.target_bytes(), 0, "nothing was allocated");
}

/// Under `-coverage` with the geometry metric alone, a window the edge between two flat,
/// evenly lit surfaces runs through shades one sample per surface, and the pixel is their
/// shades mixed by the share of the window each covers: the reference itself, within one step,
/// at every M.
#[test]
fn coverage_shades_one_sample_per_surface_and_mixes_them_by_coverage() {
    let (mut renderer, _gpu) = renderer(Generator::Edge, &ambient_only(), settings(96, 64));
    for m in 2..=4 {
        let prepared =
            renderer.prepare(format!("adaptive-{m}x{m}-geometry-coverage").parse().unwrap()).unwrap();
        prepared.render().unwrap();
        let coverage = prepared.read_images().unwrap();
        let through = edge_pixels(&prepared.read_gbuffer().unwrap(), m, 0);
        for (p, &n) in counts(&coverage).iter().enumerate() {
            assert_eq!(n, if through[p] { 2 } else { 1 }, "{m}×{m}: pixel {p}");
        }
        let reference = render(&mut renderer, &format!("reference-{m}x{m}"));
        let steps = max_step(&coverage, &reference);
        assert!(steps <= 1, "{m}×{m}: {steps} steps from the reference");
        // The mix is not a blur: the edge keeps intermediate shades, as the reference does.
        assert!(colours(&coverage).len() >= m as usize * m as usize, "{m}×{m}: too few shades on the edge");
    }
}

/// Under ambient light, shading is the albedo times the ambient radiance: a pixel of one
/// surface shaded once and carried to the mean of its samples' albedos is the reference's
/// average of sixteen textured samples. On the texture scene (checkers from magnified to far
/// below a pixel) `-coverage` with the geometry metric shades about one sample per pixel and is
/// within one step of reference-4x4 on all but a few pixels, where the paper's adaptive-4x4
/// (whose samples point-sample the checkers) and `-cells` are not.
#[test]
fn coverage_filters_textures_at_the_references_rate_while_shading_once_per_surface() {
    let (mut renderer, _gpu) = renderer(Generator::Texture, &ambient_only(), settings(128, 96));
    let reference = render(&mut renderer, "reference-4x4");
    let off = |image: &FrameImages| {
        let pixels = image.display.rgba.chunks_exact(4).zip(reference.display.rgba.chunks_exact(4));
        pixels.filter(|(a, b)| a.iter().zip(*b).any(|(x, y)| x.abs_diff(*y) > 1)).count() as f64
            / f64::from(128 * 96)
    };
    let coverage = render(&mut renderer, "adaptive-4x4-geometry-coverage");
    let shaded: u64 = counts(&coverage).iter().map(|&n| u64::from(n)).sum();
    assert!(shaded < 2 * 128 * 96, "{shaded} samples for {} pixels", 128 * 96);
    let (coverage_off, paper_off, cells_off) = (
        off(&coverage),
        off(&render(&mut renderer, "adaptive-4x4")),
        off(&render(&mut renderer, "adaptive-4x4-cells")),
    );
    assert!(
        coverage_off < 0.02,
        "coverage: {:.1}% of pixels off by more than one step",
        100.0 * coverage_off
    );
    assert!(
        paper_off > 5.0 * coverage_off && cells_off > 5.0 * coverage_off,
        "paper {paper_off}, cells {cells_off}"
    );
}

/// A highlight narrower than a pixel can fall between the pixel centres where S is shaded, or
/// saturate S and its neighbours alike: the luma cross then reads the window as flat. The
/// light-aware term of `-cells` and `-coverage` bounds each light's lobe over the pixel, so on
/// the glossy spheres every pixel away from a geometric edge where the reference's highlight
/// differs from deferred shading's by more than eight steps takes more than one sample; the
/// paper's metric, which has only the cross, leaves some of them at one.
#[test]
fn the_light_aware_term_samples_highlights_that_the_luma_cross_misses() {
    let (mut renderer, _gpu) = renderer(Generator::Specular, &lit(), settings(128, 96));
    let deferred = render(&mut renderer, "deferred-1x1");
    let reference = render(&mut renderer, "reference-4x4");
    let prepared = renderer.prepare("adaptive-4x4-cells".parse().unwrap()).unwrap();
    prepared.render().unwrap();
    let cells = prepared.read_images().unwrap();
    let near_edge = edge_pixels(&prepared.read_gbuffer().unwrap(), 4, 1);
    let steps = |p: usize| {
        let (a, b) = (&reference.display.rgba[4 * p..4 * p + 3], &deferred.display.rgba[4 * p..4 * p + 3]);
        a.iter().zip(b).map(|(x, y)| x.abs_diff(*y)).max().unwrap_or(0)
    };
    let highlights: Vec<usize> = (0..128 * 96).filter(|&p| !near_edge[p] && steps(p) > 8).collect();
    assert!(highlights.len() >= 20, "only {} highlight pixels", highlights.len());
    let single = |counts: &[u8]| highlights.iter().filter(|&&p| counts[p] == 1).count();
    let paper = render(&mut renderer, "adaptive-4x4");
    let (cells_single, paper_single) = (single(counts(&cells)), single(counts(&paper)));
    assert_eq!(
        cells_single,
        0,
        "-cells: {cells_single} of {} highlight pixels took one sample",
        highlights.len()
    );
    assert!(paper_single > 0, "the paper's metric sampled every highlight pixel: the test shows nothing");
}

/// With every sample forced, every cell stands for itself and `-coverage` is the reference
/// within one step, lit, with textures and thin geometry.
#[test]
fn forcing_every_sample_under_coverage_reproduces_the_reference_within_one_step() {
    let mut forced = settings(128, 96);
    forced.adaptive.force_all_samples = true;
    let (mut renderer, _gpu) = renderer(Generator::Thin, &lit(), forced);
    for m in 2..=4 {
        let coverage = render(&mut renderer, &format!("adaptive-{m}x{m}-coverage"));
        assert!(counts(&coverage).iter().all(|&n| u32::from(n) == m * m));
        let reference = render(&mut renderer, &format!("reference-{m}x{m}"));
        let steps = max_step(&coverage, &reference);
        assert!(steps <= 1, "{m}×{m}: {steps} steps from the reference");
    }
}
