#![allow(dead_code)] // Each test crate uses a part of what they share.
//! What the tests share: the fixtures the reference scored, their frames, and the port's score
//! of a fixture.

use aabench_cvvdp::{Cvvdp, Frame, Score};
use serde_json::Value;
use std::path::{Path, PathBuf};

fn fixtures_dir() -> PathBuf {
    std::env::var_os("CVVDP_FIXTURES")
        .map(PathBuf::from)
        .unwrap_or_else(|| Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures"))
}

pub fn fixtures() -> Value {
    let path = fixtures_dir().join("fixtures.json");
    let text = std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    serde_json::from_str(&text).unwrap()
}

/// A stacked strip's frames as display-encoded RGB in [0, 1].
pub fn frames(name: &str, which: &str, width: usize, height: usize, count: usize) -> Vec<Vec<f32>> {
    let path = fixtures_dir().join(format!("{name}.{which}.png"));
    let image = image::open(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display())).to_rgb8();
    assert_eq!(
        (image.width() as usize, image.height() as usize),
        (width, height * count),
        "{}",
        path.display()
    );
    let values: Vec<f32> = image.as_raw().iter().map(|&v| f32::from(v) / 255.0).collect();
    values.chunks_exact(width * height * 3).map(<[f32]>::to_vec).collect()
}

pub fn frame(width: usize, height: usize, rgb: &[f32]) -> Frame<'_> {
    Frame { width, height, rgb }
}

/// The background and the two families of bars of [`bars`], as 8-bit code values.
const BARS_BACKGROUND: [i64; 3] = [20, 40, 90];
const BARS_STEEP: [i64; 3] = [230, 200, 60];
const BARS_SHALLOW: [i64; 3] = [240, 240, 240];

/// Frame `frame` of make_fixtures.py's `bars`, to the integer: two families of thin moving
/// bars over a plain background, each pixel the mean of `samples` × `samples` point samples
/// (1: its centre, aliased; 4: the truth), rounded half up, in `bits`-bit code values scaled to
/// display-encoded RGB in [0, 1]. Positions are integers in 1/8 px; a sample is on a steep bar
/// where (5 sx + 2 sy + 148 f) mod 720 < 24, else on a shallow one where
/// (sx − 4 sy − 36 f) mod 800 < 30. The colours are 8-bit codes c, or (1023 c + 127) div 255 at
/// 10 bits.
pub fn bars(width: usize, height: usize, frame: i64, samples: i64, bits: u32) -> Vec<f32> {
    assert_eq!(4 % samples, 0);
    let step = 8 / samples;
    let count = samples * samples;
    let top = (1i64 << bits) - 1;
    let code = |colour: [i64; 3]| colour.map(|c| (c * top + 127) / 255);
    let [background, steep, shallow] = [BARS_BACKGROUND, BARS_STEEP, BARS_SHALLOW].map(code);
    let mut out = Vec::with_capacity(width * height * 3);
    for y in 0..height as i64 {
        for x in 0..width as i64 {
            let mut total = [0i64; 3];
            for i in 0..samples {
                for j in 0..samples {
                    let (sx, sy) = (8 * x + i * step + step / 2, 8 * y + j * step + step / 2);
                    let colour = if (5 * sx + 2 * sy + 148 * frame).rem_euclid(720) < 24 {
                        steep
                    } else if (sx - 4 * sy - 36 * frame).rem_euclid(800) < 30 {
                        shallow
                    } else {
                        background
                    };
                    (0..3).for_each(|c| total[c] += colour[c]);
                }
            }
            out.extend(total.map(|t| ((t + count / 2) / count) as f32 / top as f32));
        }
    }
    out
}

/// A fixture's test and reference frames: synthesised where it names a synthesis, else read
/// from its strips (a fixture with a warm-up may read another's).
pub fn fixture_frames(fixture: &Value) -> (Vec<Vec<f32>>, Vec<Vec<f32>>) {
    let dims = |key: &str| fixture[key].as_u64().unwrap() as usize;
    let (width, height, count) = (dims("width"), dims("height"), dims("frames"));
    if let Some(synthesis) = fixture.get("synthesis") {
        assert_eq!(synthesis["pattern"], "bars", "{synthesis}");
        let bits = synthesis["bits"].as_u64().unwrap_or(8) as u32;
        let clip = |key: &str| {
            let samples = synthesis[key].as_i64().unwrap();
            (0..count as i64).map(|f| bars(width, height, f, samples, bits)).collect()
        };
        return (clip("test_samples"), clip("reference_samples"));
    }
    let name = fixture["strips"].as_str().or(fixture["name"].as_str()).unwrap();
    (frames(name, "test", width, height, count), frames(name, "reference", width, height, count))
}

/// The port on `display`, seen at the fixture's pixels a degree where it names them.
pub fn metric_for(display: &aabench_cvvdp::Display, fixture: &Value) -> Cvvdp {
    let mut display = display.clone();
    if let Some(ppd) = fixture["pixels_per_degree"].as_f64() {
        display.pixels_per_degree = ppd;
    }
    Cvvdp::new(display)
}

/// Scores a fixture with the port: a clip with a warm-up (`warmup` frames, absent in fixtures
/// from before it) pooled over the frames after it.
pub fn score(metric: &Cvvdp, fixture: &Value) -> Score {
    let dims = |key: &str| fixture[key].as_u64().unwrap() as usize;
    let (width, height, count) = (dims("width"), dims("height"), dims("frames"));
    let (test, reference) = fixture_frames(fixture);
    if count == 1 {
        return metric.image(frame(width, height, &test[0]), frame(width, height, &reference[0])).unwrap();
    }
    let warmup = fixture["warmup"].as_u64().unwrap_or(0) as usize;
    let mut video =
        metric.video(width, height, fixture["fps"].as_f64().unwrap()).unwrap().measured_from(warmup);
    for (t, r) in test.iter().zip(&reference) {
        video.push(frame(width, height, t), frame(width, height, r)).unwrap();
    }
    video.finish().unwrap()
}
