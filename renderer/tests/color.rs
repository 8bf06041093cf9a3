//! The colour pipeline on lavapipe against its CPU twins (`renderer/src/color.rs`): the tonemap
//! meets its anchors and rises, transfer functions match (PQ its published values), NaN, Inf
//! and negative radiance become defined colours, dither keeps a 3-bit gradient's mean, and
//! FXAA touches only edges and brings an edge nearer its truth.
//!
//! The first tests run the WGSL of `lib/color.wgsl` in a compute shader and compare each value
//! with the twin; the others feed HDR images through a frame's colour passes. The twins' own
//! properties (anchors in f64, bad parameters naming their field, round trips, zero-mean grain)
//! are unit tests in `src/color.rs`, and `tests/properties.rs` checks them over hostile inputs.

use crate::support;

use aabench_renderer::color::{ColorSettings, Dither, Tonemap, Transfer};
use aabench_renderer::scene::generate::Generator;
use aabench_renderer::shaders::{self, Features};
use aabench_renderer::{DisplayImage, RenderSettings};
use support::*;
use wgpu::util::DeviceExt;

/// Evaluates `expression` (WGSL of `x: f32`, giving a vec4<f32>) with lib/color.wgsl's
/// functions and `constants`, once per input, in a compute shader.
fn evaluate(expression: &str, inputs: &[f32], constants: &[(&str, f64)]) -> Vec<[f32; 4]> {
    let (gpu, _guard) = gpu();
    let library = shaders::compose("lib/color.wgsl", Features::default()).expect("lib/color.wgsl");
    let source = format!(
        "{library}
@group(0) @binding(0) var<storage, read> inputs: array<f32>;
@group(0) @binding(1) var<storage, read_write> outputs: array<vec4<f32>>;
@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {{
    if id.x < arrayLength(&inputs) {{
        let x = inputs[id.x];
        outputs[id.x] = {expression};
    }}
}}"
    );
    let device = &gpu.device;
    let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
        label: Some("color test"),
        source: wgpu::ShaderSource::Wgsl(source.into()),
    });
    let pipeline = device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
        label: Some("color test"),
        layout: None,
        module: &module,
        entry_point: Some("main"),
        compilation_options: wgpu::PipelineCompilationOptions { constants, ..Default::default() },
        cache: None,
    });
    let input = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
        label: None,
        contents: bytemuck::cast_slice(inputs),
        usage: wgpu::BufferUsages::STORAGE,
    });
    let bytes = 16 * inputs.len() as u64;
    let output = device.create_buffer(&wgpu::BufferDescriptor {
        label: None,
        size: bytes,
        usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
        mapped_at_creation: false,
    });
    let readback = device.create_buffer(&wgpu::BufferDescriptor {
        label: None,
        size: bytes,
        usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    });
    let group = device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: None,
        layout: &pipeline.get_bind_group_layout(0),
        entries: &[
            wgpu::BindGroupEntry { binding: 0, resource: input.as_entire_binding() },
            wgpu::BindGroupEntry { binding: 1, resource: output.as_entire_binding() },
        ],
    });
    let mut encoder = device.create_command_encoder(&Default::default());
    {
        let mut pass = encoder.begin_compute_pass(&Default::default());
        pass.set_pipeline(&pipeline);
        pass.set_bind_group(0, &group, &[]);
        pass.dispatch_workgroups((inputs.len() as u32).div_ceil(64), 1, 1);
    }
    encoder.copy_buffer_to_buffer(&output, 0, &readback, 0, bytes);
    gpu.queue.submit([encoder.finish()]);
    readback.slice(..).map_async(wgpu::MapMode::Read, |_| {});
    device.poll(wgpu::PollType::wait_indefinitely()).expect("poll");
    let values: Vec<f32> =
        bytemuck::cast_slice(&readback.slice(..).get_mapped_range().expect("mapped")).to_vec();
    values.chunks_exact(4).map(|v| [v[0], v[1], v[2], v[3]]).collect()
}

fn tonemap_constants(tonemap: &Tonemap) -> Vec<(&'static str, f64)> {
    let curve = tonemap.curve().expect("a valid curve");
    vec![
        ("CONTRAST", curve.contrast),
        ("SHOULDER", curve.shoulder),
        ("CURVE_B", curve.b),
        ("CURVE_C", curve.c),
        ("HDR_MAX", tonemap.hdr_max),
        ("CROSSTALK", tonemap.crosstalk),
        ("SATURATION", tonemap.saturation),
        ("CROSS_SATURATION", tonemap.cross_saturation),
    ]
}

/// For the default curve and a darker, higher-contrast one, the GPU maps mid_in to mid_out and
/// hdr_max to 1 within 10⁻⁶, never falls over 4097 points of [0, hdr_max], matches the twin on
/// grey within 2·10⁻⁶ and on colour within 10⁻⁵.
#[test]
fn the_tonemap_meets_its_anchors_rises_and_matches_its_twin() {
    let defaults = Tonemap::default();
    let darker = Tonemap { mid_out: 0.18 / 3f64.exp(), contrast: 1.6, ..defaults };
    for tonemap in [defaults, darker] {
        let curve = tonemap.curve().unwrap();
        let sweep: Vec<f32> = (0..=4096).map(|i| i as f32 / 4096.0 * 64.0).collect();
        let inputs = [&[0.18f32, 64.0][..], &sweep].concat();
        let constants = tonemap_constants(&tonemap);
        let grey = evaluate("vec4<f32>(tonemap_rgb(vec3<f32>(x)), 0.0)", &inputs, &constants);
        let mid = f64::from(grey[0][0]);
        assert!((mid - tonemap.mid_out).abs() < 1e-6, "{tonemap:?}: mid_in → {mid}");
        assert!((f64::from(grey[1][0]) - 1.0).abs() < 1e-6, "{tonemap:?}: hdr_max → {}", grey[1][0]);
        for (pair, x) in grey[2..].windows(2).zip(&sweep) {
            assert!(pair[1][0] >= pair[0][0], "{tonemap:?}: falls after {x}: {pair:?}");
        }
        for (out, &x) in grey[2..].iter().zip(&sweep) {
            let twin = curve.apply(f64::from(x));
            assert!((f64::from(out[0]) - twin).abs() < 2e-6, "{tonemap:?} at {x}: {} vs {twin}", out[0]);
        }
        // Colour: the largest channel follows the curve, the ratio is kept below the top
        // stop and pushed towards white near it.
        let coloured =
            evaluate("vec4<f32>(tonemap_rgb(vec3<f32>(x, 0.5 * x, 0.1 * x)), 0.0)", &sweep, &constants);
        for (out, &x) in coloured.iter().zip(&sweep) {
            let x = f64::from(x);
            let twin = tonemap.apply(&curve, [x, 0.5 * x, 0.1 * x]);
            for c in 0..3 {
                assert!(
                    (f64::from(out[c]) - twin[c]).abs() < 1e-5,
                    "{tonemap:?} at {x}: {out:?} vs {twin:?}"
                );
            }
        }
    }
}

fn transfer_constants(transfer: Transfer) -> Vec<(&'static str, f64)> {
    vec![("TRANSFER", f64::from(transfer.shader_id())), ("PEAK_FRACTION", transfer.peak_fraction())]
}

/// sRGB, Rec. 709, gamma 2.2 and PQ match their twins within 3·10⁻⁵ over [0, 1]; PQ gives the
/// published 0, 0.5081 (10-bit code 520) and 1 at 0, 100 and 10 000 nits.
#[test]
fn transfer_functions_match_their_twins_and_pq_its_published_values() {
    let sweep: Vec<f32> = (0..=1000).map(|i| i as f32 / 1000.0).collect();
    for transfer in [Transfer::Srgb, Transfer::Rec709, Transfer::Gamma22, Transfer::Pq { peak_nits: 1000.0 }]
    {
        let encoded =
            evaluate("vec4<f32>(transfer_encode(x), 0.0, 0.0, 0.0)", &sweep, &transfer_constants(transfer));
        for (out, &l) in encoded.iter().zip(&sweep) {
            let twin = transfer.encode(f64::from(l));
            assert!((f64::from(out[0]) - twin).abs() < 3e-5, "{transfer:?} at {l}: {} vs {twin}", out[0]);
        }
    }
    // SMPTE ST 2084 at 0, 100 and 10 000 nits: 0, 0.5081 (10-bit code 520), 1.
    let pq = Transfer::Pq { peak_nits: 10_000.0 };
    let published =
        evaluate("vec4<f32>(transfer_encode(x), 0.0, 0.0, 0.0)", &[0.0, 0.01, 1.0], &transfer_constants(pq));
    assert!(published[0][0].abs() < 1e-6, "{published:?}");
    assert!((published[1][0] - 0.508_078).abs() < 1e-4, "{published:?}");
    assert_eq!((published[1][0] * 1023.0).round(), 520.0);
    assert!((published[2][0] - 1.0).abs() < 1e-5, "{published:?}");
}

/// `count` inputs drawn by proptest (deterministically): log-uniform magnitudes from 10⁻³⁰ to
/// 10³⁰ of both signs, with NaN, infinities, zeros and f32's extremes mixed in.
fn sampled_inputs(count: usize) -> Vec<f32> {
    use proptest::prelude::*;
    use proptest::strategy::ValueTree;
    let value = prop_oneof![
        6 => (-30.0f32..30.0, any::<bool>()).prop_map(|(e, negative)| if negative { -(10f32.powf(e)) } else { 10f32.powf(e) }),
        1 => prop_oneof![Just(0.0f32), Just(-0.0), Just(f32::NAN), Just(f32::INFINITY), Just(f32::NEG_INFINITY), Just(f32::MAX), Just(f32::MIN_POSITIVE)],
    ];
    let mut runner = proptest::test_runner::TestRunner::deterministic();
    prop::collection::vec(value, count).new_tree(&mut runner).expect("inputs").current()
}

/// 4096 proptest draws (magnitudes from 10⁻³⁰ to 10³⁰, NaN, infinities, zeros, f32's extremes)
/// agree with the twins through `sanitize`, `exposed` and the tonemap within 2·10⁻⁶, and,
/// folded into [0, 1], through the four transfer functions within 3·10⁻⁵.
#[test]
fn the_gpu_agrees_with_the_twins_on_sampled_hostile_inputs() {
    let inputs = sampled_inputs(4096);
    let tonemap = Tonemap::default();
    let curve = tonemap.curve().unwrap();
    // The tonemap pass's path: sanitize and expose, then the curve.
    let out = evaluate(
        "vec4<f32>(tonemap_rgb(exposed(vec3<f32>(x), 1.0)), 0.0)",
        &inputs,
        &tonemap_constants(&tonemap),
    );
    for (out, &x) in out.iter().zip(&inputs) {
        let twin = tonemap.apply(&curve, [aabench_renderer::color::sanitize(f64::from(x)); 3]);
        assert!((f64::from(out[0]) - twin[0]).abs() < 2e-6, "tonemap at {x}: {} vs {}", out[0], twin[0]);
    }
    // Transfer functions on the same draws folded into [0, 1] (the display pass clamps first).
    let unit: Vec<f32> = inputs.iter().map(|x| if x.is_finite() { x.abs().fract() } else { 0.5 }).collect();
    for transfer in [Transfer::Srgb, Transfer::Rec709, Transfer::Gamma22, Transfer::Pq { peak_nits: 400.0 }] {
        let encoded =
            evaluate("vec4<f32>(transfer_encode(x), 0.0, 0.0, 0.0)", &unit, &transfer_constants(transfer));
        for (out, &l) in encoded.iter().zip(&unit) {
            let twin = transfer.encode(f64::from(l));
            assert!((f64::from(out[0]) - twin).abs() < 3e-5, "{transfer:?} at {l}: {} vs {twin}", out[0]);
        }
    }
}

/// NaN, −Inf, negatives and −0 become 0; +Inf and overflow become 65504, the largest f16.
#[test]
fn sanitize_replaces_nan_infinities_and_negatives() {
    let inputs = [f32::NAN, -f32::NAN, f32::INFINITY, f32::NEG_INFINITY, -1.0, -0.0, 2.5, 1e30];
    let out = evaluate("vec4<f32>(sanitize(x), 0.0, 0.0, 0.0)", &inputs, &[]);
    let got: Vec<f32> = out.iter().map(|v| v[0]).collect();
    assert_eq!(got, vec![0.0, 0.0, 65504.0, 0.0, 0.0, 0.0, 2.5, 65504.0]);
}

/// A small renderer whose colour passes tests feed directly.
fn color_renderer(
    color: ColorSettings,
) -> (aabench_renderer::SceneRenderer, std::sync::MutexGuard<'static, ()>) {
    renderer(Generator::Plane, &ambient_only(), RenderSettings { color, ..settings(16, 8) })
}

/// `hdr` encoded by `mode`'s colour passes.
fn encode(renderer: &mut aabench_renderer::SceneRenderer, mode: &str, hdr: &[[f32; 4]]) -> DisplayImage {
    let prepared = renderer.prepare(mode.parse().unwrap()).unwrap();
    prepared.render().unwrap();
    prepared.display_from_hdr(hdr).unwrap()
}

/// What the shader's `sanitize` makes of a value, as the HDR target stores it.
fn sanitized(v: f32) -> f32 {
    let v = half::f16::from_f32(v).to_f32();
    if v.is_nan() || v == f32::NEG_INFINITY { 0.0 } else { v.clamp(0.0, 65504.0) }
}

/// NaN, ±Inf and negatives injected into the HDR image give exactly the image of the
/// CPU-sanitized input, tonemapped and LDR, through deferred and FXAA modes, and every code is
/// within 1 of the twin's. +Inf red is full red in an LDR scene and white past the tonemap's
/// top.
#[test]
fn nan_inf_and_negative_hdr_values_display_as_their_sanitized_colours() {
    let specials = [
        [f32::NAN, 0.5, 0.5, 1.0],
        [f32::INFINITY, 0.0, 0.0, 1.0],
        [f32::NEG_INFINITY, 0.3, 0.3, 1.0],
        [-1.0, -1.0, -1.0, 1.0],
        [f32::NAN, f32::NAN, f32::NAN, f32::NAN],
        [1e9, 2.0, 0.1, 1.0],
    ];
    let hdr: Vec<[f32; 4]> = (0..16 * 8)
        .map(|p| if p % 7 == 3 { specials[p / 7 % specials.len()] } else { [0.2, 0.25, 0.3, 1.0] })
        .collect();
    let clean: Vec<[f32; 4]> = hdr.iter().map(|t| t.map(sanitized)).collect();
    let hdr_scene = ColorSettings { dither: Dither::Off, ..ColorSettings::default() };
    for color in [hdr_scene, ColorSettings::plain()] {
        let (mut renderer, _gpu) = color_renderer(color);
        for mode in ["deferred-1x1", "fxaa"] {
            // Every pass after the first sees only sanitized values: fed the values the CPU
            // sanitized, the frame gives the same bits, FXAA's neighbourhoods included.
            let dirty = encode(&mut renderer, mode, &hdr);
            let expected = encode(&mut renderer, mode, &clean);
            assert_eq!(dirty, expected, "{mode}, tonemap {}", color.tonemap.is_some());
        }
        // And the colours are the CPU twin's, NaN black.
        let image = encode(&mut renderer, "deferred-1x1", &hdr);
        for (p, texel) in clean.iter().enumerate() {
            let linear = match &color.tonemap {
                Some(tonemap) => {
                    tonemap.apply(&tonemap.curve().unwrap(), [0, 1, 2].map(|c| f64::from(texel[c])))
                }
                None => [0, 1, 2].map(|c| f64::from(texel[c])),
            };
            for (c, &value) in linear.iter().enumerate() {
                let code = color.quantize(value, 0.0);
                let got = image.rgba[4 * p + c];
                assert!(got.abs_diff(code) <= 1, "pixel {p} channel {c}: {got} for {code} ({:?})", hdr[p]);
            }
        }
        // Pixel 10 holds +Inf red: full red in an LDR scene; white past the tonemap's top,
        // where crosstalk takes every channel to the peak.
        let inf_red = if color.tonemap.is_some() { [255; 3] } else { [255, 0, 0] };
        assert_eq!(image.rgba[40..43], inf_red, "+Inf red");
    }
}

/// Mean linear light of codes up to `max`.
fn mean_of_codes(codes: impl Iterator<Item = u16>, transfer: Transfer, max: f64) -> f64 {
    let (mut sum, mut n) = (0.0, 0.0);
    for code in codes {
        sum += transfer.decode(f64::from(code) / max);
        n += 1.0;
    }
    sum / n
}

/// A gradient dithered to 3 bits keeps its mean linear light within 1% in sRGB, Rec. 709 and
/// gamma 2.2, where rounding alone is off by more than twice as much; PQ is held to 1% at 5
/// bits with asymmetric grain. The GPU's codes equal the twin's on at least 99% of pixels.
#[test]
fn dithering_a_gradient_to_a_few_bits_keeps_its_mean() {
    let (width, height) = (256u32, 16u32);
    let gradient: Vec<f32> = (0..width * height)
        .map(|p| half::f16::from_f32((p % width) as f32 / (width - 1) as f32).to_f32())
        .collect();
    let mean = gradient.iter().map(|&v| f64::from(v)).sum::<f64>() / gradient.len() as f64;
    let pixel = |p: usize| (p as u32 % width, p as u32 / width);
    // PQ spends most of its codes above a 400-nit display's peak: at 3 bits only five codes
    // are left below it, too few for grain of any shape (the twin's mean is 4 % off), so it is
    // held to 1 % at 5 bits, where the slides show it.
    for (transfer, dither, bits) in [
        (Transfer::Srgb, Dither::Symmetric, 3),
        (Transfer::Rec709, Dither::Symmetric, 3),
        (Transfer::Gamma22, Dither::Symmetric, 3),
        (Transfer::Pq { peak_nits: 400.0 }, Dither::Asymmetric, 5),
    ] {
        let color = ColorSettings { tonemap: None, transfer, bits, dither };
        let max = f64::from(color.max_code());
        // The CPU twin, and without dither for contrast: plain rounding moves the mean more.
        let twin = |dither: Dither| {
            let color = ColorSettings { dither, ..color };
            gradient.iter().enumerate().map(move |(p, &v)| {
                let (x, y) = pixel(p);
                color.quantize(f64::from(v), color.grain(x, y, 0))
            })
        };
        let dithered = (mean_of_codes(twin(dither), transfer, max) / mean - 1.0).abs();
        assert!(dithered < 0.01, "{transfer:?}: the twin's mean is off by {dithered}");
        let rounded = (mean_of_codes(twin(Dither::Off), transfer, max) / mean - 1.0).abs();
        if bits == 3 {
            assert!(rounded > 2.0 * dithered, "{transfer:?}: rounding alone is off by only {rounded}");
        }

        let (mut renderer, _gpu) =
            renderer(Generator::Plane, &ambient_only(), RenderSettings { color, ..settings(width, height) });
        let hdr: Vec<[f32; 4]> = gradient.iter().map(|&v| [v, v, v, 1.0]).collect();
        let image = encode(&mut renderer, "deferred-1x1", &hdr);
        let codes: Vec<u16> =
            image.rgba.chunks_exact(4).map(|t| (f64::from(t[0]) / 255.0 * max).round() as u16).collect();
        let gpu_mean = mean_of_codes(codes.iter().copied(), transfer, max);
        assert!((gpu_mean / mean - 1.0).abs() < 0.01, "{transfer:?}: GPU mean {gpu_mean} for {mean}");
        let agree = codes.iter().zip(twin(dither)).filter(|(a, b)| **a == *b).count();
        assert!(
            agree * 100 >= codes.len() * 99,
            "{transfer:?}: GPU and twin agree on {agree} of {}",
            codes.len()
        );
    }
}

/// Rec. 601 luma of an 8-bit pixel, as FXAA computes it.
fn luma(image: &DisplayImage, width: usize, x: usize, y: usize) -> f64 {
    let p = &image.rgba[4 * (y * width + x)..];
    (0.299 * f64::from(p[0]) + 0.587 * f64::from(p[1]) + 0.114 * f64::from(p[2])) / 255.0
}

/// On the edge scene at 96×64, FXAA changes only pixels that pass its own edge test (more than
/// 32 of them, under a tenth of the frame) and brings the image nearer its 8×8 truth: its
/// squared error is below 0.8 × deferred-1x1's.
#[test]
fn fxaa_changes_only_edge_pixels_and_brings_an_edge_nearer_its_truth() {
    let (width, height) = (96usize, 64usize);
    let (mut renderer, _gpu) = renderer(Generator::Edge, &lit(), settings(width as u32, height as u32));
    let deferred = render(&mut renderer, "deferred-1x1").display;
    let fxaa = render(&mut renderer, "fxaa").display;
    let mut changed = 0;
    for y in 0..height {
        for x in 0..width {
            let p = 4 * (y * width + x);
            if deferred.rgba[p..p + 3] == fxaa.rgba[p..p + 3] {
                continue;
            }
            changed += 1;
            // FXAA's own early exit: the cross of luma around the pixel must span at least
            // max(EDGE_THRESHOLD_MIN, EDGE_THRESHOLD × its brightest luma).
            let at = |dx: isize, dy: isize| {
                let cx = (x as isize + dx).clamp(0, width as isize - 1) as usize;
                let cy = (y as isize + dy).clamp(0, height as isize - 1) as usize;
                luma(&deferred, width, cx, cy)
            };
            let cross = [at(0, 0), at(1, 0), at(-1, 0), at(0, 1), at(0, -1)];
            let (lo, hi) = cross.iter().fold((f64::MAX, f64::MIN), |(lo, hi), &v| (lo.min(v), hi.max(v)));
            assert!(hi - lo >= 0.0833f64.max(0.166 * hi) - 1e-4, "({x}, {y}) changed off an edge: {cross:?}");
        }
    }
    assert!(changed > height / 2, "FXAA smoothed only {changed} pixels of a {height}-row edge");
    assert!(changed < width * height / 10, "{changed} pixels changed");

    let truth = renderer.render_truth(8, 64 << 20).unwrap().images.display;
    let mse = |image: &DisplayImage| {
        let pairs = image.rgba.iter().zip(&truth.rgba).enumerate().filter(|(i, _)| i % 4 != 3);
        pairs.map(|(_, (a, b))| (f64::from(*a) - f64::from(*b)).powi(2)).sum::<f64>()
    };
    let (before, after) = (mse(&deferred), mse(&fxaa));
    assert!(after < 0.8 * before, "FXAA's error {after} against deferred-1x1's {before}");
}
