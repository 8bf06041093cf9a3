//! What the runner measures, as functions of images and samples with no knowledge of a run:
//! a frame's pixels against a reference (`pixels.rs`: MSE, PSNR, sample counts, blank frames),
//! perceptual error (`perceptual.rs`: FLIP, SSIM, ColorVideoVDP), error along the motion
//! (`temporal.rs`: flicker, ghosting, measured speed), the statistics of repeated timings
//! (`stats.rs`), and the machine the times belong to (`machine.rs`).

pub mod machine;
pub mod perceptual;
pub mod pixels;
pub mod stats;
pub mod temporal;
