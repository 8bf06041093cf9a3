//! The foundation's invariants, on lavapipe: the supersampling path at M = 1 is the deferred
//! path, flat surfaces do not change with M, edges blend only when supersampled, renders are
//! deterministic, and the G-buffer really is written.
//!
//! Stalled modes render the same image as their plain twins, and a stall longer than
//! lavapipe's loop limit still runs every step. The ground truth rendered in one tile is
//! reference-4x4 bit for bit, rendered in bands it shows no seams, and at 8×8 it is nearer
//! reference-4x4 than reference-2x2. A scene reuses the pipelines that earlier scenes on the
//! device compiled, and renders the same bits with them.

use crate::support;

use aabench_renderer::scene::generate::Generator;
use aabench_renderer::{ColorSettings, DisplayImage, Gpu, RenderSettings, SceneRenderer};
use support::*;

#[test]
fn reference_1x1_equals_deferred_1x1_bit_for_bit() {
    for generator in [Generator::Specular, Generator::Atrium] {
        let (mut renderer, _gpu) = renderer(generator, &lit(), settings(160, 120));
        let deferred = render(&mut renderer, "deferred-1x1");
        let reference = render(&mut renderer, "reference-1x1");
        assert_eq!(deferred.display, reference.display, "{generator}: display images differ");
        assert_eq!(deferred.hdr, reference.hdr, "{generator}: HDR images differ");
    }
}

#[test]
fn a_flat_untextured_plane_has_one_colour_at_every_m() {
    let (mut renderer, _gpu) = renderer(Generator::Plane, &ambient_only(), settings(96, 64));
    let mut seen = Vec::new();
    for mode in ["deferred-1x1", "reference-2x2", "reference-3x3", "reference-4x4"] {
        let image = render(&mut renderer, mode);
        let colours = colours(&image);
        assert_eq!(colours.len(), 1, "{mode}: {} colours on a flat plane", colours.len());
        seen.push(*colours.first().unwrap());
    }
    assert!(seen.windows(2).all(|w| w[0] == w[1]), "the plane's colour changes with M: {seen:?}");
    // Ambient 1 × albedo 0.6, sRGB-encoded: 0.6 → 203.
    assert_eq!(seen[0], [203, 203, 203]);
}

#[test]
fn an_edge_has_intermediate_values_only_when_supersampled() {
    let (mut renderer, _gpu) = renderer(Generator::Edge, &ambient_only(), settings(96, 64));
    let deferred = render(&mut renderer, "deferred-1x1");
    let flat = colours(&deferred);
    assert_eq!(flat.len(), 2, "one sample per pixel sees either plane: {flat:?}");
    let (dark, light) = (*flat.first().unwrap(), *flat.last().unwrap());
    let is_between = |p: &[u8]| p[0] > dark[0] && p[0] < light[0];
    for m in 2..=4 {
        let image = render(&mut renderer, &format!("reference-{m}x{m}"));
        let bytes = image.display.bytes();
        let rows: Vec<&[u8]> = bytes.chunks_exact(4 * 96).collect();
        let mut blended = 0;
        for row in &rows {
            let pixels: Vec<&[u8]> = row.chunks_exact(4).collect();
            for (x, p) in pixels.iter().enumerate().filter(|(_, p)| is_between(p)) {
                blended += 1;
                // A blended pixel sits on the edge: light on its left, dark on its right.
                let near = |range: std::ops::Range<usize>, colour: [u8; 3]| {
                    range.filter_map(|i| pixels.get(i)).any(|q| q[..3] == colour)
                };
                assert!(
                    near(x.saturating_sub(2)..x, light),
                    "reference-{m}x{m}: blend at x={x} without light to its left"
                );
                assert!(
                    near(x + 1..x + 3, dark),
                    "reference-{m}x{m}: blend at x={x} without dark to its right"
                );
                let _ = p;
            }
        }
        // The edge crosses 64 rows; at M = 2 about half of them blend, more at larger M.
        assert!((28..=3 * 64).contains(&blended), "reference-{m}x{m}: {blended} blended pixels");
    }
}

#[test]
fn renders_are_bit_identical_across_frames_and_renderers() {
    let mode = "reference-2x2-stalled";
    let (mut first, _gpu) = renderer(Generator::Atrium, &lit(), settings(160, 120));
    let prepared = first.prepare(mode.parse().unwrap()).unwrap();
    prepared.render().unwrap();
    let a = prepared.read_images().unwrap();
    prepared.render().unwrap();
    let b = prepared.read_images().unwrap();
    drop(_gpu);
    let (mut second, _gpu) = renderer(Generator::Atrium, &lit(), settings(160, 120));
    let c = render(&mut second, mode);
    assert_eq!(a, b, "two frames of one renderer differ");
    assert_eq!(a, c, "two renderers differ");
}

#[test]
fn the_gbuffer_is_written_and_the_background_is_marked() {
    let (mut renderer, _gpu) = renderer(Generator::Atrium, &lit(), settings(128, 96));
    let prepared = renderer.prepare("reference-2x2".parse().unwrap()).unwrap();
    prepared.render().unwrap();
    let gbuffer = prepared.read_gbuffer().unwrap();
    assert_eq!((gbuffer.width, gbuffer.height), (256, 192));
    let covered: Vec<usize> =
        (0..gbuffer.depth.len()).filter(|&i| gbuffer.normal_material[i][3] >= 0.0).collect();
    let fraction = covered.len() as f64 / gbuffer.depth.len() as f64;
    // The atrium's camera sees sky above the court and geometry everywhere else.
    assert!((0.6..0.99).contains(&fraction), "covered fraction {fraction}");
    for &i in &covered {
        let [x, y, z, material] = gbuffer.normal_material[i];
        let length = (x * x + y * y + z * z).sqrt();
        assert!((length - 1.0).abs() < 2e-3, "sample {i}: normal length {length}");
        assert!(material.fract() == 0.0, "sample {i}: material {material}");
        assert!(gbuffer.depth[i] > 0.05 && gbuffer.depth[i] < 80.0, "sample {i}: depth {}", gbuffer.depth[i]);
    }
    // A pixel whose 2×2 window is all background shows the background radiance.
    let image = prepared.read_images().unwrap();
    let sky = (0..128 * 96)
        .find(|&p| {
            let (x, y) = (2 * (p % 128), 2 * (p / 128));
            [(0, 0), (1, 0), (0, 1), (1, 1)]
                .iter()
                .all(|(dx, dy)| gbuffer.normal_material[(y + dy) * 256 + x + dx][3] < 0.0)
        })
        .expect("some sky");
    // Within one f16 step: lavapipe truncates when it stores f16, where `half` rounds.
    for (c, expected) in image.hdr[4 * sky..4 * sky + 3].iter().zip(lit().background.to_array()) {
        let ulp = half::f16::from_f32(expected).to_f32() * 2f32.powi(-10);
        assert!((c - expected).abs() <= ulp, "sky pixel {sky}: {c} for {expected}");
    }
}

#[test]
fn stalled_modes_render_the_same_image() {
    let (mut renderer, _gpu) = renderer(Generator::Specular, &lit(), settings(128, 96));
    for mode in ["deferred-1x1", "reference-3x3"] {
        let plain = render(&mut renderer, mode);
        let stalled = render(&mut renderer, &format!("{mode}-stalled"));
        assert_eq!(plain.display, stalled.display, "{mode}: the stall changed the image");
    }
}

/// The truth at m = 4 in one tile is reference-4x4 bit for bit. In four bands it differs from
/// it only where samples near an edge flip (fewer than 2% of pixels, no more on the band
/// borders than scattered flips put there, and by at most one sample's share plainly encoded),
/// both plainly encoded and tonemapped with dither, whose grain follows frame positions across
/// tiles. The frame uniforms are restored afterwards.
#[test]
fn the_truth_in_one_tile_is_the_reference_and_its_tiles_do_not_show() {
    // Plain encoding, where one sample's share bounds a pixel's change; then tonemapped and
    // dithered, where the grain must follow frame positions, not tile positions, or every
    // band but the first would differ almost everywhere.
    for color in [ColorSettings::plain(), ColorSettings::default()] {
        let (mut renderer, _gpu) =
            renderer(Generator::Atrium, &lit(), RenderSettings { color, ..settings(96, 64) });
        let reference = render(&mut renderer, "reference-4x4");
        let whole = renderer.render_truth(4, u64::MAX).unwrap();
        assert_eq!(whole.tiles, 1);
        assert_eq!(whole.images.display, reference.display, "one tile must be reference-4x4 bit for bit");
        assert_eq!(whole.images.hdr, reference.hdr);

        // Four bands, each with its own projection. A band's vertices reach the rasterizer's
        // sub-sample grid through other float rounding than the whole frame's, so samples
        // within a rounding error of an edge may flip. The atrium at 96×64 has about 46
        // triangles per pixel, so a few pixels change, by at most one sample's share; seams
        // would change whole rows at the band borders.
        let band_bytes = 16 * 16 * 36 * 96;
        let tiled = renderer.render_truth(4, band_bytes).unwrap();
        assert_eq!(tiled.tiles, 4);
        let pixel = |image: &DisplayImage, p: usize| image.rgba[4 * p..4 * p + 3].to_vec();
        let differing: Vec<usize> = (0..96 * 64)
            .filter(|&p| pixel(&tiled.images.display, p) != pixel(&reference.display, p))
            .collect();
        let at_borders = differing.iter().filter(|&&p| [15, 16, 31, 32, 47, 48].contains(&(p / 96))).count();
        assert!(differing.len() < 96 * 64 / 50, "{} pixels differ", differing.len());
        // The six border rows are 6/64 of the frame: scattered flips put about that share of
        // the differing pixels there (4 of 48 plainly, 5 of 49 tonemapped); a seam puts a
        // whole row of 96.
        let share = differing.len() * 6 / 64;
        assert!(at_borders <= 2 * share + 4, "{at_borders} differing pixels on band borders: a seam");
        if color.tonemap.is_none() {
            assert!(max_step(&tiled.images, &reference) <= 255 / 16 + 4, "more than one sample's share");
        }

        // The frame uniforms are restored: modes rendered afterwards are unchanged.
        assert_eq!(render(&mut renderer, "reference-4x4").display, reference.display);
    }
}

/// Against the 8×8 truth, reference-4x4's squared error is above 0 and below 0.6 ×
/// reference-2x2's.
#[test]
fn the_8x8_truth_is_nearer_to_reference_4x4_than_reference_2x2_is() {
    let (mut renderer, _gpu) = renderer(Generator::Thin, &lit(), settings(96, 64));
    let truth = renderer.render_truth(8, 16 << 20).unwrap();
    assert_eq!((truth.m, truth.images.width, truth.images.height), (8, 96, 64));
    let mse = |image: &aabench_renderer::FrameImages| {
        let sum: f64 = image
            .display
            .rgba
            .iter()
            .zip(&truth.images.display.rgba)
            .map(|(a, b)| (f64::from(*a) - f64::from(*b)).powi(2))
            .sum();
        sum / image.display.rgba.len() as f64
    };
    let (m2, m4) =
        (mse(&render(&mut renderer, "reference-2x2")), mse(&render(&mut renderer, "reference-4x4")));
    assert!(m4 > 0.0, "the truth has more samples than reference-4x4, so it differs");
    assert!(m4 < m2 * 0.6, "reference-4x4 ({m4}) should be much nearer the truth than reference-2x2 ({m2})");
}

/// The stall's hash chain on the CPU: what `stall` in lib/shading.wgsl returns for `texel`.
fn stall_twin(x: u32, y: u32, iterations: u32) -> f32 {
    let mut h = x.wrapping_mul(0x8da6_b343) ^ y.wrapping_mul(0xd816_3841);
    for _ in 0..iterations {
        h = (h ^ (h >> 15)).wrapping_mul(0x2c1b_3c6d);
    }
    (h >> 8) as f32 / 16_777_216.0
}

/// A stall of 100 003 steps, past lavapipe's limit of 65 535 loop iterations, runs every step:
/// each pixel's HDR alpha matches the CPU hash chain within one f16 step, where a chain cut at
/// 65 535 would differ on every pixel but (0, 0), which starts at a fixed point.
#[test]
fn stalls_beyond_lavapipes_loop_limit_are_honoured_step_for_step() {
    // lavapipe ends a shader's loops after 65 535 iterations in all; a stall of 100 003 steps
    // (16 per iteration, 3 alone) must still run every step: the alpha channel of a stalled
    // deferred frame holds the chain's result, which differs at every step count.
    let (width, height) = (8, 6);
    let iterations = 100_003;
    let settings = RenderSettings { stall_iterations: iterations, ..settings(width, height) };
    let (mut renderer, _gpu) = renderer(Generator::Edge, &lit(), settings);
    let image = render(&mut renderer, "deferred-1x1-stalled");
    // The f16 target keeps 11 significant bits, rounded as the rasterizer rounds: a match is
    // within one f16 step, far finer than the chain's jumps from one count to the next.
    let matches = |stored: f32, value: f32| (stored - value).abs() <= value.abs() / 1024.0;
    let mut truncated_would_differ = 0;
    for y in 0..height {
        for x in 0..width {
            let alpha = image.hdr[((y * width + x) * 4 + 3) as usize];
            let expected = stall_twin(x, y, iterations);
            assert!(matches(alpha, expected), "pixel ({x}, {y}): {alpha} vs {expected}");
            truncated_would_differ += usize::from(!matches(alpha, stall_twin(x, y, 65_535)));
        }
    }
    // Pixel (0, 0) starts the chain at 0, a fixed point; every other one tells the counts apart.
    assert_eq!(truncated_would_differ, (width * height - 1) as usize);
}

/// Pipelines outlive their scene: after two scenes, the device holds what both compiled, less
/// the shaders they compose alike; a third scene of the same shaders compiles nothing; and
/// every image is bit for bit what a device that compiled for that scene alone renders.
#[test]
fn a_scene_reuses_the_pipelines_of_the_scenes_before_it_and_renders_the_same_bits() {
    let modes = ["deferred-1x1", "fxaa", "smaa", "msaa-4x", "reference-2x2", "adaptive-2x2"];
    let _guard = gpu();
    let fresh = || std::sync::Arc::new(Gpu::new().expect("a device"));
    let renders = |gpu: &std::sync::Arc<Gpu>, generator: Generator| {
        let (scene, camera) = generated(generator);
        let mut renderer =
            SceneRenderer::new(std::sync::Arc::clone(gpu), &scene, &camera, &lit(), settings(64, 48))
                .unwrap();
        let images: Vec<DisplayImage> =
            modes.iter().map(|mode| render(&mut renderer, mode).display).collect();
        (images, renderer.compiled_pipelines())
    };
    let (plain_alone, plain_compiled) = renders(&fresh(), Generator::Edge);
    let (textured_alone, textured_compiled) = renders(&fresh(), Generator::Atrium);
    let device = fresh();
    let (plain, _) = renders(&device, Generator::Edge);
    let (textured, both) = renders(&device, Generator::Atrium);
    assert!(
        textured_compiled < both && both < plain_compiled + textured_compiled,
        "alone {plain_compiled} and {textured_compiled}, one after the other {both}"
    );
    let (again, compiled_again) = renders(&device, Generator::Edge);
    assert_eq!(compiled_again, both, "the same shaders compiled again");
    assert!(plain == plain_alone && again == plain_alone, "other bits than with pipelines of its own");
    assert!(textured == textured_alone, "other bits than with pipelines of its own");
}
