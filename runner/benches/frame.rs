//! One quick-tier adaptive frame of the atrium on lavapipe (256×192, adaptive-4x4), and its
//! reference for scale. Frame time only: the scene is generated, loaded and prepared once.

use std::path::Path;
use std::sync::Arc;

use aabench::manifest::Manifest;
use aabench::plan::Tier;
use aabench_renderer::{Gpu, Mode, SceneRenderer};
use criterion::{Criterion, criterion_group, criterion_main};

fn frames(c: &mut Criterion) {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../scenes/atrium.json");
    let manifest = Manifest::load(&root).expect("scenes/atrium.json");
    let loaded = aabench::run::scenes::load(&manifest).expect("atrium loads");
    let gpu = Arc::new(Gpu::new().expect("a Vulkan adapter (lavapipe)"));
    let extra_samples = manifest.adaptive.settings().extra_samples;
    let settings = aabench::run::render_settings(&manifest, Tier::Quick, extra_samples);
    let mut renderer =
        SceneRenderer::new(gpu, &loaded.scene, &loaded.camera, &loaded.lighting, settings).expect("upload");
    for id in ["adaptive-4x4", "reference-4x4"] {
        let mode: Mode = id.parse().expect("mode id");
        let prepared = renderer.prepare(mode).expect("prepare");
        prepared.render().expect("warm-up frame");
        c.bench_function(&format!("atrium quick {id} frame"), |bench| {
            bench.iter(|| prepared.render().expect("frame"))
        });
    }
}

criterion_group! {
    name = gpu;
    config = Criterion::default().sample_size(10);
    targets = frames
}
criterion_main!(gpu);
