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

/// Scores a fixture with the port: a clip with a warm-up (`warmup` frames, absent in fixtures
/// from before it) pooled over the frames after it.
pub fn score(metric: &Cvvdp, fixture: &Value) -> Score {
    // A fixture with a warm-up reads another's strips (absent in fixtures from before: its own).
    let name = fixture["strips"].as_str().or(fixture["name"].as_str()).unwrap();
    let dims = |key: &str| fixture[key].as_u64().unwrap() as usize;
    let (width, height, count) = (dims("width"), dims("height"), dims("frames"));
    let test = frames(name, "test", width, height, count);
    let reference = frames(name, "reference", width, height, count);
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
