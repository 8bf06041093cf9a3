//! Where the difference is: the reference's per-pixel distortion map (its "raw" heat map). Each
//! band's differences are weighed and pooled across channels as the score pools them, the bands
//! are put back together as a Laplacian pyramid is, and each pixel's pooled difference is mapped
//! to JOD: the map holds 1 − JOD/10, 0 where no difference shows.

use crate::masking::{SafePow, safe_pow};
use crate::parameters::Parameters;
use crate::pyramid::{Plane, expand};

/// The distortion map of one frame from its bands' per-pixel differences (`[band][channel]`,
/// the baseband last), in [0, 1]; `to_jod` maps a pooled difference to JOD.
pub fn distortion_map(
    bands: &[Vec<Plane>],
    parameters: &Parameters,
    is_image: bool,
    to_jod: impl Fn(f32) -> f32,
) -> Plane {
    let last = bands.len() - 1;
    let weights = parameters.channel_weights();
    let integration = if is_image { parameters.image_int } else { 1.0 };
    let power = SafePow::new(parameters.beta_tch);
    let pooled: Vec<Plane> = bands
        .iter()
        .enumerate()
        .map(|(b, channels)| {
            // The pyramid stores the middle bands halved: its reconstruction doubles them back.
            let gain = if b == 0 || b == last { 1.0 } else { 2.0 };
            let weight = |c: usize| {
                weights[c] * integration * if b == last { parameters.baseband_weight[c] } else { 1.0 }
            };
            let first = &channels[0];
            let data = (0..first.data.len())
                .map(|i| {
                    let sum: f32 =
                        channels.iter().enumerate().map(|(c, d)| power.of(d.data[i] * weight(c))).sum();
                    safe_pow(sum, 1.0 / parameters.beta_tch) / gain
                })
                .collect();
            Plane { width: first.width, height: first.height, data }
        })
        .collect();
    let mut image = pooled[last].clone();
    for band in pooled[..last].iter().rev() {
        let coarse = expand(&image, band.width, band.height);
        image =
            Plane { data: coarse.data.iter().zip(&band.data).map(|(c, f)| c + f).collect(), ..band.clone() };
    }
    image.map(|q| 1.0 - to_jod(q) / 10.0)
}
