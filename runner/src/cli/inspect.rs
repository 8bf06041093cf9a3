//! Commands that look before a run: `gen-scenes` (the generated glTF files), `graph` (a mode's
//! pass graph), `info` (the adapter and platform key) and `modes` (the mode ids).

use std::path::{Path, PathBuf};

use aabench_renderer::{ExtraSamples, Mode};

use super::{fail, out};
use crate::exit;
use crate::manifest::Manifest;
use crate::plan::{self, Tier};
use crate::run::{self, scenes};

pub(super) fn gen_scenes(paths: &[PathBuf], force: bool) -> u8 {
    let manifests = match plan::find_manifests(paths) {
        Ok(manifests) => manifests,
        Err(message) => return fail(message),
    };
    let mut code = exit::OK;
    for path in manifests {
        let result = Manifest::load(&path).map_err(anyhow::Error::from).and_then(|manifest| {
            if manifest.generate.is_none() {
                return Ok(format!("{}: not generated (no `generate` section)", manifest.name));
            }
            let start = std::time::Instant::now();
            let wrote = scenes::ensure_generated(&manifest, force)?;
            Ok(if wrote {
                format!(
                    "{}: wrote {} in {:.1} s",
                    manifest.name,
                    manifest.gltf_path().display(),
                    start.elapsed().as_secs_f64()
                )
            } else {
                format!("{}: {} is current", manifest.name, manifest.gltf_path().display())
            })
        });
        match result {
            Ok(line) => say!("{line}"),
            Err(error) => code = fail(format!("{error:#}")),
        }
    }
    code
}

pub(super) fn print_graph(
    path: &Path,
    mode: &str,
    tier: Tier,
    extra_samples: ExtraSamples,
    dot: bool,
) -> anyhow::Result<()> {
    let mode: Mode = mode.parse().map_err(|e| anyhow::anyhow!("--mode: {e}"))?;
    let manifest = Manifest::load(path)?;
    let loaded = scenes::load(&manifest)?;
    let settings = run::render_settings(&manifest, tier, extra_samples);
    let needs = aabench_renderer::frame::SceneNeeds::of(&loaded.scene, &loaded.lighting);
    // The adaptive list's layout follows the device's limits.
    let limits = aabench_renderer::Gpu::new()?.device.limits();
    let graph = aabench_renderer::frame::describe(&needs, mode, &settings, &limits, dot)?;
    if !dot {
        let [width, height] = [settings.width, settings.height];
        say!("{} {mode} ({} tier, {width}×{height}; {needs})\n", manifest.name, tier.name());
    }
    out(format_args!("{graph}"));
    Ok(())
}

pub(super) fn info() -> u8 {
    match aabench_renderer::Gpu::new() {
        Ok(gpu) => {
            let p = &gpu.platform;
            say!("adapter      {} ({}, {})", p.adapter, p.backend, p.device_type);
            say!("driver       {} {}", p.driver, p.driver_info);
            say!("cpu          {} ({} cores)", p.cpu_model, p.cpu_cores);
            say!(
                "threads      LP_NUM_THREADS={}",
                p.lp_num_threads.as_deref().unwrap_or("(unset: one per core)")
            );
            say!("build        {}", p.build_profile);
            say!("platform key {}", p.key());
            exit::OK
        }
        Err(error) => fail(error),
    }
}

fn list_modes() {
    for (name, modes) in Mode::groups() {
        say!("{name}:");
        for mode in modes {
            say!("  {mode}");
        }
    }
    say!("also: reference-1x1 (equals deferred-1x1; a self-check)");
    say!(
        "also: adaptive-MxM with any of these words, in this order: geometry or shading (one metric), \
         area, cells or coverage (the reconstruction), stable (the counts; not with coverage); \
         e.g. adaptive-2x2-shading-area-stable"
    );
}

/// `aabench modes`: every mode id and group, or with a tier the modes it runs (or, with
/// `timed_by_gate`, those whose time the gate compares), one a line.
pub(super) fn modes(tier: Option<Tier>, timed_by_gate: bool) -> u8 {
    let Some(tier) = tier else {
        list_modes();
        return exit::OK;
    };
    let modes = if timed_by_gate { tier.gate_timed_modes() } else { tier.default_modes() };
    for mode in modes {
        say!("{mode}");
    }
    exit::OK
}
