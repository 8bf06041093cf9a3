//! Where an adaptive mode's extra samples spend their time (`docs/design-notes.md`, "Where the extra-sample
//! cost went"). For each M it renders, interleaved in one process, the reference, the adaptive
//! mode and the adaptive mode with every sample forced into the list, and prints per-pass
//! medians with three per-sample costs:
//!
//! - the reference's cost per sample, over all samples and over the samples that geometry
//!   covers (background samples return early, so the two differ where the sky is large);
//! - the adaptive list's cost per extra sample, and the share of those samples on background;
//! - the forced list's cost per sample: the same samples as the reference, shaded through the
//!   list, so its ratio to the reference is the list's own overhead and nothing else.
//!
//! `cargo run --release --example sample_cost -- scenes/thin.json [quick|nightly] [reps] [M…] [stalled]`

use std::collections::BTreeMap;
use std::path::Path;
use std::sync::Arc;

use aabench::manifest::Manifest;
use aabench::measure::stats::Summary;
use aabench::plan::Tier;
use aabench::run::render_settings;
use aabench::run::scenes;
use aabench_renderer::adaptive::sample_order;
use aabench_renderer::{
    AdaptiveSettings, BACKGROUND_MATERIAL, ExtraSamples, GBufferImages, Gpu, PreparedMode, RenderSettings,
    SceneRenderer,
};
use anyhow::Context;

/// A second shader folder to measure beside the first (A/B).
const VARIANT_VARIABLE: &str = "SAMPLE_COST_VARIANT";

fn main() -> anyhow::Result<()> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let path = args.first().context("usage: sample_cost MANIFEST [quick|nightly] [reps] [M…] [stalled]")?;
    let tier = if args.iter().any(|a| a == "nightly") { Tier::Nightly } else { Tier::Quick };
    let stalled = args.iter().any(|a| a == "stalled");
    let numbers: Vec<u32> = args.iter().skip(1).filter_map(|a| a.parse().ok()).collect();
    let reps = numbers.first().copied().unwrap_or(5).max(1) as usize;
    let ms: Vec<u32> = if numbers.len() > 1 { numbers[1..].to_vec() } else { vec![2, 4] };
    let manifest = Manifest::load(Path::new(path))?;
    let loaded = scenes::load(&manifest)?;
    let settings = render_settings(&manifest, tier, ExtraSamples::Compact);
    let forced_settings = RenderSettings {
        adaptive: AdaptiveSettings { force_all_samples: true, ..settings.adaptive },
        ..settings.clone()
    };
    let gpu = Arc::new(Gpu::new()?);
    let new_renderer = |settings: RenderSettings| {
        SceneRenderer::new(Arc::clone(&gpu), &loaded.scene, &loaded.camera, &loaded.lighting, settings)
    };
    let mut renderer = new_renderer(settings.clone())?;
    let mut forced = new_renderer(forced_settings.clone())?;
    // A second shader tree, A/B in the same process.
    let variant = std::env::var_os(VARIANT_VARIABLE);
    let mut variants = match &variant {
        Some(dir) => {
            let mut pair = [new_renderer(settings.clone())?, new_renderer(forced_settings)?];
            for renderer in &mut pair {
                renderer.read_shaders_from(dir.into());
            }
            pair.into()
        }
        None => Vec::new(),
    };
    let (w, h) = (settings.width, settings.height);
    let suffix = if stalled { "-stalled" } else { "" };
    println!("# {} ({}, {w}×{h}, {reps} repetitions)\n", manifest.name, tier.name());
    for m in ms {
        let reference = renderer.prepare(format!("reference-{m}x{m}{suffix}").parse()?)?;
        let adaptive_mode = format!("adaptive-{m}x{m}{suffix}").parse()?;
        let mut arms = vec![
            ("reference", reference),
            ("adaptive", renderer.prepare(adaptive_mode)?),
            ("forced", forced.prepare(adaptive_mode)?),
        ];
        if let [plain, all] = &mut variants[..] {
            arms.push(("adaptive B", plain.prepare(adaptive_mode)?));
            arms.push(("forced B", all.prepare(adaptive_mode)?));
        }
        let mut times: BTreeMap<(&str, &str), Vec<f64>> = BTreeMap::new();
        for _ in 0..reps + 1 {
            for (name, mode) in &arms {
                for pass in mode.render()?.passes {
                    times.entry((name, pass.name)).or_default().push(pass.seconds);
                }
            }
        }
        // The first repetition warms up.
        let median = |mode: &str, pass: &str| -> f64 {
            let samples = times.get(&(mode, pass)).map(|t| t[1..].to_vec()).unwrap_or_default();
            Summary::new(samples).map_or(0.0, |s| s.median)
        };
        // The sum of the passes' medians (run.json's speed-up takes whole frames' medians).
        let frame = |mode: &str| -> f64 {
            times.keys().filter(|(name, _)| *name == mode).map(|(_, pass)| median(mode, pass)).sum()
        };
        let background = background_mask(&arms[0].1)?;
        let all_samples = background.1.len() as f64;
        let covered = background.1.iter().filter(|&&b| !b).count() as f64;
        let (extra, extra_background) = listed(&arms[1].1, &background, m)?;
        println!("## {m}×{m}{suffix}\n");
        for (name, _) in &arms {
            let passes: Vec<String> = times
                .keys()
                .filter(|(mode, _)| mode == name)
                .map(|(_, pass)| format!("{pass} {:.1}", 1e3 * median(name, pass)))
                .collect();
            println!("- {name} (ms, Σ pass medians {:.1}): {}", 1e3 * frame(name), passes.join(", "));
        }
        let ns = |seconds: f64, samples: f64| 1e9 * seconds / samples;
        let per_sample = ns(median("reference", "shade"), all_samples);
        let per_covered = ns(median("reference", "shade"), covered);
        println!(
            "- reference: {per_sample:.2} ns per sample, {per_covered:.2} ns per covered sample \
             ({:.1} % covered)",
            100.0 * covered / all_samples
        );
        for (adaptive, forced) in [("adaptive", "forced"), ("adaptive B", "forced B")] {
            if !times.contains_key(&(adaptive, "shade_extra")) {
                continue;
            }
            let per_extra = ns(median(adaptive, "shade_extra"), extra);
            let per_forced = ns(median(forced, "shade_extra"), all_samples);
            println!(
                "- {adaptive}: {extra} extra samples, {:.1} % on background, {per_extra:.2} ns each \
                 = {:.2}× the reference's; speed-up {:.3}×",
                100.0 * extra_background / extra.max(1.0),
                per_extra / per_sample,
                frame("reference") / frame(adaptive)
            );
            println!(
                "- {forced}: {per_forced:.2} ns per sample = {:.2}× the reference's \
                 (the list's own overhead)",
                per_forced / per_sample
            );
        }
        println!();
    }
    Ok(())
}

/// The reference's G-buffer, and per sample (row-major) whether no geometry covers it.
fn background_mask(reference: &PreparedMode) -> anyhow::Result<(GBufferImages, Vec<bool>)> {
    let gbuffer = reference.read_gbuffer()?;
    let background = BACKGROUND_MATERIAL as f32;
    let mask = gbuffer.normal_material.iter().map(|s| s[3] == background).collect();
    Ok((gbuffer, mask))
}

/// The adaptive mode's listed samples and how many of them lie on background.
fn listed(
    adaptive: &PreparedMode,
    (gbuffer, background): &(GBufferImages, Vec<bool>),
    m: u32,
) -> anyhow::Result<(f64, f64)> {
    let counts = adaptive.read_sample_counts()?.context("an adaptive mode has counts")?;
    let order = sample_order(m);
    let w = gbuffer.width / m;
    let (mut extra, mut on_background) = (0.0, 0.0);
    for (p, &n) in counts.iter().enumerate() {
        let n = u32::from(n);
        let first = if n == m * m { 0 } else { 1 };
        let window: Vec<usize> = gbuffer.window_indices(m, p as u32 % w, p as u32 / w).collect();
        for rank in first..n {
            extra += 1.0;
            on_background += f64::from(u8::from(background[window[order[rank as usize] as usize]]));
        }
    }
    Ok((extra, on_background))
}
