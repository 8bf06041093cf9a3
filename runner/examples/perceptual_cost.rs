//! What the perceptual metrics cost per image: FLIP and SSIM of one display image against
//! another, each timed over a few rounds (`docs/measuring.md`). SSIM is timed as a run pays
//! it, the truth's share computed once beforehand.
//!
//! `cargo run --release --example perceptual_cost -- IMAGE.png TRUTH.png`

use std::time::Instant;

use aabench::measure::perceptual;
use aabench_renderer::DisplayImage;
use anyhow::Context;

fn main() -> anyhow::Result<()> {
    let mut args = std::env::args().skip(1);
    let usage = "usage: perceptual_cost IMAGE.png TRUTH.png";
    let load = |path: String| -> anyhow::Result<(DisplayImage, u32, u32)> {
        let image = image::open(&path).with_context(|| path.clone())?.into_rgba8();
        let (w, h) = image.dimensions();
        Ok((DisplayImage::from_rgba8(image.as_raw()), w, h))
    };
    let (image, w, h) = load(args.next().context(usage)?)?;
    let (truth, tw, th) = load(args.next().context(usage)?)?;
    anyhow::ensure!((w, h) == (tw, th), "the images differ in size");
    let ssim_truth = perceptual::SsimTruth::new(&truth, w, h);
    for round in 1..=3 {
        let start = Instant::now();
        let flip =
            perceptual::flip(&image, &truth, [w, h], perceptual::FLIP_DEFAULT_PIXELS_PER_DEGREE).mean();
        let flip_s = start.elapsed().as_secs_f64();
        let start = Instant::now();
        let ssim = ssim_truth.ssim(&image);
        let ssim_s = start.elapsed().as_secs_f64();
        println!("round {round}: {w}×{h} FLIP {flip:.6} in {flip_s:.3} s, SSIM {ssim:.6} in {ssim_s:.3} s");
    }
    Ok(())
}
