//! The error-against-run-time front in a real run of the texture stress scene, and what the
//! `-cells` variant recovers there against the truth.

mod support;

use serde_json::Value;
use support::*;

const MODES: &str =
    "deferred-1x1,reference-2x2,reference-4x4,adaptive-4x4,adaptive-4x4-area,adaptive-4x4-cells";

fn psnr(mode: &Value) -> f64 {
    mode["vs_ground_truth"]["psnr_db"].as_f64().expect("a finite PSNR against the truth")
}

/// The record of a quick run of the texture stress scene in `modes`, in a workspace of its own.
fn texture_run(name: &str, modes: &str, repetitions: &str) -> Value {
    let ws = Workspace::new(name);
    let manifest = concat!(env!("CARGO_MANIFEST_DIR"), "/../scenes/texture.json");
    std::fs::copy(manifest, ws.dir.join("scenes/texture.json")).unwrap();
    let output = ws.run(&["run", "scenes/texture.json", "--modes", modes, "--repetitions", repetitions]);
    assert!(output.status.success(), "{}", stderr(&output));
    ws.record()
}

#[test]
fn the_texture_scene_places_every_mode_on_or_behind_the_front_and_cells_recover_the_texture() {
    let _serial = SERIAL.lock().unwrap_or_else(|e| e.into_inner());
    let record = texture_run("front", MODES, "3");
    let scene = &record["scenes"][0];
    let modes = scene["modes"].as_array().unwrap();
    assert_eq!(modes.len(), 6);

    let mut on_front = 0;
    for mode in modes {
        let place = &mode["front"];
        let dominated_by = place["dominated_by"].as_array().cloned().unwrap_or_default();
        assert_eq!(place["on_front"].as_bool(), Some(dominated_by.is_empty()), "{place}");
        on_front += usize::from(dominated_by.is_empty());
        // Each dominator is what the front says it is: as near the truth within a tie and not
        // slower (its median inside this mode's interval or below it), by the margins recorded.
        for dominator in &dominated_by {
            let other = support::mode(scene, dominator["mode"].as_str().unwrap());
            let gain = psnr(other) - psnr(mode);
            assert!((dominator["psnr_gain_db"].as_f64().unwrap() - gain).abs() < 1e-9, "{dominator}");
            assert!(gain >= -aabench::front::PSNR_TIE_DB, "{dominator}");
            assert!(
                other["frame_ms"]["median"].as_f64().unwrap()
                    <= mode["frame_ms"]["ci_high"].as_f64().unwrap(),
                "{} is slower than {}",
                dominator["mode"],
                mode["mode"]
            );
        }
    }
    // The nearest mode to the truth can be dominated by none; the fastest by none either.
    assert!(on_front >= 2, "{on_front} modes on the front");
    let nearest = modes.iter().max_by(|a, b| psnr(a).total_cmp(&psnr(b))).unwrap();
    assert_eq!(nearest["front"]["on_front"], true, "{}", nearest["mode"]);

    // Measured at the quick tier: the paper's adaptive-4x4 36.1 dB, the area weights 38.6,
    // cells 41.7, the reference 46.3. Cells must keep at least 3 dB of its 5.6 over the paper:
    // the texture edges inside pixels filtered rather than point-sampled, and the texture
    // contrast that S hides counted by the metric.
    let paper = psnr(support::mode(scene, "adaptive-4x4"));
    let cells = psnr(support::mode(scene, "adaptive-4x4-cells"));
    let area = psnr(support::mode(scene, "adaptive-4x4-area"));
    assert!(cells >= paper + 3.0, "cells {cells:.2} dB against the paper's {paper:.2} dB");
    assert!(cells > area, "cells {cells:.2} dB against the area weights' {area:.2} dB");

    // Which technique for this scene, by JOD: from row to row the level and the time rise;
    // each row's level is its own mode's; the last row is the cheapest mode within the margin
    // of the best.
    let parsed: aabench::record::RunRecord = serde_json::from_value(record.clone()).unwrap();
    let rows = aabench::report::ranking(&parsed.scenes[0], aabench::report::Basis::Still);
    assert!(rows.len() >= 2, "{} levels", rows.len());
    let median = |m: &Value| m["frame_ms"]["median"].as_f64().unwrap();
    let jod = |m: &Value| m["vs_ground_truth"]["jod"].as_f64().unwrap();
    let margin = aabench::vocabulary::JOD_MARGIN;
    for pair in rows.windows(2) {
        assert!(pair[1].level > pair[0].level, "levels {} and {}", pair[0].level, pair[1].level);
        assert!(pair[1].ms > pair[0].ms, "times {} and {}", pair[0].ms, pair[1].ms);
    }
    for row in &rows {
        assert_eq!(jod(support::mode(scene, &row.mode.mode)), row.level, "a row's level is its own mode's");
    }
    let ranked: Vec<&Value> = modes.iter().filter(|m| m["stalled"] == false && m["mode"] != "taa").collect();
    let best = ranked.iter().map(|m| jod(m)).fold(f64::MIN, f64::max);
    let answer = (ranked.iter())
        .filter(|m| jod(m) >= best - margin)
        .min_by(|a, b| median(a).total_cmp(&median(b)))
        .unwrap();
    assert_eq!(rows.last().unwrap().mode.mode, answer["mode"].as_str().unwrap());
}

/// The texture stress scene at the quick tier (the gate's): the best adaptive variant at 4×4,
/// `-coverage`, which reads every sample's albedo as the reference does, is within 1 dB of
/// reference-4x4 against the truth (the tolerance the issue set; measured 0.1 dB behind at the
/// nightly tier), where the paper's adaptive-4x4 is 10 dB behind.
#[test]
fn the_best_adaptive_variant_at_4x4_is_within_a_decibel_of_the_reference_on_the_texture_scene() {
    let _serial = SERIAL.lock().unwrap_or_else(|e| e.into_inner());
    let record = texture_run("front-texture", "reference-4x4,adaptive-4x4,adaptive-4x4-coverage", "1");
    let scene = &record["scenes"][0];
    let reference = psnr(support::mode(scene, "reference-4x4"));
    let coverage = psnr(support::mode(scene, "adaptive-4x4-coverage"));
    let paper = psnr(support::mode(scene, "adaptive-4x4"));
    assert!(coverage >= reference - 1.0, "coverage {coverage:.2} dB, reference {reference:.2} dB");
    assert!(paper < reference - 5.0, "the paper's mode {paper:.2} dB: the scene no longer stresses textures");
}
