//! The stiff scenes of scenes/, loaded as `aabench run` loads them: a scene far from the origin
//! samples like its twin at the origin, and the Cornell box samples alike in mm, m and km.
//! Every mode at tiny and odd resolutions, and the loop strategy's stall limit, are tested in
//! `renderer/tests/adaptive.rs`.

use std::path::{Path, PathBuf};
use std::sync::Arc;

use aabench::manifest::Manifest;
use aabench::plan::Tier;
use aabench_renderer::{ExtraSamples, Gpu, Mode, SceneRenderer};

use crate::support;

fn scene_file(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../scenes").join(format!("{name}.json"))
}

/// The sample counts and HDR image of `mode` for a scene of scenes/, at the quick tier.
fn render(gpu: &Arc<Gpu>, name: &str, mode: &str) -> (Vec<u8>, Vec<f32>) {
    let manifest = Manifest::load(&scene_file(name)).unwrap();
    let loaded = aabench::run::scenes::load(&manifest).unwrap();
    let settings = aabench::run::render_settings(&manifest, Tier::Quick, ExtraSamples::Compact);
    let mut renderer =
        SceneRenderer::new(Arc::clone(gpu), &loaded.scene, &loaded.camera, &loaded.lighting, settings)
            .unwrap();
    let prepared = renderer.prepare(mode.parse::<Mode>().unwrap()).unwrap();
    prepared.render().unwrap();
    let images = prepared.read_images().unwrap();
    (images.sample_counts.unwrap(), images.hdr)
}

/// Pixels whose sample counts differ.
fn differing(a: &[u8], b: &[u8]) -> usize {
    a.iter().zip(b).filter(|(x, y)| x != y).count()
}

/// At adaptive-2x2 and adaptive-4x4 on the quick tier's 160×120, `far-depth` differs from its
/// twin at the origin in at most 0.1% of sample counts (6 and 14 of 19 200 when measured), and
/// `cornell-mm` and `cornell-km` differ from `cornell-m` in at most 0.1% as well. The far
/// scene's HDR output is finite.
#[test]
fn far_from_the_origin_samples_like_at_the_origin_and_the_unit_does_not_matter() {
    let _serial = support::SERIAL.lock().unwrap_or_else(|p| p.into_inner());
    let gpu = Arc::new(Gpu::new().unwrap());
    for mode in ["adaptive-2x2", "adaptive-4x4"] {
        // 10⁵ units out, positions are relative to a scene origin 1024-aligned near the
        // geometry: they round differently from the twin's by at most an ulp of a few hundred
        // units (3·10⁻⁵), which may move a count across a rounding boundary here and there.
        let (far, far_hdr) = render(&gpu, "far-depth", mode);
        let (near, _) = render(&gpu, "far-depth-origin", mode);
        eprintln!("{mode}: far-depth vs its twin: {} of {} counts differ", differing(&far, &near), far.len());
        assert!(
            differing(&far, &near) * 1000 <= far.len(),
            "{mode}: {} of {} counts differ",
            differing(&far, &near),
            far.len()
        );
        assert!(far_hdr.iter().all(|v| v.is_finite()), "{mode}");

        // The relative depth metric is unit-free: mm, m and km give the same map.
        let (m, _) = render(&gpu, "cornell-m", mode);
        for other in ["cornell-mm", "cornell-km"] {
            let (counts, _) = render(&gpu, other, mode);
            eprintln!("{mode}: {other} vs cornell-m: {} counts differ", differing(&counts, &m));
            assert!(
                differing(&counts, &m) * 1000 <= m.len(),
                "{mode} {other}: {} counts differ",
                differing(&counts, &m)
            );
        }
    }
}
