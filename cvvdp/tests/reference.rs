//! The port against the reference implementation: every fixture in `fixtures/` (frames the
//! reference, `cvvdp` 0.5.7 on the `standard_fhd` display, at its own pixels a degree or the
//! fixture's, scored with `fixtures/make_fixtures.py`) must score within 0.01 JOD of the reference's JOD, and each
//! frame's pooled difference per channel and band within 0.1 % of the reference's, so that a
//! broken stage (a table, a filter, the pyramid's borders, the masking, the pooling) fails here
//! even where the total hides it.

use crate::common;

use aabench_cvvdp::Display;
use common::{fixtures, score};
use serde_json::Value;
use std::time::Instant;

/// The largest difference in JOD from the reference that a fixture may show.
const JOD_TOLERANCE: f64 = 0.01;

#[test]
fn every_fixture_scores_within_a_hundredth_of_a_jod_of_the_reference() {
    let display = Display::standard_fhd();
    let fixtures = fixtures();
    let mut failures = Vec::new();
    println!(
        "{:<26} {:>6} {:>9} {:>9} {:>8} {:>9}",
        "fixture", "frames", "port", "reference", "diff", "port ms"
    );
    for fixture in fixtures["fixtures"].as_array().unwrap() {
        let name = fixture["name"].as_str().unwrap();
        let start = Instant::now();
        let score = score(&common::metric_for(&display, fixture), fixture);
        let elapsed = start.elapsed().as_secs_f64() * 1e3;
        let expected = fixture["jod"].as_f64().unwrap();
        let diff = score.jod - expected;
        println!(
            "{name:<26} {:>6} {:>9.4} {expected:>9.4} {diff:>+8.4} {elapsed:>9.1}",
            fixture["frames"], score.jod
        );
        if diff.abs() > JOD_TOLERANCE {
            failures.push(format!("{name}: {:.4} JOD against the reference's {expected:.4}", score.jod));
        }
        failures.extend(stage_differences(name, &score, fixture));
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

/// Where the per-channel, per-band, per-frame pooled differences leave the reference's by
/// more than 0.1 % (and 10⁻⁵ absolute, for values near the guard's floor).
fn stage_differences(name: &str, score: &aabench_cvvdp::Score, fixture: &Value) -> Vec<String> {
    let expected = fixture["q_per_ch"].as_array().unwrap();
    let mut out = Vec::new();
    for (c, channel) in expected.iter().enumerate() {
        for (f, frame) in channel.as_array().unwrap().iter().enumerate() {
            for (b, value) in frame.as_array().unwrap().iter().enumerate() {
                let want = value.as_f64().unwrap();
                let got = f64::from(score.per_channel[f][c][b]);
                if (got - want).abs() > 1e-5 + 1e-3 * want.abs() {
                    out.push(format!("{name}: channel {c} frame {f} band {b}: {got} against {want}"));
                }
            }
        }
    }
    out
}
