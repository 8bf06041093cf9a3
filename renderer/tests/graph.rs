//! Every (scene, mode) graph compiles, binds every shader binding to a resource of the right
//! kind (checked against naga's reflection of the WGSL when each pass is built), reaches the
//! allocation's lower bound, and has only the passes its scene needs.
//!
//! The pool shares allocations between modes, an untextured scene allocates no texture array,
//! and shadowed frames are bit-identical across repetitions and renderers. The compiler's own
//! rules (sharing, usage flags, rejected graphs, order) are unit tests without a device in
//! `src/graph/tests.rs`; a swapped or mistyped binding is refused in a unit test of
//! `src/bindings.rs`.

use crate::support;

use aabench_renderer::scene::generate::Generator;
use aabench_renderer::scene::{Light, LightKind, Lighting, Shadow};
use aabench_renderer::{
    AdaptiveSettings, ColorSettings, Counts, ExtraSamples, Metrics, Mode, Reconstruction, Technique,
};
use glam::Vec3;
use support::*;

/// Every mode the runner knows, plus the adaptive ablations and variants.
fn every_mode() -> Vec<Mode> {
    let mut modes = Mode::baseline_modes();
    modes.extend(Mode::adaptive_modes());
    modes.extend(Mode::ablation_modes());
    modes.extend(Mode::variant_modes());
    modes
}

/// `lit()` with its first light casting a shadow.
pub fn shadowed() -> Lighting {
    let mut lighting = lit();
    lighting.lights[0].shadow = Some(Shadow { resolution: 64, ..Shadow::default() });
    lighting
}

/// Every mode of five scenes, with and without a shadow light, compiles for LDR at 8 bits
/// with both extra-sample strategies and for HDR at 10 bits with the compact one. Each graph
/// allocates exactly its lower bound, has a shadow pass and cube exactly when a light casts
/// shadows, a tonemap pass exactly in HDR, evaluation passes only in adaptive modes, a resolve
/// pass only in reference modes, and FXAA last in FXAA modes.
#[test]
fn every_mode_of_every_scene_compiles_binds_and_reaches_the_allocation_bound() {
    let scenes =
        [Generator::Thin, Generator::Specular, Generator::ShadowRoom, Generator::Plane, Generator::Edge];
    for generator in scenes {
        for lighting in [lit(), shadowed()] {
            // An LDR scene both ways, an HDR scene (tonemap pass) with the default list.
            let variants = [
                (ExtraSamples::Compact, ColorSettings::plain()),
                (ExtraSamples::Loop, ColorSettings::plain()),
                (ExtraSamples::Compact, ColorSettings { bits: 10, ..ColorSettings::default() }),
            ];
            for (strategy, color) in variants {
                let mut settings = settings(64, 48);
                settings.adaptive = AdaptiveSettings { extra_samples: strategy, ..settings.adaptive };
                settings.color = color;
                let (mut renderer, _gpu) = renderer(generator, &lighting, settings);
                let shadows = renderer.needs().shadows.is_some();
                assert_eq!(shadows, lighting.lights.iter().any(|l| l.shadow.is_some()));
                for mode in every_mode() {
                    let prepared = renderer
                        .prepare(mode)
                        .unwrap_or_else(|e| panic!("{generator} {mode} {strategy:?} shadows {shadows}: {e}"));
                    let graph = prepared.graph();
                    let context = format!("{generator} {mode} {strategy:?}: {graph:?}");
                    assert_eq!(graph.allocated_bytes, graph.lower_bound_bytes, "{context}");
                    assert!(graph.allocated_bytes <= graph.one_per_output_bytes, "{context}");
                    let has = |pass: &str| graph.passes.iter().any(|p| p == pass);
                    assert_eq!(has("shadow"), shadows, "{context}");
                    let cube =
                        graph.allocations.iter().any(|a| a.holds.iter().any(|h| h == "shadow.shadow_cubes"));
                    assert_eq!(cube, shadows, "{context}");
                    let adaptive = matches!(mode.technique, Technique::Adaptive(..));
                    assert_eq!(has("evaluate"), adaptive, "{context}");
                    // `-coverage` lists its samples under either strategy: the list holds their
                    // slopes, which the loop has no room for.
                    let listed = strategy == ExtraSamples::Compact
                        || mode.reconstruction() == aabench_renderer::Reconstruction::Coverage;
                    assert_eq!(has("shade_extra"), adaptive && listed, "{context}");
                    assert_eq!(has("resolve"), mode.technique == Technique::Reference, "{context}");
                    let msaa = mode.technique == Technique::Msaa;
                    for pass in ["msaa_classify", "msaa_samples", "msaa_pixels"] {
                        assert_eq!(has(pass), msaa, "{context}");
                    }
                    assert_eq!(
                        graph.passes.first().map(String::as_str),
                        Some(if shadows { "shadow" } else { "gbuffer" })
                    );
                    assert_eq!(has("tonemap"), color.tonemap.is_some(), "{context}");
                    let last = match mode.technique {
                        Technique::Fxaa => "fxaa",
                        Technique::Smaa => "smaa_blend",
                        _ => "display",
                    };
                    assert_eq!(graph.passes.last().map(String::as_str), Some(last), "{context}");
                }
            }
        }
    }
}

/// The pool holds at least what the largest mode needs and less than half of all modes'
/// allocations together.
#[test]
fn modes_share_their_allocations_through_the_pool() {
    let (mut renderer, _gpu) = renderer(Generator::Specular, &lit(), settings(64, 48));
    let mut each = Vec::new();
    for mode in every_mode() {
        let prepared = renderer.prepare(mode).unwrap();
        each.push(prepared.graph().allocated_bytes);
    }
    let adaptive = renderer
        .prepare(Mode::new(
            Technique::Adaptive(Metrics::Both, Reconstruction::Equal, Counts::PerFrame),
            2,
            false,
        ))
        .unwrap();
    assert_eq!(
        adaptive.graph().passes,
        ["gbuffer", "shade_first", "evaluate", "compact", "shade_extra", "gather", "display"]
    );
    // Modes run one at a time, so the pool holds what the largest needs per descriptor, far
    // less than every mode's own allocations together.
    let pooled = renderer.target_bytes();
    let (largest, total) = (*each.iter().max().unwrap(), each.iter().sum::<u64>());
    assert!(
        pooled >= largest && pooled < total / 2,
        "pool {pooled}, largest mode {largest}, all modes {total}"
    );
}

#[test]
fn an_untextured_scene_allocates_no_texture_array() {
    for (generator, textured) in [(Generator::Plane, false), (Generator::ShadowRoom, true)] {
        let (renderer, _gpu) = renderer(generator, &lit(), settings(32, 24));
        assert_eq!(renderer.needs().features.textured, textured, "{generator}");
        assert_eq!(renderer.texture_bytes() > 0, textured, "{generator}");
    }
}

#[test]
fn shadowed_frames_are_bit_identical_across_repetitions_and_renderers() {
    let lighting = Lighting {
        lights: vec![Light {
            kind: LightKind::Point,
            position: Vec3::new(0.0, 3.0, 0.0),
            color: Vec3::ONE,
            intensity: 25.0,
            range: 15.0,
            shadow: Some(Shadow { resolution: 128, ..Shadow::default() }),
        }],
        ..lit()
    };
    let mut first = Vec::new();
    for attempt in 0..2 {
        let (mut renderer, _gpu) = renderer(Generator::ShadowRoom, &lighting, settings(96, 72));
        for mode in ["deferred-1x1", "reference-2x2", "adaptive-2x2"] {
            let prepared = renderer.prepare(mode.parse().unwrap()).unwrap();
            let mut images = Vec::new();
            for _ in 0..2 {
                prepared.render().unwrap();
                images.push(prepared.read_images().unwrap());
            }
            assert_eq!(images[0], images[1], "{mode}: two frames of one renderer differ");
            if attempt == 0 {
                first.push(images.remove(0));
            } else {
                assert_eq!(first.remove(0), images[0], "{mode}: two renderers differ");
            }
        }
    }
}
