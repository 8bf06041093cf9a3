//! The error-against-run-time front in a real run of the texture stress scene, and what the
//! `-cells` variant recovers there against the truth.

use crate::support;

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
    let record = texture_run("front", MODES, "5");
    let scene = &record["scenes"][0];
    let modes = scene["modes"].as_array().unwrap();
    assert_eq!(modes.len(), 6);

    // Each mode has a place on the PSNR front and on the still's JOD front.
    let psnr_margin = aabench::record::vocabulary::PSNR_MARGIN_DB;
    let mut on_front = 0;
    for mode in modes {
        for key in ["psnr_vs_truth", "jod_vs_truth"] {
            assert!(mode["fronts"][key]["verdict"].is_string(), "{}: no place on {key}", mode["mode"]);
        }
        let place = &mode["fronts"]["psnr_vs_truth"];
        let against = place["against"].as_array().cloned().unwrap_or_default();
        let verdict = place["verdict"].as_str().unwrap();
        assert_eq!(verdict == "front", against.is_empty(), "{place}");
        on_front += usize::from(verdict == "front");
        // Each rival is what the front says it is: as near the truth within the margin and, where
        // it puts the mode behind, faster in every one of the rounds the two shared (five
        // rounds: the sign test's interval is their whole range).
        for rival in &against {
            let other = support::mode(scene, rival["mode"].as_str().unwrap());
            let gain = psnr(other) - psnr(mode);
            assert!((rival["gain"].as_f64().unwrap() - gain).abs() < 1e-9, "{rival}");
            assert!(gain >= -psnr_margin, "{rival}");
            let rounds = |m: &Value| -> Vec<f64> {
                m["frame_ms"]["samples"].as_array().unwrap().iter().map(|v| v.as_f64().unwrap()).collect()
            };
            let (theirs, own) = (rounds(other), rounds(mode));
            let faster = theirs.iter().zip(&own).all(|(a, b)| a < b);
            assert_eq!(
                verdict == "behind",
                faster,
                "{} against {}: {theirs:?} {own:?}",
                mode["mode"],
                rival["mode"]
            );
        }
    }
    // The nearest mode to the truth has no rival but slower ones.
    let nearest = modes.iter().max_by(|a, b| psnr(a).total_cmp(&psnr(b))).unwrap();
    assert_ne!(nearest["fronts"]["psnr_vs_truth"]["verdict"], "behind", "{}", nearest["mode"]);
    assert!(on_front >= 1, "{on_front} modes on the front");

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
    let margin = aabench::record::vocabulary::JOD_MARGIN;
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

/// The fronts decided on recorded rounds repeat: the committed baselines keep each blessed
/// process's frame times, round by round, and the metrics of the images both rendered. Decided
/// on each process's own rounds, the still's fronts (PSNR's and JOD's) must agree: of the
/// (scene, mode, front) places both processes decide, at most 2 % differ, and at least 60 % are
/// decided in both.
#[test]
fn the_blessed_processes_rounds_decide_the_same_fronts() {
    use aabench::record::FrontVerdict;
    use aabench::record::front::{FrontPoint, decide};
    use aabench::record::vocabulary::{Table, fronts};

    let root = concat!(env!("CARGO_MANIFEST_DIR"), "/../baselines");
    let files: Vec<std::path::PathBuf> = std::fs::read_dir(root)
        .unwrap()
        .map(|platform| platform.unwrap().path().join("quick"))
        .filter(|tier| tier.is_dir())
        .flat_map(|tier| std::fs::read_dir(tier).unwrap())
        .map(|file| file.unwrap().path())
        .collect();
    assert!(files.len() >= 10, "{} baselines", files.len());
    let (mut places, mut decided, mut differ) = (0, 0, Vec::new());
    for file in &files {
        let baseline = aabench::baseline::load(file).unwrap();
        for metric in fronts(Table::Still) {
            let margin = metric.front_margin.unwrap();
            let verdicts: Vec<Vec<Option<FrontVerdict>>> = (0..2)
                .map(|process| {
                    let points: Vec<Option<FrontPoint>> = (baseline.modes.iter())
                        .map(|(id, mode)| {
                            let level = mode.metrics.get(metric.id)?.0;
                            let rounds = baseline.times.get(id)?.frame_ms.as_ref()?.get(process)?;
                            let stalled = id.parse::<aabench_renderer::Mode>().ok()?.stalled;
                            Some(FrontPoint { mode: id, stalled, level, rounds: Some(rounds), path: None })
                        })
                        .collect();
                    decide(&points, margin).into_iter().map(|place| place.map(|p| p.verdict)).collect()
                })
                .collect();
            for ((id, first), second) in baseline.modes.keys().zip(&verdicts[0]).zip(&verdicts[1]) {
                let (Some(first), Some(second)) = (first, second) else { continue };
                places += 1;
                if *first != FrontVerdict::Undecided && *second != FrontVerdict::Undecided {
                    decided += 1;
                    if first != second {
                        differ.push(format!("{} {id} {}: {first:?} / {second:?}", baseline.scene, metric.id));
                    }
                }
            }
        }
    }
    eprintln!("{places} places: {decided} decided in both processes, {} of them differently", differ.len());
    assert!(places >= 500, "{places} places");
    assert!(decided * 100 >= places * 60, "decided in both: {decided} of {places}");
    assert!(differ.len() * 100 <= decided * 2, "{} of {decided} differ: {differ:#?}", differ.len());
}
