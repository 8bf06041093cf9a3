//! What posing a moving scene costs a frame, on the CPU and with its upload: the `walker`
//! scene's skinned figure (its vertices now and its positions of the frame before) and the
//! `crossing` scene's rigid crate, each beside one deferred-1x1 frame of the scene for scale, at
//! the quick tier's 256×192 and the nightly's 1024×768. Posing on the CPU does not depend on the
//! resolution, so it is measured once.

use std::path::Path;
use std::sync::Arc;

use aabench::manifest::Manifest;
use aabench::plan::Tier;
use aabench_renderer::scene::pose::Poser;
use aabench_renderer::{Gpu, Mode, SceneRenderer};
use criterion::{Criterion, criterion_group, criterion_main};

fn poses(c: &mut Criterion) {
    let gpu = Arc::new(Gpu::new().expect("a Vulkan adapter (lavapipe)"));
    for name in ["walker", "crossing"] {
        let path = Path::new(env!("CARGO_MANIFEST_DIR")).join(format!("../scenes/{name}.json"));
        let manifest = Manifest::load(&path).expect("a suite manifest");
        let loaded = aabench::run::scenes::load(&manifest).expect("the scene loads");
        let poser = Poser::of(&loaded.scene).expect("its animation plays");
        let step = 1.0 / 60.0;
        c.bench_function(&format!("{name}: pose on the CPU"), |bench| {
            let mut time = 0.0;
            bench.iter(|| {
                time = (time + step) % 2.0;
                (poser.vertices_at(time), poser.positions_at(time - step))
            })
        });
        let extra_samples = manifest.adaptive.settings().extra_samples;
        for tier in [Tier::Quick, Tier::Nightly] {
            let settings = aabench::run::render_settings(&manifest, tier, extra_samples);
            let mut renderer =
                SceneRenderer::new(gpu.clone(), &loaded.scene, &loaded.camera, &loaded.lighting, settings)
                    .expect("upload");
            c.bench_function(&format!("{name} ({}): pose and upload", tier.name()), |bench| {
                let mut time = 0.0;
                bench.iter(|| {
                    time = (time + step) % 2.0;
                    renderer.pose(time, time - step).expect("pose")
                })
            });
            let deferred =
                renderer.prepare("deferred-1x1".parse::<Mode>().expect("mode id")).expect("prepare");
            deferred.render().expect("warm-up frame");
            c.bench_function(
                &format!("{name} ({}): a deferred-1x1 frame, for scale", tier.name()),
                |bench| bench.iter(|| deferred.render().expect("frame")),
            );
        }
    }
}

criterion_group! {
    name = cpu;
    config = Criterion::default().sample_size(20);
    targets = poses
}
criterion_main!(cpu);
