//! What ColorVideoVDP costs at the quick tier's resolution: a 256×192 still against its truth,
//! and a path of 8 such frames at 60 frames a second (the quick tier's sequence), with and
//! without the distortion map of its worst frame (which the runner keeps).

use aabench_cvvdp::{Cvvdp, Display, Frame};
use criterion::{Criterion, criterion_group, criterion_main};
use std::hint::black_box;

const WIDTH: usize = 256;
const HEIGHT: usize = 192;

/// A frame of code values k/255 with detail at every scale, shifted `shift` pixels right and
/// perturbed by `noise`.
fn frame(shift: usize, noise: u32) -> Vec<f32> {
    (0..WIDTH * HEIGHT * 3)
        .map(|i| {
            let (x, y, c) = ((i / 3) % WIDTH + shift, i / 3 / WIDTH, i % 3);
            let pattern = (x * 7 + y * 13 + c * 31) % 97 + (x / 16 + y / 16) % 2 * 100;
            let jitter = (i as u32).wrapping_mul(2_654_435_761) % (noise + 1);
            ((pattern as u32 + jitter).min(255)) as f32 / 255.0
        })
        .collect()
}

fn score(c: &mut Criterion) {
    let metric = Cvvdp::new(Display::standard_fhd());
    let truth: Vec<Vec<f32>> = (0..8).map(|f| frame(4 * f, 0)).collect();
    let test: Vec<Vec<f32>> = (0..8).map(|f| frame(4 * f, 24)).collect();
    c.bench_function("image 256x192", |b| {
        b.iter(|| black_box(metric.image(at(&test[0]), at(&truth[0])).unwrap().jod))
    });
    for (name, map) in
        [("video 256x192x8 at 60 fps", false), ("video 256x192x8 at 60 fps, worst frame's map", true)]
    {
        c.bench_function(name, |b| {
            b.iter(|| {
                let video = metric.video(WIDTH, HEIGHT, 60.0).unwrap();
                let mut video = if map { video.with_worst_map() } else { video };
                for (t, r) in test.iter().zip(&truth) {
                    video.push(at(t), at(r)).unwrap();
                }
                black_box(video.finish().unwrap().jod)
            })
        });
    }
}

fn at(rgb: &[f32]) -> Frame<'_> {
    Frame { width: WIDTH, height: HEIGHT, rgb }
}

criterion_group! {
    name = benches;
    config = Criterion::default().sample_size(10);
    targets = score
}
criterion_main!(benches);
