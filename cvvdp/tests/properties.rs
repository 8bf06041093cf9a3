//! What JOD must say of clips whose order is known, checked first on the reference (the
//! fixtures' scores are cvvdp 0.5.7's) and then on the port: each fails on a port whose
//! temporal channels, masking or pooling is broken, even where a broken stage keeps every
//! score in [0, 10].

use crate::common;

use aabench_cvvdp::{Cvvdp, Display, Frame};
use serde_json::Value;

fn fixture<'a>(fixtures: &'a Value, name: &str) -> &'a Value {
    fixtures["fixtures"].as_array().unwrap().iter().find(|f| f["name"] == name).unwrap()
}

/// The port's JOD and the reference's for a fixture.
fn jods(metric: &Cvvdp, fixtures: &Value, name: &str) -> (f64, f64) {
    let f = fixture(fixtures, name);
    (common::score(metric, f).jod, f["jod"].as_f64().unwrap())
}

#[test]
fn a_frozen_first_frame_scores_below_the_mode_it_froze() {
    let (metric, fixtures) = (Cvvdp::new(Display::standard_fhd()), common::fixtures());
    let (frozen, frozen_ref) = jods(&metric, &fixtures, "frozen");
    let (moving, moving_ref) = jods(&metric, &fixtures, "thin-32-deferred");
    assert!(frozen_ref < moving_ref - 1.0, "the reference shows it");
    assert!(frozen < moving - 1.0, "frozen {frozen:.3} JOD against the moving mode's {moving:.3}");
}

#[test]
fn a_blur_of_the_truth_scores_below_reference_4x4() {
    let (metric, fixtures) = (Cvvdp::new(Display::standard_fhd()), common::fixtures());
    let (blur, blur_ref) = jods(&metric, &fixtures, "blur");
    let (supersampled, supersampled_ref) = jods(&metric, &fixtures, "thin-8-reference-4x4");
    assert!(blur_ref < supersampled_ref - 1.0, "the reference shows it");
    assert!(
        blur < supersampled - 1.0,
        "σ 1.5 px blur {blur:.3} JOD against reference-4x4's {supersampled:.3}"
    );
}

/// ColorVideoVDP integrates over time: an error that alternates in sign at 60 frames a second
/// (a ±½ px shimmer of a still) averages towards zero in the sustained channel, and its
/// transient channel adds less than a steady +½ px error of the same per-frame MSE costs. The
/// reference scores the shimmer 0.13 JOD *above* the steady shift (and higher still at every
/// period from 1 to 16 frames on 32 frames): JOD does not rank zero-mean flicker of fine
/// detail below a steady error, and the port must not either.
#[test]
fn an_alternating_half_pixel_shimmer_scores_as_the_reference_does_above_a_steady_shift_of_equal_mse() {
    let (metric, fixtures) = (Cvvdp::new(Display::standard_fhd()), common::fixtures());
    let mse = |name: &str| -> f64 {
        let values = fixture(&fixtures, name)["mse"]
            .as_array()
            .unwrap()
            .iter()
            .map(|v| v.as_f64().unwrap())
            .collect::<Vec<_>>();
        values.iter().sum::<f64>() / values.len() as f64
    };
    assert!((mse("shimmer") / mse("steady") - 1.0).abs() < 0.05, "the two clips' per-frame MSE agree");
    let (shimmer, shimmer_ref) = jods(&metric, &fixtures, "shimmer");
    let (steady, steady_ref) = jods(&metric, &fixtures, "steady");
    assert!(shimmer_ref > steady_ref + 0.1, "the reference's order");
    assert!(shimmer > steady + 0.1, "shimmer {shimmer:.3} JOD against steady {steady:.3}");
}

#[test]
fn identical_clips_score_ten_and_more_noise_scores_lower() {
    let metric = Cvvdp::new(Display::standard_fhd());
    let (width, height) = (48, 40);
    let base: Vec<f32> = (0..width * height * 3).map(|i| ((i * 7919) % 251) as f32 / 250.0).collect();
    let noisy = |amplitude: f32| -> Vec<f32> {
        base.iter()
            .enumerate()
            .map(|(i, v)| (v + amplitude * (((i * 104_729) % 13) as f32 / 6.0 - 1.0)).clamp(0.0, 1.0))
            .collect()
    };
    let score = |test: &[f32]| {
        let frame = |rgb| Frame { width, height, rgb };
        let mut video = metric.video(width, height, 60.0).unwrap();
        for _ in 0..4 {
            video.push(frame(test), frame(&base)).unwrap();
        }
        video.finish().unwrap().jod
    };
    assert_eq!(score(&base), 10.0);
    let (small, large) = (score(&noisy(0.02)), score(&noisy(0.08)));
    assert!(10.0 > small && small > large, "10 > {small:.3} > {large:.3}");
}

/// A warm-up is history, not score: a clip whose warm-up differs from the reference and whose
/// window matches it scores near 10 (the window's first frames still see the warm-up through
/// the temporal filters), one whose warm-up matches and whose window differs scores as low as
/// the window's difference says; each frame's pooled values are the clip's without a warm-up,
/// and a warm-up of 0 is the reference's scoring.
#[test]
fn a_warm_up_feeds_the_filters_but_only_the_window_is_pooled() {
    let metric = Cvvdp::new(Display::standard_fhd());
    let (width, height) = (48, 40);
    let base: Vec<f32> = (0..width * height * 3).map(|i| ((i * 7919) % 251) as f32 / 250.0).collect();
    let noisy: Vec<f32> = base
        .iter()
        .enumerate()
        .map(|(i, v)| (v + 0.08 * (((i * 104_729) % 13) as f32 / 6.0 - 1.0)).clamp(0.0, 1.0))
        .collect();
    // A window longer than the filters' 17 taps: over a window of 16 frames the two clips
    // below would weigh the same differences in reverse order (the taps are symmetric) and score
    // alike.
    let (warmup, window) = (16, 32);
    // A clip of the warm-up's frames and the window's, each either the base or its noisy twin.
    let score = |[early, late]: [&[f32]; 2], warm: usize| {
        let frame = |rgb| Frame { width, height, rgb };
        let mut video = metric.video(width, height, 60.0).unwrap().with_worst_map().measured_from(warm);
        for f in 0..warmup + window {
            video.push(frame(if f < warmup { early } else { late }), frame(&base)).unwrap();
        }
        video.finish().unwrap()
    };
    let bad_warmup = [noisy.as_slice(), base.as_slice()];
    let bad_window = [base.as_slice(), noisy.as_slice()];
    let (history, window_only) = (score(bad_warmup, warmup), score(bad_window, warmup));
    assert!(history.jod > 9.0, "a bad warm-up before a perfect window: {:.3}", history.jod);
    // The worst frame is the window's, where the warm-up's differences still echo.
    assert_eq!(history.worst.as_ref().unwrap().frame, warmup);
    // (8.59 against 9.32 JOD; scored whole, the bad warm-up's clip falls to 8.84.)
    assert!(window_only.jod < history.jod - 0.5, "{:.3} against {:.3}", window_only.jod, history.jod);
    // The same clip scored whole: its per-frame values are the same, its pooling is over all
    // frames, so the bad warm-up now counts.
    let whole = score(bad_warmup, 0);
    assert_eq!(whole.per_channel, history.per_channel);
    assert!(whole.jod < history.jod - 0.3, "{:.3} against {:.3}", whole.jod, history.jod);
    // A warm-up of every frame leaves nothing to score.
    let frame = |rgb| Frame { width, height, rgb };
    let mut video = metric.video(width, height, 60.0).unwrap().measured_from(2);
    video.push(frame(&base), frame(&base)).unwrap();
    video.push(frame(&base), frame(&base)).unwrap();
    assert!(video.finish().is_err());
}
